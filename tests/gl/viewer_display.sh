#!/usr/bin/env bash
# ngi_gl_viewer --display, headless under Xvfb (issue 47): the front face rasterized at the window's size, the
# pipeline's 64 x 64 lightmap brought there by ngi::DisplayView; the frames are written at the window's size and
# timings.json reports the display view's stages. Exit 77 (skipped) where xvfb-run is missing.
# Usage: viewer_display.sh VIEWER MODEL WORK_DIR
set -euo pipefail
viewer=$1 model=$2 work=$3
rm -rf "$work" "$work.foreign"
# Issue 51: --time was CLI11's float: "nan" passed the range check and "0x10" read as 16 h. Usage errors (exit 2)
# before any window opens.
for bad in nan 0x10 25 -1 ""; do
  set +e; "$viewer" --time "$bad" --headless --out "$work" > "$work.time.log" 2>&1; rc=$?; set -e
  [ $rc = 2 ] && grep -q "must be a decimal number of hours" "$work.time.log" || {
    echo "FAILED: --time '$bad': exit $rc: $(cat "$work.time.log")" >&2; exit 1; }
done
# Issue 51: the viewer wrote into an --out holding foreign files (and left frame_0000.png on a full disk). Now the
# output is staged and committed at the end, and an --out holding anything it does not write is refused at once.
mkdir -p "$work.foreign" && echo keep > "$work.foreign/notes.txt"
set +e; "$viewer" --headless --frames 1 --out "$work.foreign" > "$work.foreign.log" 2>&1; rc=$?; set -e
[ $rc = 1 ] && grep -q "holds 'notes.txt', which ngi_gl_viewer does not write" "$work.foreign.log" &&
  [ "$(ls "$work.foreign")" = notes.txt ] || {
  echo "FAILED: a foreign --out: exit $rc: $(cat "$work.foreign.log"); now holds: $(ls "$work.foreign")" >&2; exit 1; }
# Issue 51: an in-range bake of 45 G rays (--bake-rays 65536 --bake-texels 16) ran past 60 s; refused at once now.
status=0
bash "$(dirname "$0")/run_under_xvfb.sh" "$viewer" --bake-rays 65536 --bake-texels 16 --headless --frames 1 \
    --window 64 --out "$work.bake" > "$work.bake.log" 2>&1 || status=$?
[ $status = 77 ] && exit 77
[ $status = 1 ] && grep -q "beyond the 268435456 one bake may trace" "$work.bake.log" || {
  echo "FAILED: the 45 G-ray bake: exit $status: $(cat "$work.bake.log")" >&2; exit 1; }
status=0
bash "$(dirname "$0")/run_under_xvfb.sh" "$viewer" --headless --frames 2 --warmup 1 --window 96 --display \
    --scene sculpture:seed=1 --model "$model" --out "$work" > "$work.log" 2>&1 || status=$?
[ $status = 77 ] && exit 77
[ $status = 0 ] || { cat "$work.log" >&2; echo "FAILED: the viewer exited with $status" >&2; exit 1; }
/usr/bin/python3 - "$work" <<'PY'
import json, struct, sys
work = sys.argv[1]
j = json.load(open(f"{work}/timings.json"))
assert j["display"] == 96, j["display"]
d = j["frames"][-1]["display"]
assert d["upsample_ms"] > 0 and d["temporal_ms"] > 0 and j["median"]["display_upsample_temporal_ms"] > 0, d
with open(f"{work}/frame_0001.png", "rb") as f:
    head = f.read(24)
w, h = struct.unpack(">II", head[16:24])
assert (w, h) == (96, 96), (w, h)
PY
echo "viewer --display: 96 x 96 frames, display stages timed"

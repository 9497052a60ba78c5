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
# --window takes W or WxH, each in [64, 4096]; --gi off needs --display. Usage errors (exit 2).
for bad in 1280x 1280x720x2 63 64x5000 x720 abc; do
  set +e; "$viewer" --window "$bad" --headless --out "$work" > "$work.window.log" 2>&1; rc=$?; set -e
  [ $rc = 2 ] && grep -q -- "--window" "$work.window.log" || {
    echo "FAILED: --window '$bad': exit $rc: $(cat "$work.window.log")" >&2; exit 1; }
done
set +e; "$viewer" --gi off --headless --out "$work" > "$work.gi.log" 2>&1; rc=$?; set -e
[ $rc = 2 ] && grep -q "off needs --display" "$work.gi.log" || {
  echo "FAILED: --gi off without --display: exit $rc: $(cat "$work.gi.log")" >&2; exit 1; }
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
# A wide window shows the centre crop of the square front view, with and without GI (the same display path).
for gi in on off; do
  status=0
  bash "$(dirname "$0")/run_under_xvfb.sh" "$viewer" --headless --frames 1 --warmup 1 --window 128x72 --display \
      --gi $gi --scene bleed --model "$model" --out "$work.wide_$gi" > "$work.wide_$gi.log" 2>&1 || status=$?
  [ $status = 0 ] || { cat "$work.wide_$gi.log" >&2; echo "FAILED: --window 128x72 --gi $gi: exit $status" >&2; exit 1; }
done
/usr/bin/python3 - "$work" <<'PY'
import json, struct, sys
work = sys.argv[1]
j = json.load(open(f"{work}/timings.json"))
assert j["display"] == 96 and j["window"] == [96, 96], (j["display"], j["window"])
d = j["frames"][-1]["display"]
assert d["upsample_ms"] > 0 and d["temporal_ms"] > 0 and j["median"]["display_upsample_temporal_ms"] > 0, d

def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    return struct.unpack(">II", head[16:24])

def png_pixels(path):  # the viewer writes 8-bit RGB PNGs; zlib + filters are enough to compare two of them
    import zlib
    data = open(path, "rb").read()
    pos, idat, (w, h) = 8, b"", png_size(path)
    while pos < len(data):
        n = struct.unpack(">I", data[pos:pos + 4])[0]
        if data[pos + 4:pos + 8] == b"IDAT":
            idat += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    return zlib.decompress(idat), w, h

assert png_size(f"{work}/frame_0001.png") == (96, 96)
for gi in ("on", "off"):
    w = json.load(open(f"{work}.wide_{gi}/timings.json"))
    assert w["display"] == 128 and w["window"] == [128, 72] and w["gi"] == (gi == "on"), w
    assert png_size(f"{work}.wide_{gi}/frame_0000.png") == (128, 72)
    assert png_size(f"{work}.wide_{gi}/capture.png") == (128, 72)
on, off = png_pixels(f"{work}.wide_on/frame_0000.png")[0], png_pixels(f"{work}.wide_off/frame_0000.png")[0]
assert on != off, "--gi off gave the GI frame"
PY
echo "viewer --display: 96 x 96 frames, display stages timed; 128 x 72 windows with and without GI"

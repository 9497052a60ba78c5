#!/usr/bin/env bash
# End-to-end CLI checks (ctest cli_end_to_end): render a tiny frame, merge it, run a generator on it; then the
# bad-input cases must fail with exit code 1, name the offending file, and leave no output folder behind.
# Usage: test_cli.sh NGI_BINARY WORK_DIR
set -euo pipefail
ngi=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
# A 6-level pix2pix generator from PyTorch (random weights): the CLI's plumbing, not the model, is under test.
/usr/bin/python3 "$(dirname "$0")/../parity/make_parity.py" --out "$work/parity" > "$work/parity.log" 2>&1
model=$work/parity/pix2pix_running.safetensors
fail() { echo "FAILED: $*" >&2; exit 1; }

# A 32 x 32 frame: global view 128 x 64, which the 6-level parity generator accepts.
"$ngi" render --scene room:seed=1 --face 32 --spp 4 --feature-spp 1 --out "$work/frame" > /dev/null
"$ngi" merge --frame "$work/frame" --out "$work/merged" > /dev/null
for f in globalview_albedo.exr globalview_normal.exr coord.exr input.npy; do
  [ -s "$work/merged/$f" ] || fail "ngi merge did not write $f"
done
"$ngi" lightmap --frame "$work/frame" --model "$model" --out "$work/lm" > /dev/null
for f in lightmap.exr final.png compare.png metrics.json; do
  [ -s "$work/lm/$f" ] || fail "ngi lightmap did not write $f"
done

# ngi metrics prints strict JSON: a PSNR/SSIM that is not a number is null with a note saying why
# (docs/CONVENTIONS.md, Metrics). check_metrics FILE_A FILE_B RANGE PYTHON_ASSERTION (m = the parsed output).
check_metrics() {
  "$ngi" metrics "$1" "$2" --range "$3" > "$work/metrics.out"
  /usr/bin/python3 -c "import json, sys; m = json.loads(open(sys.argv[1]).read()); assert $4, m" "$work/metrics.out" ||
    fail "ngi metrics $1 $2 --range $3: $(cat "$work/metrics.out")"
}
ref=$work/frame/reference.exr direct=$work/frame/front_direct.exr
check_metrics "$ref" "$ref" 1 \
  'm["mse"] == 0 and m["psnr"] is None and "+infinity" in m["psnr_note"] and m["ssim"] == 1 and "ssim_note" not in m'
check_metrics "$direct" "$ref" 0 \
  'm["mse"] > 0 and m["psnr"] is None and m["ssim"] is None and "data_range is 0" in m["psnr_note"] + m["ssim_note"]'
check_metrics "$direct" "$ref" 2 'set(m) == {"mse", "psnr", "ssim"} and all(type(v) is float for v in m.values())'

# expect_failure NAME CMD...: exit code 1, the message names $expect, no $work/NAME output folder.
expect_failure() {
  local name=$1; shift
  set +e
  "$@" > "$work/$name.out" 2> "$work/$name.err"
  local rc=$?
  set -e
  [ $rc -eq 1 ] || fail "$name: exit code $rc, expected 1"
  grep -q -- "$expect" "$work/$name.err" || fail "$name: message does not name $expect: $(cat "$work/$name.err")"
  [ ! -e "$work/out_$name" ] || fail "$name: left output behind in $work/out_$name"
}

cp -r "$work/frame" "$work/missing" && rm "$work/missing/left_depth.exr"
expect=left_depth.exr
expect_failure missing_merge "$ngi" merge --frame "$work/missing" --out "$work/out_missing_merge"
expect_failure missing_lightmap "$ngi" lightmap --frame "$work/missing" --model "$model" --out "$work/out_missing_lightmap"

cp -r "$work/frame" "$work/truncated" && head -c 100 "$work/frame/up_normal.exr" > "$work/truncated/up_normal.exr"
expect=up_normal.exr
expect_failure truncated "$ngi" merge --frame "$work/truncated" --out "$work/out_truncated"

expect=nonexistent.safetensors
expect_failure no_model "$ngi" lightmap --frame "$work/frame" --model "$work/nonexistent.safetensors" --out "$work/out_no_model"

echo "cli_end_to_end: 3 commands ran, 4 bad inputs refused cleanly"

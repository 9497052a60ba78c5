#!/usr/bin/env bash
# ctest c_sample_lightmap: renders a frame folder with the ngi CLI, then runs the C sample (samples/c/lightmap.c)
# on it with both shipped models, on the device under test ($NGI_TEST_DEVICE, default cpu).
# Usage: run_sample.sh <work dir> <ngi CLI> <ngi_c_lightmap> <source dir>
set -euo pipefail
work=$1 ngi=$2 sample=$3 src=$4
device=${NGI_TEST_DEVICE:-cpu}
rm -rf "$work"
mkdir -p "$work"
"$ngi" render --scene room:seed=3 --face 64 --spp 4 --feature-spp 1 --device "$device" --out "$work/frame" > /dev/null
"$sample" "$work/frame" "$src/models/surround.safetensors" "$work/lightmap.exr" "$work/final.png" "$device"
"$sample" "$work/frame" "$src/models/single_view.safetensors" "$work/single.exr" "$work/single.png" "$device"
for f in lightmap.exr final.png single.exr single.png; do
  [ -s "$work/$f" ] || { echo "run_sample.sh: $f missing or empty" >&2; exit 1; }
done
# Bad input reaches the user as the library's message and exit code 1, with no output written.
if "$sample" "$work/no-such-frame" "$src/models/surround.safetensors" "$work/bad.exr" "$work/bad.png" "$device" \
    2> "$work/err.txt"; then
  echo "run_sample.sh: a missing frame folder was accepted" >&2; exit 1
fi
grep -q "NGI_ERROR_INPUT" "$work/err.txt" && grep -q "no-such-frame" "$work/err.txt"
[ ! -e "$work/bad.exr" ]
echo "run_sample.sh: ok"

#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, path-traces a frame of a scene the shipped models
# never saw in training, and runs the surround-aware GI model (and the single-view baseline) on it with ngi.
# Outputs in ./out/demo: frame/ (the rendered frame folder), surround/ and single_view/ (lightmap.exr,
# final.png, compare.png = direct only | network | path-traced reference, metrics.json).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
export POCL_CACHE_DIR="$PWD/build/.cache/pocl" NGI_CACHE_DIR="$PWD/build/.cache/ngi"
mkdir -p "$POCL_CACHE_DIR" "$NGI_CACHE_DIR" out/demo
ngi=build/ngi
scene=${NGI_DEMO_SCENE:-backlit:seed=101}   # a held-out test scene of configs/dataset_n64.json

echo "== OpenCL devices"
$ngi devices

echo "== Path-tracing a frame of $scene (six faces of feature buffers + the front view's reference lighting)"
$ngi render --scene "$scene" --frame 12 --path-frames 30 --face 64 --spp 256 --out out/demo/frame \
     --preview out/demo/reference.png

for model in surround single_view; do
  echo "== ngi lightmap with models/$model.safetensors"
  $ngi lightmap --frame out/demo/frame --model models/$model.safetensors --out out/demo/$model --size 256x256
done
echo "== Done: out/demo/surround/compare.png shows direct light only | surround-aware network | path-traced reference"

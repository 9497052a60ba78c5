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
scene=${NGI_DEMO_SCENE:-room:seed=204}   # not in the training set (docs/RESULTS.md's moving-camera scene)
frame=${NGI_DEMO_FRAME:-45}              # walking towards a sunlit opening: bounce light on the walls

echo "== OpenCL devices"
$ngi devices

echo "== Path-tracing a frame of $scene (six faces of feature buffers + the front view's reference lighting)"
$ngi render --scene "$scene" --frame "$frame" --path-frames 100 --face 64 --spp 256 --out out/demo/frame \
     --preview out/demo/reference.png

for model in surround single_view; do
  echo "== ngi lightmap with models/$model.safetensors"
  $ngi lightmap --frame out/demo/frame --model models/$model.safetensors --out out/demo/$model --size 256x256
done
echo "== Done: out/demo/surround/compare.png shows direct light only | surround-aware network | path-traced reference"

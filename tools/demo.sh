#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, path-traces a frame of a scene the shipped models
# never saw in training, and runs the indirect-light generator (and the thesis's whole-lightmap generator) on it with ngi.
# Outputs in ./out/demo: frame/ (the rendered frame folder), gi/ (the indirect-light generator) and thesis/ (the
# thesis's whole-lightmap generator), each with lightmap.exr, final.png, compare.png = direct only | network |
# path-traced reference, metrics.json (the network and direct light alone against the reference); then the planner picks the
# most accurate zoo rung that fits a time budget on this device for this scene (plan.json; it renders calibration
# frames with references to decide) and ngi lightmap runs it (planned/).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
export POCL_CACHE_DIR="$PWD/build/.cache/pocl" NGI_CACHE_DIR="$PWD/build/.cache/ngi"
mkdir -p "$POCL_CACHE_DIR" "$NGI_CACHE_DIR" out/demo
ngi=build/ngi
scene=${NGI_DEMO_SCENE:-room:seed=204}   # not in the training set (docs/RESULTS.md's moving-camera scene)
frame=${NGI_DEMO_FRAME:-45}              # walking towards a sunlit opening: bounce light on the walls
max_ms=${NGI_DEMO_MAX_MS:-300}            # the planner's time budget (ms per frame, the whole ngi lightmap command)

echo "== OpenCL devices"
$ngi devices

echo "== Path-tracing a frame of $scene (six faces of feature buffers + the front view's reference lighting)"
$ngi render --scene "$scene" --frame "$frame" --path-frames 100 --face 64 --spp 256 --out out/demo/frame \
     --preview out/demo/reference.png

# The indirect-light generator (issue 25: the network predicts only what direct light lacks, ngi adds the frame's
# direct light) and, for comparison, the thesis's generator that predicts the whole lightmap.
echo "== ngi lightmap with models/ladder/gi_single_view_n64_ngf16.safetensors (predicts indirect light)"
$ngi lightmap --frame out/demo/frame --model models/ladder/gi_single_view_n64_ngf16.safetensors --out out/demo/gi \
     --size 256x256
echo "== ngi lightmap with models/surround.safetensors (the thesis's mode: predicts the whole lightmap)"
$ngi lightmap --frame out/demo/frame --model models/surround.safetensors --out out/demo/thesis --size 256x256
echo "== Planning: the most accurate rung of the model zoo (models/zoo.json) within $max_ms ms per frame on $scene"
# Renders calibration and validation frames of the scene with references, scores every rung on them and writes the
# choice; ngi lightmap --plan runs it (docs/RESULTS.md, "Model only what a scene requires").
PYTHONPATH=build/python /usr/bin/python3 -m ngi.plan --scene "$scene" --max-ms "$max_ms" --frames 3 --validate 2 \
     --spp 512 --out out/demo/plan.json
plan_n=$(/usr/bin/python3 -c "import json; print(json.load(open('out/demo/plan.json'))['n'])")
planned_frame=out/demo/frame
if [ "$plan_n" != 64 ]; then  # a rung at another face size runs on the frame rendered at that size
  planned_frame=out/demo/frame_n$plan_n
  $ngi render --scene "$scene" --frame "$frame" --path-frames 100 --face "$plan_n" --spp 256 --out "$planned_frame"
fi
$ngi lightmap --frame "$planned_frame" --plan out/demo/plan.json --out out/demo/planned --size 256x256
echo "== Done: out/demo/gi/compare.png shows direct light only | the indirect-light network | path-traced reference;"
echo "   out/demo/plan.json is the planner's choice and its evidence, out/demo/planned/ what that rung produced"

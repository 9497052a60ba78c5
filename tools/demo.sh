#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, path-traces a frame of a scene the shipped models
# never saw in training with the inputs an engine has (converged direct light: ngi render's default), and lights it
# with ngi two ways. Outputs in ./out/demo: frame/ (the rendered frame folder), ssgi/ (surround screen-space GI: one
# bounce of the light the six faces show, no network) and gi/ (the indirect-light generator, for comparison), each with
# lightmap.exr, final.png, compare.png = direct only | that rung | path-traced reference, metrics.json (the rung and
# direct light alone against the reference); then the planner picks the most accurate zoo rung that fits a time budget
# on this device for this scene (plan.json; it renders calibration frames with references to decide, and never takes a
# rung that a cheaper one beats in PSNR or SSIM) and ngi lightmap runs it (planned/).
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

echo "== Path-tracing a frame of $scene (six faces of feature buffers with converged direct light + the reference)"
$ngi render --scene "$scene" --frame "$frame" --path-frames 100 --face 64 --spp 256 --out out/demo/frame \
     --preview out/demo/reference.png

# Surround screen-space GI (issue 45): the light the six faces already show, bounced once more to the front view;
# and, for comparison, the indirect-light generator (issue 25: the network predicts what direct light lacks).
echo "== ngi lightmap with ssgi_surround (models/ssgi/ssgi_surround.safetensors: no network)"
$ngi lightmap --frame out/demo/frame --model ssgi_surround --out out/demo/ssgi --size 256x256
echo "== ngi lightmap with gi_surround_n64_ngf16 (models/ladder/: a network that predicts indirect light)"
$ngi lightmap --frame out/demo/frame --model gi_surround_n64_ngf16 --out out/demo/gi --size 256x256
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
echo "== Done: out/demo/ssgi/compare.png shows direct light only | surround SSGI | path-traced reference (gi/: the network);"
echo "   out/demo/plan.json is the planner's choice and its evidence, out/demo/planned/ what that rung produced"

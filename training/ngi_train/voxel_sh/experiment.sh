#!/usr/bin/env bash
# Seed 004 end to end, as recorded in docs/RESULTS_VOXEL_SH.md: the Cornell-box data, the networks, the voxel-level
# and frame-level evaluation. Every step skips what is already done (data folders, finished trainings resume from
# their checkpoints), so an interrupted run continues where it stopped.
# Usage: training/ngi_train/voxel_sh/experiment.sh WORK_DIR [STAGE...]   stages: data train eval (default: all three)
# Needs a build (tools/build.sh), its Python package and the training package (PYTHONPATH, set below).
set -euo pipefail
cd "$(dirname "$0")/../../.."
root=$PWD
work=${1:?usage: experiment.sh WORK_DIR [data] [train] [eval]}
shift
stages=${*:-data train eval}
ngi=$root/build/ngi
export PYTHONPATH=$root/training:$root/build/python
dev=${NGI_DEVICE:-pocl}
D=$work/vf
train_scenes="$D/cornell_0 $D/cornell_1 $D/cornell_2 $D/cornell_3 $D/cornell_4"
test_scenes="$D/cornell_pink_5 $D/cornell_5"

for stage in $stages; do case $stage in
data)
  # Ground truth at full settings (M = 1024 directions, 256 point samples, 8 bounces): 5 training boxes, the pink
  # test box (with a second estimate: the noise floor) and its white twin; then 100 procedural boxes at M = 256 and
  # 16 point samples (only their SH is used: training data for "do more scenes help?").
  for s in 0 1 2 3 4; do
    [ -d "$D/cornell_$s" ] || "$ngi" voxel-data --scene "cornell:seed=$s" --out "$D/cornell_$s" --device "$dev"
  done
  [ -d "$D/cornell_pink_5" ] || "$ngi" voxel-data --scene cornell_pink:seed=5 --out "$D/cornell_pink_5" --noise --device "$dev"
  [ -d "$D/cornell_5" ] || "$ngi" voxel-data --scene cornell:seed=5 --out "$D/cornell_5" --device "$dev"
  for s in $(seq 100 199); do
    [ -d "$D/proc/cornell_$s" ] || "$ngi" voxel-data --scene "cornell:seed=$s" --out "$D/proc/cornell_$s" \
      --directions 256 --samples 16 --device "$dev"
  done ;;
train)
  # name architecture steps training-set [extra trainer options]
  run() {
    local name=$1 arch=$2 steps=$3 set=$4; shift 4
    /usr/bin/python3 -m ngi_train.voxel_sh.train --arch "$arch" --train $set --test $test_scenes --steps "$steps" \
      --work "$work/runs/$name" --out "$work/models/$name.safetensors" --card "$work/models/$name.md" --half "$@"
  }
  run voxel_sh_mlp mlp 3000 "$train_scenes"
  run voxel_sh_set set 3000 "$train_scenes"
  run voxel_sh_resnet resnet 2000 "$train_scenes"
  run voxel_sh_mlp_nowd mlp 3000 "$train_scenes" --weight-decay 0
  run voxel_sh_set_proc100 set 3000 "$(ls -d "$D"/proc/cornell_* | tr '\n' ' ')" ;;
eval)
  models=$(ls "$work"/models/*.safetensors)
  # Voxel level (SH MSE in standardized units, face and probe irradiance errors, model times) + the baseline SH.
  /usr/bin/python3 -m ngi_train.voxel_sh.evaluate --train $train_scenes --test $test_scenes --models $models \
    --devices pocl --baselines "$work/baselines" --out "$work/voxel_metrics.json"
  # Frame level: views of the test boxes lit from every field, against 1024-spp references (128^2: the surround
  # generator needs N divisible by 64).
  model_args=()
  for m in $models; do model_args+=(--model "$m"); done
  for view in 0 40 80; do
    extra=(); [ "$view" = 0 ] && extra=(--noise-floor)
    [ -f "$work/frames/pink_v$view/metrics.json" ] || "$ngi" probe-gi --scene cornell_pink:seed=5 \
      --field "$D/cornell_pink_5" --frame "$view" --face 128 --spp 1024 "${model_args[@]}" \
      --sh "mean_position=$work/baselines/mean_position_cornell_pink_5.npy" \
      --surround-model models/surround.safetensors "${extra[@]}" --out "$work/frames/pink_v$view" --device "$dev"
  done
  [ -f "$work/frames/white_v0/metrics.json" ] || "$ngi" probe-gi --scene cornell:seed=5 --field "$D/cornell_5" \
    --frame 0 --face 128 --spp 1024 "${model_args[@]}" --sh "mean_position=$work/baselines/mean_position_cornell_5.npy" \
    --surround-model models/surround.safetensors --out "$work/frames/white_v0" --device "$dev"
  # The LTF's per-voxel lighting into the voxel-level table too.
  /usr/bin/python3 -m ngi_train.voxel_sh.evaluate --train $train_scenes --test $test_scenes --models $models \
    --devices pocl --ltf "$work/frames/pink_v0" "$work/frames/white_v0" --out "$work/voxel_metrics.json"
  # Costs on each OpenCL stack, with nothing else running: a small view (cheap reference), every method timed
  # (the frame runs above share the machine's 2 cores with whatever else runs).
  [ -f "$work/frames/pink_pocl_costs/metrics.json" ] || "$ngi" probe-gi --scene cornell_pink:seed=5 \
    --field "$D/cornell_pink_5" --face 32 --spp 16 "${model_args[@]}" --out "$work/frames/pink_pocl_costs" --device pocl
  [ -f "$work/frames/pink_rusticl/metrics.json" ] || RUSTICL_ENABLE=llvmpipe "$ngi" probe-gi --scene cornell_pink:seed=5 --field "$D/cornell_pink_5" --face 32 --spp 16 \
    "${model_args[@]}" --out "$work/frames/pink_rusticl" --device rusticl ;;
*) echo "unknown stage $stage (data train eval)" >&2; exit 2 ;;
esac; done

#!/usr/bin/env bash
# Seed 002 end to end at this machine's scale (docs/RESULTS_NEURAL_GI.md): render, train, evaluate, report.
# Every step resumes: `ngi dataset` skips written frames, train resumes its checkpoint, sequences skips
# written renders; run the same command again after an interruption.
#
#   bash training/ngi_train/neural_gi/reproduce.sh [render|sequences|train|evaluate|report|all] [scene ...]
#   bash training/ngi_train/neural_gi/reproduce.sh one SCENE VARIANT     # one training (variants: see variant_args)
#
# Environment: STEPS (training steps of every variant, default 5000, as shipped), DATA (default data), PT_SPP
# (path tracing sample counts rendered and scored beside the models, default "16 32 100": 16 ~ the network's time,
# 100 ~ the network plus its 256-spp direct-light input, measured in docs/RESULTS_NEURAL_GI.md), JOBS (trainings at
# once, default 2, one thread each).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$ROOT"
STAGE="${1:-all}"
shift || true
if [ "$STAGE" = one ]; then ONE=("$@"); set --; fi
SCENES=("${@:-bleed room}")
read -r -a SCENES <<< "${SCENES[*]}"
STEPS="${STEPS:-5000}"
DATA="${DATA:-data}"
PT_SPP="${PT_SPP:-16 32 100}"
JOBS="${JOBS:-2}"
PY=/usr/bin/python3
export PYTHONPATH="$ROOT/training:$ROOT/build/python${PYTHONPATH:+:$PYTHONPATH}"
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$ROOT/build/.cache/pocl}"
NGI="$ROOT/build/ngi"
T=ngi_train.neural_gi  # the family's commands: $PY -m $T.<command>
RUNS="$DATA/neural_gi_runs"
RESULTS="$DATA/neural_gi_results"
SEQ="$DATA/neural_gi_seq_n32"

folder() { case "$1" in bleed) echo bleed_seed1 ;; room) echo room_seed1 ;; *) echo "unknown scene $1" >&2; exit 2 ;; esac; }

render() {
  for s in "${SCENES[@]}"; do
    "$NGI" dataset --config "configs/neural_gi_${s}_n32.json" --out "$DATA/neural_gi_${s}_n32"
  done
}

sequences() {
  for s in "${SCENES[@]}"; do
    "$PY" -m "$T.sequences" --config "configs/neural_gi_${s}_n32.json" --out "$SEQ" --ngi "$NGI" --pt-spp $PT_SPP
  done
}

# variant -> extra arguments of the trainer (the network: C_B 16, ngf 32, num_downs 5 = a 1 x 1 bottleneck at N = 32,
# MLP 8 x 256 with the input re-injected at layer 4)
variant_args() {
  case "$1" in
    neural_gi) echo "--seed 1" ;;
    neural_gi_seed2) echo "--seed 2" ;;
    no_buffer) echo "--seed 1 --no-buffer" ;;
    unet_only) echo "--seed 1 --unet-only" ;;
    *) echo "unknown variant $1" >&2; return 2 ;;
  esac
}

train_one() {  # scene variant
  local s="$1" v="$2" f work args
  f="$(folder "$s")" || return 2
  args="$(variant_args "$v")" || return 2
  work="$RUNS/$f/$v"
  mkdir -p "$work"
  # shellcheck disable=SC2086
  nice -n 5 "$PY" -m "$T.train" --dataset "$DATA/neural_gi_${s}_n32" --work "$work" --cache "$DATA/neural_gi_cache" \
    --out "$work/model.safetensors" --steps "$STEPS" --num-downs 5 --eval-every 500 --threads 1 $args \
    > "$work/train.out" 2> "$work/train.err" || { echo "train $s $v failed: see $work/train.err" >&2; return 1; }
}

train() {
  local jobs=()
  for v in neural_gi neural_gi_seed2 unet_only no_buffer; do  # the comparisons that matter most first
    for s in "${SCENES[@]}"; do jobs+=("$s $v"); done
  done
  printf '%s\n' "${jobs[@]}" | xargs -P "$JOBS" -I{} bash -c 'train_one {}'
}

evaluate() {
  mkdir -p "$RESULTS"
  for s in "${SCENES[@]}"; do
    local f
    f="$(folder "$s")"
    for v in neural_gi neural_gi_seed2 no_buffer unet_only; do
      local m="$RUNS/$f/$v/model.safetensors"
      [ -f "$m" ] || continue
      "$PY" -m "$T.evaluate" --dataset "$DATA/neural_gi_${s}_n32" --model "$m" --cache "$DATA/neural_gi_cache" \
        --out "$RESULTS/${f}__${v}__heldout.json"
      for q in moving_camera moving_light; do
        "$PY" -m "$T.evaluate" --dataset "$SEQ" --scene "$f" --split "$q" --test-split "$q" --model "$m" \
          --path-traced $(for x in $PT_SPP; do echo "${q}_pt$x"; done) --temporal --cache "$DATA/neural_gi_cache_seq" \
          --out "$RESULTS/${f}__${v}__${q}.json"
      done
    done
  done
}

report() {
  "$PY" -m "$T.report" --runs "$RUNS" --results "$RESULTS" --out docs/neural_gi
}

export -f train_one variant_args folder
export PY T RUNS DATA STEPS
case "$STAGE" in
  render) render ;;
  sequences) sequences ;;
  train) train ;;
  evaluate) evaluate ;;
  report) report ;;
  one) train_one "${ONE[0]}" "${ONE[1]}" ;;
  all) render; sequences; train; evaluate; report ;;
  *) echo "usage: $0 [render|sequences|train|evaluate|report|all] [bleed] [room]" >&2; exit 2 ;;
esac

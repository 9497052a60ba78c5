#!/usr/bin/env bash
# ngi on every OpenCL device present -- for a user with a GPU: the GEMM self-check, the device's test cases (the op
# harness by default), a quick GEMM tuner sweep with a proposed tuning-database entry, and the GEMM, generator and
# whole-frame benchmarks, into one JSON report (perf/gpu_check.py says what each step is). Builds first if needed.
#   bash tools/gpu_check.sh --out gpu_check [--tests quick|full|none|FILTER] [--bench quick|full|none|A,B]
#                           [--devices P:D,...] [--tune-max N] [--repeats R]
# Mesa's rusticl lists llvmpipe only with RUSTICL_ENABLE=llvmpipe (set it to check that CPU stack too).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/ngi ] && [ -x build/tests/ngi_tests ] && [ -x build/perf/ngi_bench ] || bash tools/build.sh
PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}" exec /usr/bin/python3 perf/gpu_check.py "$@"

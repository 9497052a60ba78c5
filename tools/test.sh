#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs the whole suite on PoCL (CPU OpenCL).
# NGI_TEST_DEVICE=gpu (or P:D) runs the same suite on another OpenCL device.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
# Compiled kernels are cached per build tree (PoCL's work-group functions, ngi's program binaries).
export POCL_CACHE_DIR="$PWD/build/.cache/pocl" NGI_CACHE_DIR="$PWD/build/.cache/ngi"
mkdir -p "$POCL_CACHE_DIR" "$NGI_CACHE_DIR"
cd build
ctest --output-on-failure --timeout 1500

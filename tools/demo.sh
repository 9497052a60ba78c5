#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs the generator end to end on a built-in
# input - a pix2pix generator exported from PyTorch, run by ngi on PoCL, its output compared with PyTorch's.
# Outputs land in ./out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
export POCL_CACHE_DIR="$PWD/build/.cache/pocl" NGI_CACHE_DIR="$PWD/build/.cache/ngi"
mkdir -p "$POCL_CACHE_DIR" "$NGI_CACHE_DIR" out/demo
ngi=build/ngi

echo "== OpenCL devices"
$ngi devices

echo "== A pix2pix U-Net from PyTorch (random weights, per-image batch norm), converted to an ngi model file"
/usr/bin/python3 tests/parity/make_parity.py --out out/demo/parity > out/demo/parity.log 2>&1
case=out/demo/parity/pix2pix_per_image
$ngi generate --model $case.safetensors --input ${case}_input.npy --output out/demo/generated.npy --profile

echo "== ngi vs PyTorch on the same input"
/usr/bin/python3 - "$case" <<'PY'
import sys, numpy as np
case = sys.argv[1]
ngi, torch = np.load("out/demo/generated.npy"), np.load(case + "_expected.npy")
print(f"output {ngi.shape}, max |ngi - torch| = {np.abs(ngi - torch).max():.2e}")
PY

#!/usr/bin/env bash
# Installs what ngi needs on Debian 12 (as root), skipping packages that are already there.
# Build: cmake, ninja, g++, OpenCL headers + ICD loader, PoCL (the CPU OpenCL device every test runs on),
# Catch2, nlohmann-json, OpenEXR, libpng, GLM, CLI11 (the ngi CLI's parser), tinygltf (glTF mesh files: header-only,
# compiled into ngi_render; OBJ and PLY are read by ngi's own readers). Python side (parity oracle,
# training, perf baseline): Debian's python3-torch/numpy/skimage/matplotlib/tqdm, and OpenBLAS so PyTorch's BLAS is
# not the reference one. Python bindings: pybind11, the Python headers, pyopencl (interop tests), pytest, onnx (the
# ONNX import, python3 -m ngi.convert model.onnx).
# Distributed dataset rendering (ngi-dataset-mpi): OpenMPI.
# Gates (tools/test.sh): Mesa's rusticl (mesa-opencl-icd, a second OpenCL stack), oclgrind (the kernel
# simulator), clang-15 + libFuzzer (the sanitize and fuzz stages), llvm-15 (llvm-symbolizer: stack traces in their
# reports).
# Packaging (the package stage, pip install .): debhelper, dh-python, python3-setuptools/-wheel/-pip/-venv.
# Benchmark baseline: Intel Embree 3 (libembree-dev, with TBB), the CPU ray tracer perf/bench_bvh compares the
# triangle BVH with (optional: CMake skips bench_bvh where it is missing).
set -euo pipefail
packages=(
  cmake ninja-build g++ pkg-config
  ocl-icd-opencl-dev opencl-headers pocl-opencl-icd clinfo
  catch2 nlohmann-json3-dev libopenexr-dev libpng-dev libglm-dev libcli11-dev libtinygltf-dev
  python3-torch python3-numpy python3-skimage python3-matplotlib python3-tqdm libopenblas0-pthread
  pybind11-dev python3-dev python3-pyopencl python3-pytest python3-onnx
  libopenmpi-dev openmpi-bin
  mesa-opencl-icd oclgrind clang-15 libfuzzer-15-dev llvm-15
  libglfw3-dev libepoxy-dev libgl-dev libgl1-mesa-dri libstb-dev xvfb xauth
  libembree-dev
  debhelper dh-python python3-setuptools python3-wheel python3-pip python3-venv
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  if [ "$(id -u)" -ne 0 ]; then echo "install-deps: run as root (apt-get needs it)" >&2; exit 1; fi
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
# Optional assets, with NGI_FETCH_ASSETS=1: the Stanford bunny as ~/.cache/ngi/assets/bunny.obj (tools/fetch_bunny.sh: npm,
# non-fatal when offline). No build or test needs it.
if [ "${NGI_FETCH_ASSETS:-0}" = 1 ]; then bash "$(dirname "$0")/fetch_bunny.sh" > /dev/null; fi

#!/usr/bin/env bash
# Configures and builds ngi into ./build (Release), or into $NGI_BUILD_DIR. Extra arguments go to cmake, e.g.
# NGI_BUILD_DIR=build-sanitize bash tools/build.sh -DNGI_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${NGI_BUILD_DIR:-build}
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >&2
cmake --build "$dir" -j "$(nproc)" >&2

#!/usr/bin/env bash
# Configures and builds ngi into ./build (Release). Extra arguments go to cmake, e.g. -DNGI_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >&2
cmake --build build -j "$(nproc)" >&2

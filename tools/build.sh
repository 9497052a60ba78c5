#!/usr/bin/env bash
# Configures and builds ngi into ./build (Release), or into $NGI_BUILD_DIR. Extra arguments go to cmake, e.g.
# NGI_BUILD_DIR=build-sanitize bash tools/build.sh -DNGI_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${NGI_BUILD_DIR:-build}
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >&2
# NGI_BUILD_TARGETS="ngi_tests": build only these targets (the tsan stage needs only the test binary).
# shellcheck disable=SC2086
cmake --build "$dir" -j "$(nproc)" ${NGI_BUILD_TARGETS:+--target $NGI_BUILD_TARGETS} >&2
# Register this build's Python package (build/python/ngi) with Debian's /usr/bin/python3, as an editable install
# does: a .pth file in its site directory. Only for the default tree, and only as root (a system directory).
if [ "$dir" = build ] && [ -d "$dir/python/ngi" ] && [ "$(id -u)" -eq 0 ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  mkdir -p "$site" && echo "$PWD/$dir/python" > "$site/ngi.pth"
fi

#!/usr/bin/env bash
# The install stage of tools/test.sh: installs a build tree into a temporary prefix and builds two out-of-tree
# consumers against the installed files only: a C99 program through pkg-config (plus every samples/c/*.c, all with
# -std=c99 -Wall -Wextra -pedantic -Werror) and a C++ program through find_package(ngi); runs them; checks that
# libngi_c exports nothing but the C ABI. Prints the number of checks passed on stdout; exits non-zero on a failure.
# Usage: tools/ci/install_consumers.sh BUILD_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
checks=0
step() { echo "install: $*" >&2; }

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
step "installed into $prefix ($(find "$prefix" -type f | wc -l) files)"
libdir=$(dirname "$(find "$prefix" -name 'libngi_c.so' | head -1)")
[ -n "$libdir" ] || { step "libngi_c.so not installed"; exit 1; }
export PKG_CONFIG_PATH=$libdir/pkgconfig LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}

# 1. The shared C library exports the C ABI only.
others=$(nm -D --defined-only "$libdir/libngi_c.so" | awk '{print $3}' | grep -v '^ngi_' || true)
if [ -n "$others" ]; then step "libngi_c.so exports non-ngi symbols:"; echo "$others" | head >&2; exit 1; fi
step "libngi_c.so exports $(nm -D --defined-only "$libdir/libngi_c.so" | grep -c ' ngi_') ngi_* symbols, nothing else"
checks=$((checks + 1))

# 2. C through pkg-config.
cflags="-std=c99 -Wall -Wextra -pedantic -Werror"
# shellcheck disable=SC2046,SC2086
cc $cflags "$root/tests/consumers/c_pkgconfig/main.c" -o "$work/c_consumer" $(pkg-config --cflags --libs ngi) -lm
for sample in "$root"/samples/c/*.c; do
  # shellcheck disable=SC2046,SC2086
  cc $cflags "$sample" -o "$work/$(basename "$sample" .c)" $(pkg-config --cflags --libs ngi)
  step "compiled $(basename "$sample") as C99 against the installed ngi.h"
  checks=$((checks + 1))
done
"$work/c_consumer" "$root/models/single_view.safetensors" >&2
checks=$((checks + 1))

# 3. C++ through find_package(ngi).
cmake -S "$root/tests/consumers/cxx_find_package" -B "$work/cxx" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" > "$work/cxx-configure.log" || { cat "$work/cxx-configure.log" >&2; exit 1; }
cmake --build "$work/cxx" > "$work/cxx-build.log" || { cat "$work/cxx-build.log" >&2; exit 1; }
"$work/cxx/cxx_consumer" "$root/models/surround.safetensors" >&2
checks=$((checks + 1))

# 4. Python: the installed package (pure-Python modules + the native module) imports from the prefix alone and
# runs a shipped model, from a directory that holds no ngi sources.
pydir=$prefix/lib/python3/dist-packages
if [ -d "$pydir/ngi" ]; then
  (cd "$work" && PYTHONPATH=$pydir /usr/bin/python3 -c '
import sys, numpy as np, ngi
assert ngi.__file__.startswith(sys.argv[1]), ngi.__file__
m = ngi.Model(ngi.Device(), sys.argv[2])
y = m.run(np.zeros((1, 48, 4, 4), np.float32))
assert y.shape == (1, 1, 4, 4) and np.isfinite(y).all()
import ngi.model_file
print("install: python: ngi", ngi.__version__, "from", ngi.__file__, file=sys.stderr)
' "$pydir" "$root/models/ao_sculpture_16x8.safetensors") || { step "the installed Python package does not work"; exit 1; }
  checks=$((checks + 1))
else
  step "no Python package installed ($pydir)"; exit 1
fi
echo "$checks"

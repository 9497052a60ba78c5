#!/usr/bin/env bash
# Out-of-tree consumers of an installed ngi, one per exported target, built against the installed files only:
#   C99 through pkg-config (plus every samples/c/*.c, all -std=c99 -Wall -Wextra -pedantic -Werror), linked with
#   the rpath the README documents; C through find_package(ngi COMPONENTS c); C++ through find_package for
#   ngi::core (which must not look for OpenEXR, libpng or assimp), ngi::io, ngi::pipeline (the default components;
#   the application owns its OpenCL context) and ngi::render; the ngi CLI and the Python package finding the
#   shipped models by name; the READMEs' C++ and Python snippets (tools/ci/readme_snippets.py). Checks that libngi_c
#   exports nothing but the C ABI. Prints the number of checks passed
#   on stdout; exits non-zero on a failure.
# Usage: tools/ci/install_consumers.sh BUILD_DIR              the install stage of tools/test.sh: installs
#                                                             BUILD_DIR into a temporary prefix and tests that
#        tools/ci/install_consumers.sh --installed PREFIX     an existing installation on the system's default
#                                                             paths (the package stage: the .debs, PREFIX /usr):
#                                                             no search path is set, nothing is found elsewhere
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
checks=0
step() { echo "install: $*" >&2; }
run_logged() {  # log, command...: the command's output only on failure
  local log=$1; shift
  "$@" > "$log" 2>&1 || { cat "$log" >&2; return 1; }
}

if [ "${1:-}" = --installed ]; then
  prefix=$2 system=1
  cmake_prefix=()
  pydir=$prefix/lib/python3/dist-packages
else
  build=$(cd "$1" && pwd) system=0
  prefix=$work/prefix
  cmake --install "$build" --prefix "$prefix" > "$work/install.log"
  step "installed into $prefix ($(find "$prefix" -type f | wc -l) files)"
  cmake_prefix=(-DCMAKE_PREFIX_PATH="$prefix")
  pydir=$prefix/lib/python3/dist-packages
fi
libngi=$(find "$prefix/lib" -maxdepth 2 -name 'libngi_c.so' | head -1)
[ -n "$libngi" ] || { step "libngi_c.so not installed under $prefix/lib"; exit 1; }
libdir=$(dirname "$libngi")
models=$prefix/share/ngi/models
[ -f "$models/zoo.json" ] && [ -f "$models/surround.safetensors" ] || { step "no models in $models"; exit 1; }
step "models: $(find "$models" -name '*.safetensors' | wc -l) files in $models"
if [ $system = 0 ]; then export PKG_CONFIG_PATH=$libdir/pkgconfig; fi
# A consumer resolves model names from the installed models: with the override pointing there for a temporary
# prefix (a program outside the prefix has nothing else to find it by), by the system path for /usr.
model_env=()
if [ $system = 0 ]; then model_env=(NGI_MODEL_PATH="$models"); fi

# 1. The shared C library exports the C ABI only.
others=$(nm -D --defined-only "$libngi" | awk '{print $3}' | grep -v '^ngi_' || true)
if [ -n "$others" ]; then step "libngi_c.so exports non-ngi symbols:"; echo "$others" | head >&2; exit 1; fi
step "libngi_c.so exports $(nm -D --defined-only "$libngi" | grep -c ' ngi_') ngi_* symbols, nothing else"
checks=$((checks + 1))

# 2. C through pkg-config, run through the rpath of pkg-config's libdir (README), no LD_LIBRARY_PATH.
cflags="-std=c99 -Wall -Wextra -pedantic -Werror"
rpath="-Wl,-rpath,$(pkg-config --variable=libdir ngi)"
[ $system = 1 ] && rpath=""   # a standard libdir: the loader finds it
# shellcheck disable=SC2046,SC2086
cc $cflags "$root/tests/consumers/c_pkgconfig/main.c" -o "$work/c_consumer" $(pkg-config --cflags --libs ngi) $rpath -lm
for sample in "$root"/samples/c/*.c; do
  # shellcheck disable=SC2046,SC2086
  cc $cflags "$sample" -o "$work/$(basename "$sample" .c)" $(pkg-config --cflags --libs ngi) $rpath
  step "compiled $(basename "$sample") as C99 against the installed ngi.h"
  checks=$((checks + 1))
done
env -u LD_LIBRARY_PATH "$work/c_consumer" "$models/single_view.safetensors" >&2
checks=$((checks + 1))

# 3. CMake consumers, one per exported target (each run without LD_LIBRARY_PATH: CMake's build rpath for ngi::c).
cmake_consumer() {  # folder: configure and build tests/consumers/<folder>
  run_logged "$work/$1-configure.log" cmake -S "$root/tests/consumers/$1" -B "$work/$1" -G Ninja \
    -DCMAKE_BUILD_TYPE=Release "${cmake_prefix[@]}"
  run_logged "$work/$1-build.log" cmake --build "$work/$1"
}
cmake_consumer c_find_package
env -u LD_LIBRARY_PATH "$work/c_find_package/c_cmake_consumer" "$models/single_view.safetensors" >&2
checks=$((checks + 1))
# ngi::core: the configure step itself fails if find_package looked for OpenEXR, libpng or assimp; the program
# finds a shipped model by name, and it must be the installed one.
cmake_consumer cxx_core
got=$(env -u LD_LIBRARY_PATH "${model_env[@]}" "$work/cxx_core/cxx_core_consumer" single_view)
[ "$got" = "$models/single_view.safetensors" ] || { step "ngi::core: 'single_view' resolved to $got, not $models"; exit 1; }
grep -q -i -E 'openexr|imath|assimp' "$work/cxx_core/CMakeCache.txt" &&
  { step "ngi::core consumer: its CMake cache names an image-file or mesh library"; exit 1; }
checks=$((checks + 1))
cmake_consumer cxx_io
"$work/cxx_io/cxx_io_consumer" "$work" >&2
checks=$((checks + 1))
cmake_consumer cxx_find_package   # ngi::pipeline through the default components (core, pipeline, c)
grep -q -i -E 'openexr|imath|assimp' "$work/cxx_find_package/CMakeCache.txt" &&
  { step "ngi::pipeline consumer: find_package(ngi) without components looked for OpenEXR or assimp"; exit 1; }
"$work/cxx_find_package/cxx_consumer" "$models/surround.safetensors" >&2
checks=$((checks + 1))
cmake_consumer cxx_render
"$work/cxx_render/cxx_render_consumer" >&2
checks=$((checks + 1))

# 4. The CLI finds the installed models by name, relative to itself (no override).
/usr/bin/python3 -c 'import numpy as np, sys; np.save(sys.argv[1], np.zeros((1, 10, 64, 64), np.float32))' "$work/x.npy"
out=$(env -u NGI_MODEL_PATH "$prefix/bin/ngi" generate --model single_view --input "$work/x.npy" --output "$work/y.npy")
echo "$out" | grep -q "^model *$models/single_view.safetensors:" ||
  { echo "$out" >&2; step "ngi generate --model single_view did not load $models/single_view.safetensors"; exit 1; }
step "ngi generate --model single_view: $models/single_view.safetensors"
checks=$((checks + 1))

# 5. Python: the installed package (pure-Python modules + the native module) imports from the prefix alone, from a
# directory that holds no ngi sources, finds the installed models by name and runs one.
# PYTHONPATH in both modes: for /usr too, since a build tree registered with the system Python (tools/build.sh
# writes an ngi.pth into site-packages, as an editable install does) would otherwise be found before dist-packages.
pypath=(PYTHONPATH="$pydir")
[ -d "$pydir/ngi" ] || { step "no Python package installed ($pydir)"; exit 1; }
(cd "$work" && env -u NGI_MODEL_PATH "${pypath[@]}" /usr/bin/python3 -c '
import sys, numpy as np, ngi
pydir, models = sys.argv[1:]
assert ngi.__file__.startswith(pydir + "/"), ngi.__file__
m = ngi.Model(ngi.Device(), "surround")
assert m.path == models + "/surround.safetensors", (m.path, ngi.model_search_path())
y = ngi.Model(ngi.Device(), "ao_sculpture_16x8").run(np.zeros((1, 48, 4, 4), np.float32))
assert y.shape == (1, 1, 4, 4) and np.isfinite(y).all()
try:
    ngi.Model(ngi.Device(), "no_such_model")
    raise SystemExit("an unknown model name was accepted")
except ngi.InputError as e:
    assert "known names" in str(e) and "surround" in str(e), e
import ngi.model_file
print("install: python: ngi", ngi.__version__, "from", ngi.__file__, "model surround =", m.path, file=sys.stderr)
' "$pydir" "$models") || { step "the installed Python package does not work"; exit 1; }
checks=$((checks + 1))

# 6. The READMEs' snippets: README.md's C++ blocks built as one more find_package consumer, the Python blocks of
# README.md and bindings/python/README.md run with the installed package on a frame the installed CLI renders.
readme_cmake_prefix=""
[ ${#cmake_prefix[@]} -gt 0 ] && readme_cmake_prefix=${cmake_prefix[0]#-DCMAKE_PREFIX_PATH=}
n=$(env "${model_env[@]}" /usr/bin/python3 "$root/tools/ci/readme_snippets.py" --prefix "$prefix" \
      --pythonpath "$pydir" --cmake-prefix "$readme_cmake_prefix" --work "$work") ||
  { step "a README snippet does not build or run against the installed ngi"; exit 1; }
step "README snippets: $n built or run against the installed ngi"
checks=$((checks + n))
echo "$checks"

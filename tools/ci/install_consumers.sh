#!/usr/bin/env bash
# Out-of-tree consumers of an installed ngi, one per exported target, built against the installed files only:
#   C99 through pkg-config (plus every samples/c/*.c, all -std=c99 -Wall -Wextra -pedantic -Werror), linked with
#   the rpath the README documents; C through find_package(ngi COMPONENTS c); C++ through find_package for
#   ngi::core (which must not look for OpenEXR or libpng), ngi::io, ngi::pipeline (the default components;
#   the application owns its OpenCL context) and ngi::render; the ngi CLI and the Python package finding the
#   shipped models by name; the READMEs' C++ and Python snippets (tools/ci/readme_snippets.py); `ngi adapt` with the
#   installed Python packages (--help, a missing scene refused, and from a temporary prefix a whole tiny adaptation).
#   Checks that libngi_c exports nothing but the C ABI. Prints the number of checks passed on stdout; exits non-zero
#   on a failure.
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
# ngi::core: the configure step itself fails if find_package looked for OpenEXR or libpng; the program
# finds a shipped model by name, and it must be the installed one.
cmake_consumer cxx_core
got=$(env -u LD_LIBRARY_PATH "${model_env[@]}" "$work/cxx_core/cxx_core_consumer" single_view)
[ "$got" = "$models/single_view.safetensors" ] || { step "ngi::core: 'single_view' resolved to $got, not $models"; exit 1; }
grep -q -i -E 'openexr|imath' "$work/cxx_core/CMakeCache.txt" &&
  { step "ngi::core consumer: its CMake cache names an image-file library"; exit 1; }
checks=$((checks + 1))
cmake_consumer cxx_io
"$work/cxx_io/cxx_io_consumer" "$work" >&2
checks=$((checks + 1))
cmake_consumer cxx_find_package   # ngi::pipeline through the default components (core, pipeline, c)
grep -q -i -E 'openexr|imath' "$work/cxx_find_package/CMakeCache.txt" &&
  { step "ngi::pipeline consumer: find_package(ngi) without components looked for OpenEXR"; exit 1; }
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

# 7. `ngi adapt` (issue 46) from the installation alone: no PYTHONPATH, NGI_BIN or NGI_MODEL_PATH from outside, run
# from a folder without ngi sources. A stand-in interpreter records what the CLI hands over (NGI_ADAPT_PYTHON_DIRS
# must be the installed Python folder, NGI_BIN the installed ngi, PYTHONPATH not set), then runs the real one, which
# records at exit where ngi and ngi_train came from (the installed folder) and the sys.path the CLI's bootstrap left:
# the interpreter's own, with the installed folder first for a temporary prefix and in its own place for /usr (a
# site folder, behind /usr/local and ~/.local). --help is the adaptation's; a missing scene is refused before any
# work (exit 2, nothing written, not even a work folder in the cache). From a temporary prefix also a whole tiny
# adaptation through PREFIX/bin/ngi adapt (the stand-in shrinks ngi_train.adapt's frames and steps as
# training/tests/test_adapt.py does: 16 spp, 2 + 2 frames, 20-step chunks, a 30-second budget; about 40 s here): the
# base found by name among the installed models, the work folder in the user's cache, a model the installed ngi runs.
adapt_env=$work/adapt_env.txt
cat > "$work/adapt_tiny.py" << 'EOF'
import sys
code = sys.argv[2]  # python3 adapt_tiny.py -c BOOTSTRAP ARGS...: the CLI's bootstrap, run with ARGS
del sys.argv[1:3]
# The bootstrap's sys.path and checks, then ngi_train.adapt shrunk, then its run.
prepare, run = code.split("from ngi_train import adapt\n")
exec(prepare)
from ngi_train import adapt
for name, value in (("FEATURE_SPP", 16), ("REFERENCE_SPP", 16), ("VAL_FRAMES", (12, 62)), ("CHUNK_STEPS", 20),
                    ("MIN_TRAIN_SECONDS", 5.0), ("EXPORT_RESERVE_S", 5.0), ("MAX_TRAIN_FRAMES", 2)):
    setattr(adapt, name, value)
exec(run)
EOF
adapt_paths=$work/adapt_paths.txt
cat > "$work/adapt_paths.py" << EOF
import atexit, sys


def record():  # at exit: where ngi and ngi_train came from, and sys.path
    with open("$adapt_paths", "w") as f:
        for name in ("ngi", "ngi_train"):
            f.write("%s=%s\\n" % (name, getattr(sys.modules.get(name), "__file__", None)))
        f.write("".join("path=%s\\n" % p for p in sys.path))


atexit.register(record)
code = sys.argv[2]  # python3 adapt_paths.py -c BOOTSTRAP ARGS...: the CLI's bootstrap, run with ARGS
del sys.argv[1:3]
exec(code)
EOF
cat > "$work/adapt-python" << EOF
#!/bin/sh
printf '%s\n' "\${NGI_ADAPT_PYTHON_DIRS-}" "\${NGI_BIN-}" "\${PYTHONPATH-(unset)}" > "$adapt_env"
if [ -n "\${ADAPT_TINY-}" ]; then exec /usr/bin/python3 "$work/adapt_tiny.py" "\$@"; fi
exec /usr/bin/python3 "$work/adapt_paths.py" "\$@"
EOF
chmod +x "$work/adapt-python"
adapt_run() { (cd "$work" && env -u PYTHONPATH -u NGI_BIN -u NGI_MODEL_PATH NGI_PYTHON="$work/adapt-python" \
                 XDG_CACHE_HOME="$work/cache" "$@"); }
real_pydir=$(realpath "$pydir") real_ngi=$(realpath "$prefix/bin/ngi")
adapt_run "$prefix/bin/ngi" adapt --help > "$work/adapt_help.out" || { step "ngi adapt --help failed"; exit 1; }
grep -q "^usage: ngi adapt " "$work/adapt_help.out" && grep -q -- "--budget-minutes" "$work/adapt_help.out" ||
  { head -5 "$work/adapt_help.out" >&2; step "ngi adapt --help is not ngi_train.adapt's"; exit 1; }
[ "$(sed -n 1p "$adapt_env")" = "$real_pydir" ] && [ "$(sed -n 2p "$adapt_env")" = "$real_ngi" ] &&
  [ "$(sed -n 3p "$adapt_env")" = "(unset)" ] ||
  { cat "$adapt_env" >&2
    step "ngi adapt: NGI_ADAPT_PYTHON_DIRS is not $real_pydir, NGI_BIN not $real_ngi, or PYTHONPATH set"; exit 1; }
# The interpreter's own sys.path, run as the stand-in runs it (from $work, PYTHONSAFEPATH set by the CLI, no
# PYTHONPATH); the installed folder in front of it only where it is not on it already. ngi and ngi_train then come
# from the installed folder; for /usr from where the interpreter itself finds them (a folder before the site folder,
# such as the ngi.pth tools/build.sh registers in /usr/local, is left before it).
own_python() { (cd "$work" && env -u PYTHONPATH PYTHONSAFEPATH=1 /usr/bin/python3 -c "$1"); }
own=$(own_python 'import sys; print("\n".join(sys.path))')
real_own=$(while IFS= read -r p; do [ -n "$p" ] && realpath -m "$p"; done <<< "$own")
expected=$(grep -qx -- "$real_pydir" <<< "$real_own" || echo "$real_pydir"; echo "$own")
expected_from=("ngi=$real_pydir/ngi/__init__.py" "ngi_train=$real_pydir/ngi_train/__init__.py")
if grep -qx -- "$real_pydir" <<< "$real_own"; then
  mapfile -t expected_from < <(own_python 'import importlib.util as u
for n in ("ngi", "ngi_train"): print("%s=%s" % (n, u.find_spec(n).origin))')
fi
grep -qx -- "${expected_from[0]}" "$adapt_paths" && grep -qx -- "${expected_from[1]}" "$adapt_paths" ||
  { cat "$adapt_paths" >&2; step "ngi adapt: ngi or ngi_train not imported as ${expected_from[*]}"; exit 1; }
[ "$(sed -n 's/^path=//p' "$adapt_paths")" = "$expected" ] ||
  { diff <(echo "$expected") <(sed -n 's/^path=//p' "$adapt_paths") >&2
    step "ngi adapt: sys.path is not the interpreter's own with $real_pydir first only where it is missing"; exit 1; }
pydir_at=$(sed -n 's/^path=//p' "$adapt_paths" | grep -nx -- "$real_pydir" | cut -d: -f1 | head -1)
set +e
adapt_run "$prefix/bin/ngi" adapt --scene "$work/missing.vox" --out "$work/adapted.safetensors" 2> "$work/adapt_missing.err"
rc=$?
set -e
[ $rc = 2 ] && grep -q -- "--scene $work/missing.vox: cannot be loaded" "$work/adapt_missing.err" ||
  { cat "$work/adapt_missing.err" >&2; step "ngi adapt: a missing scene gave exit code $rc"; exit 1; }
[ ! -e "$work/adapted.safetensors" ] && [ ! -e "$work/cache/ngi/adapt" ] ||
  { step "ngi adapt: a missing scene left files behind"; exit 1; }
step "ngi adapt: --help and a missing scene refused (exit 2, nothing written), with $real_pydir" \
  "(sys.path[$((pydir_at - 1))]) and $real_ngi"
checks=$((checks + 1))
if [ $system = 0 ]; then
  start_adapt=$SECONDS
  adapt_run env ADAPT_TINY=1 "$prefix/bin/ngi" adapt --scene knot:seed=1 --out "$work/adapted.safetensors" \
      --budget-minutes 0.5 > "$work/adapt.log" 2>&1 || { tail -30 "$work/adapt.log" >&2; step "the tiny ngi adapt failed"; exit 1; }
  adapt_work=$work/cache/ngi/adapt/knot_seed1
  [ -f "$work/adapted.md" ] && [ -f "$adapt_work/adapt.json" ] ||
    { step "the tiny ngi adapt wrote no card, or not into its default work folder $adapt_work"; exit 1; }
  (cd "$work" && PYTHONPATH="$pydir" /usr/bin/python3 -c '
import sys, ngi.model_file as model_file
a = model_file.read_config(sys.argv[1])["adapt"]
assert a["base"] == "adapt_base_ssgi_residual_n64" and a["scene"] == "knot:seed=1" and a["steps"] >= 20, a
' "$work/adapted.safetensors") || { step "the tiny ngi adapt's model has no adapt record"; exit 1; }
  frame=$(find "$adapt_work/data/val" -mindepth 1 -maxdepth 1 -type d | sort | head -1)
  env -u NGI_MODEL_PATH "$prefix/bin/ngi" lightmap --frame "$frame" --model "$work/adapted.safetensors" \
      --out "$work/adapted_lightmap" > "$work/adapted_lightmap.log" 2>&1 ||
    { cat "$work/adapted_lightmap.log" >&2; step "the installed ngi does not run the adapted model"; exit 1; }
  step "ngi adapt: a tiny adaptation through $prefix/bin/ngi, run by its ngi lightmap ($((SECONDS - start_adapt)) s)"
  checks=$((checks + 1))
fi
echo "$checks"

#!/usr/bin/env bash
# The package stage of tools/test.sh: the Debian packages (debian/) made from an existing, built tree without
# building ngi again (NGI_DEB_BUILD_DIR: debian/rules only runs `cmake --install`), installed with dpkg, tested by
# tools/ci/install_consumers.sh --installed /usr (the C, C++, CLI and Python consumers against the installed files
# only), then purged; then `pip install .` of the same tree into a fresh venv, its models and its `ngi` command.
# The .debs, .buildinfo, .changes and the venv go to a temporary folder, not next to the checkout.
# Prints the number of checks passed on stdout; exits non-zero on a failure. Needs root (dpkg -i).
# Usage: tools/ci/package.sh BUILD_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
packages=(libngi-c0 libngi-dev ngi-tools python3-ngi ngi-models)
step() { echo "package: $*" >&2; }
installed() { dpkg-query -W -f='${Status}' "$1" 2> /dev/null | grep -q "ok installed"; }

[ "$(id -u)" -eq 0 ] || { step "needs root (dpkg -i)"; exit 1; }
for p in "${packages[@]}"; do
  if installed "$p"; then step "$p is installed already: not touching a system that has ngi packages"; exit 1; fi
done
out=$(mktemp -d)
cleanup() {
  local ours=()
  for p in "${packages[@]}"; do if installed "$p"; then ours+=("$p"); fi; done
  if [ ${#ours[@]} -gt 0 ]; then dpkg --purge "${ours[@]}" > "$out/purge.log" 2>&1 || cat "$out/purge.log" >&2; fi
  (cd "$root" && NGI_DEB_BUILD_DIR="$build" debian/rules clean > /dev/null 2>&1) || true
  rm -rf "$out"
}
trap cleanup EXIT

start=$SECONDS
if ! (cd "$root" && NGI_DEB_BUILD_DIR="$build" NGI_DEB_OUT="$out" dpkg-buildpackage -b --no-sign \
        --buildinfo-file="$out/ngi.buildinfo" --buildinfo-option=-u"$out" \
        --changes-file="$out/ngi.changes" --changes-option=-u"$out") > "$out/build.log" 2>&1; then
  tail -40 "$out/build.log" >&2; step "dpkg-buildpackage failed"; exit 1
fi
debs=("$out"/*.deb)
[ ${#debs[@]} -eq ${#packages[@]} ] || { step "expected ${#packages[@]} packages, got: ${debs[*]##*/}"; exit 1; }
for d in "${debs[@]}"; do step "built ${d##*/} ($(du -h "$d" | cut -f1), $(dpkg-deb -c "$d" | grep -c -v '/$') files)"; done
step "dpkg-buildpackage from $build: $((SECONDS - start)) s"

start=$SECONDS
dpkg -i "${debs[@]}" > "$out/install.log" 2>&1 || { cat "$out/install.log" >&2; step "dpkg -i failed"; exit 1; }
step "installed ${packages[*]} ($((SECONDS - start)) s)"
checks=$(bash "$root/tools/ci/install_consumers.sh" --installed /usr)

# Removed again, leaving nothing of ngi behind.
start=$SECONDS
dpkg --purge "${packages[@]}" > "$out/purge.log" 2>&1 || { cat "$out/purge.log" >&2; step "dpkg --purge failed"; exit 1; }
left=$(ls -d /usr/share/ngi /usr/lib/cmake/ngi /usr/include/ngi /usr/lib/python3/dist-packages/ngi \
          /usr/lib/python3/dist-packages/ngi_train /usr/bin/ngi /usr/lib/libngi_c.so* 2> /dev/null || true)
[ -z "$left" ] || { step "left behind after purging: $left"; exit 1; }
step "purged ($((SECONDS - start)) s)"

# pip: `pip install .` offline into a fresh virtual environment (system site packages: Debian's numpy, setuptools),
# reusing the same build tree (NGI_PIP_BUILD_DIR: no second build), then the package, its models and the ngi entry
# point from a folder without ngi sources.
start=$SECONDS
/usr/bin/python3 -m venv --system-site-packages "$out/venv"
if ! (cd "$root" && NGI_PIP_BUILD_DIR="$build" "$out/venv/bin/pip" install --no-build-isolation --no-index .) \
    > "$out/pip.log" 2>&1; then
  tail -30 "$out/pip.log" >&2; step "pip install . failed"; exit 1
fi
site=$("$out/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
(cd "$out" && env -u NGI_MODEL_PATH -u PYTHONPATH "$out/venv/bin/python" -c '
import sys, ngi
m = ngi.Model(ngi.Device(), "surround")
assert ngi.__file__.startswith(sys.argv[1] + "/"), ngi.__file__
assert m.path == sys.argv[1] + "/ngi/models/surround.safetensors", m.path
print("package: pip: ngi", ngi.__version__, "from", ngi.__file__, "model surround =", m.path, file=sys.stderr)
' "$site") || { step "the pip-installed package does not work"; exit 1; }
/usr/bin/python3 -c 'import numpy as np, sys; np.save(sys.argv[1], np.zeros((1, 10, 64, 64), np.float32))' "$out/x.npy"
out_cli=$(env -u NGI_MODEL_PATH "$out/venv/bin/ngi" generate --model single_view --input "$out/x.npy" --output "$out/y.npy")
echo "$out_cli" | grep -q "^model *$site/ngi/models/single_view.safetensors:" ||
  { echo "$out_cli" >&2; step "the pip-installed ngi command did not find its models"; exit 1; }
# `ngi adapt` of the pip installation: the venv's interpreter and its own ngi_train (ngi_train.adapt's usage line).
(cd "$out" && env -u PYTHONPATH "$out/venv/bin/ngi" adapt --help | grep -q "^usage: ngi adapt ") ||
  { step "the pip-installed ngi adapt --help does not run ngi_train.adapt"; exit 1; }
env -u PYTHONPATH "$out/venv/bin/python" -c 'import sys, ngi_train.adapt as a; assert a.__file__.startswith(sys.argv[1] + "/"), a.__file__' "$site" ||
  { step "the pip installation has no ngi_train of its own"; exit 1; }
step "pip install . into a fresh venv, ngi.Model(dev, 'surround'), the ngi entry point and ngi adapt: $((SECONDS - start)) s"
echo $((checks + 5))

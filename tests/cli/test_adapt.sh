#!/usr/bin/env bash
# `ngi adapt` (ctest cli_adapt): the command runs the Python adaptation in place of itself. With a stand-in
# interpreter ($NGI_PYTHON, a shell script): the arguments arrive exactly as given (a leading "--", empty ones,
# spaces, --help), the exit code is the interpreter's, it is the same process (exec) so SIGTERM reaches it and a
# death by a signal is the command's, NGI_ADAPT_PYTHON_DIRS names the build tree's package folders (PYTHONPATH is the
# caller's) and NGI_BIN this ngi; an interpreter that cannot be started is reported (exit 1). With /usr/bin/python3
# and stub packages ngi and ngi_train laid out as `pip install .` does: the sys.path the bootstrap gives (the
# installation's folder first unless Python searches it already, then in its place; never the current folder). With
# the real interpreter and packages (when the build has the native module): `ngi adapt --help` is the adaptation's, a
# missing scene is refused before any work (exit 2), and what cannot be imported is named (an interpreter without
# NumPy, PyTorch, tqdm; a binary that finds no ngi_train).
# Usage: test_adapt.sh NGI_BINARY WORK_DIR
set -euo pipefail
ngi=$(realpath "$1") work=$2
rm -rf "$work" && mkdir -p "$work"
work=$(realpath "$work")
fail() { echo "FAILED: $*" >&2; exit 1; }
build=$(dirname "$ngi")
source_training=$(cd "$(dirname "$0")/../../training" && pwd)

# The stand-in interpreter: records its pid, arguments (NUL-separated, after `-c BOOTSTRAP`) and environment, then
# exits with $FAKE_RC, waits for a signal ($FAKE_WAIT), or kills itself with $FAKE_SIGNAL.
fake=$work/fake-python
cat > "$fake" << 'EOF'
#!/usr/bin/env bash
[ "$1" = -c ] && [ -n "$2" ] || { echo "fake-python: expected -c CODE, got: $*" >&2; exit 99; }
shift 2
: > "$FAKE_OUT.args"
if [ $# -gt 0 ]; then printf '%s\0' "$@" > "$FAKE_OUT.args"; fi
printf 'pid=%s\nPYTHONPATH=%s\nNGI_ADAPT_PYTHON_DIRS=%s\nNGI_BIN=%s\nPYTHONSAFEPATH=%s\n' "$$" "${PYTHONPATH-}" \
    "${NGI_ADAPT_PYTHON_DIRS-(unset)}" "${NGI_BIN-}" "${PYTHONSAFEPATH-}" > "$FAKE_OUT.env"
if [ -n "${FAKE_WAIT-}" ]; then
  trap 'echo "got TERM" > "$FAKE_OUT.signal"; exit 143' TERM
  touch "$FAKE_OUT.ready"
  for _ in $(seq 300); do sleep 0.1; done
  exit 98
fi
if [ -n "${FAKE_SIGNAL-}" ]; then kill -"$FAKE_SIGNAL" $$; fi
exit "${FAKE_RC:-0}"
EOF
chmod +x "$fake"
export FAKE_OUT=$work/run
export NGI_PYTHON=$fake

# 1. The arguments, exactly.
args=(-- --scene "a scene with spaces.vox" "" --help -h --version --budget-minutes=3 adapt "-" "x=y")
"$ngi" adapt "${args[@]}" || fail "ngi adapt with the stand-in interpreter: exit code $?"
printf '%s\0' "${args[@]}" > "$work/expected.args"
cmp -s "$work/expected.args" "$FAKE_OUT.args" ||
  fail "ngi adapt did not pass its arguments as given: $(tr '\0' '|' < "$FAKE_OUT.args")"
"$ngi" adapt || fail "ngi adapt without arguments: exit code $?"
[ ! -s "$FAKE_OUT.args" ] || fail "ngi adapt without arguments passed some: $(tr '\0' '|' < "$FAKE_OUT.args")"

# 2. The environment: the build tree's package folders in NGI_ADAPT_PYTHON_DIRS (in that order; a caller's value
# replaced), the caller's PYTHONPATH as it was (a folder put there would come before the standard library and every
# site folder); this ngi as NGI_BIN. A copy of the binary outside any build tree or installation hands over none.
PYTHONPATH=/caller/path NGI_ADAPT_PYTHON_DIRS=/stale "$ngi" adapt --x > /dev/null
grep -qx "NGI_ADAPT_PYTHON_DIRS=$build/python:$source_training" "$FAKE_OUT.env" ||
  fail "NGI_ADAPT_PYTHON_DIRS: $(grep NGI_ADAPT_PYTHON_DIRS "$FAKE_OUT.env"), expected $build/python:$source_training"
grep -qx "PYTHONPATH=/caller/path" "$FAKE_OUT.env" ||
  fail "PYTHONPATH: $(grep PYTHONPATH "$FAKE_OUT.env"), expected the caller's /caller/path unchanged"
grep -qx "NGI_BIN=$ngi" "$FAKE_OUT.env" || fail "NGI_BIN: $(grep NGI_BIN "$FAKE_OUT.env"), expected $ngi"
grep -qx "PYTHONSAFEPATH=1" "$FAKE_OUT.env" || fail "PYTHONSAFEPATH not set: $(cat "$FAKE_OUT.env")"
env -u PYTHONPATH "$ngi" adapt --x > /dev/null
grep -qx "PYTHONPATH=" "$FAKE_OUT.env" || fail "PYTHONPATH set without a caller's: $(grep PYTHONPATH "$FAKE_OUT.env")"
mkdir -p "$work/bin" && cp "$ngi" "$work/bin/ngi"
NGI_ADAPT_PYTHON_DIRS=/stale "$work/bin/ngi" adapt --x > /dev/null
grep -qx "NGI_ADAPT_PYTHON_DIRS=(unset)" "$FAKE_OUT.env" ||
  fail "a copied binary: $(grep NGI_ADAPT_PYTHON_DIRS "$FAKE_OUT.env"), expected none"

# 3. Exit codes, as they are.
for rc in 0 1 2 7 130; do
  set +e; FAKE_RC=$rc "$ngi" adapt --scene s; got=$?; set -e
  [ "$got" = "$rc" ] || fail "the interpreter exited with $rc, ngi adapt with $got"
done

# 4. One process (exec): the pid is ngi's, SIGTERM sent to it reaches the adaptation, and a death by a signal is
# the command's.
rm -f "$FAKE_OUT.ready" "$FAKE_OUT.signal"
FAKE_WAIT=1 "$ngi" adapt --scene s &
pid=$!
for _ in $(seq 100); do [ -e "$FAKE_OUT.ready" ] && break; sleep 0.1; done
[ -e "$FAKE_OUT.ready" ] || fail "the stand-in interpreter did not start"
grep -qx "pid=$pid" "$FAKE_OUT.env" || fail "the interpreter runs as another process ($(grep pid= "$FAKE_OUT.env"), ngi $pid)"
kill -TERM "$pid"
set +e; wait "$pid"; got=$?; set -e
[ "$got" = 143 ] && grep -q "got TERM" "$FAKE_OUT.signal" 2> /dev/null ||
  fail "SIGTERM to ngi adapt: exit code $got, the interpreter $(cat "$FAKE_OUT.signal" 2> /dev/null || echo 'got nothing')"
set +e; (FAKE_SIGNAL=TERM "$ngi" adapt --scene s; exit $?) 2> /dev/null; got=$?; set -e  # no "Terminated" line
[ "$got" = 143 ] || fail "the interpreter died of SIGTERM, ngi adapt exited with $got (expected 143)"

# 5. An interpreter that cannot be started: named, with what the adaptation needs; exit 1. A name without a slash
# is looked up on PATH.
set +e; NGI_PYTHON=$work/no-such-python "$ngi" adapt --scene s 2> "$work/nopython.err"; got=$?; set -e
[ "$got" = 1 ] && grep -q "cannot run the Python interpreter $work/no-such-python" "$work/nopython.err" &&
  grep -q "PyTorch" "$work/nopython.err" || fail "no interpreter: exit code $got, $(cat "$work/nopython.err")"
PATH=$work:$PATH NGI_PYTHON=fake-python "$ngi" adapt --on-path > /dev/null ||
  fail "NGI_PYTHON=fake-python (on PATH): exit code $?"
grep -qx -- "--on-path" <(tr '\0' '\n' < "$FAKE_OUT.args") || fail "NGI_PYTHON=fake-python: not run"

# 6. `ngi help adapt` and `ngi --help` are the CLI's own (no interpreter runs).
rm -f "$FAKE_OUT.args"
"$ngi" help adapt > "$work/help.out" || fail "ngi help adapt: exit code $?"
grep -q "Usage: ngi adapt ARGS" "$work/help.out" && grep -q "exit code" "$work/help.out" ||
  fail "ngi help adapt: $(cat "$work/help.out")"
"$ngi" --help | grep -q "^  adapt " || fail "ngi --help does not list adapt"
[ ! -e "$FAKE_OUT.args" ] || fail "ngi help adapt ran the interpreter"
unset NGI_PYTHON

# 7. The sys.path the bootstrap gives, in /usr/bin/python3: an installation laid out as `pip install .` lays it out
# (ngi/ngi-cli, this binary, beside stub packages ngi and ngi_train whose adapt.main prints where ngi and ngi_train
# come from and sys.path), run from a folder that holds a package named ngi, with another one on PYTHONPATH.
if /usr/bin/python3 -c 'import importlib.util as u, sys; sys.exit(not all(u.find_spec(m) for m in ("numpy", "torch", "tqdm")))'; then
  site=$work/site
  mkdir -p "$site/ngi" "$site/ngi_train" "$work/user/ngi" "$work/cwd/ngi" "$work/pkgs"
  cp "$ngi" "$site/ngi/ngi-cli"
  touch "$site/ngi/__init__.py" "$site/ngi_train/__init__.py" "$work/user/ngi/__init__.py" "$work/cwd/ngi/__init__.py"
  printf '%s\n' 'import sys' 'import ngi' 'import ngi_train' '' '' 'def main(argv, prog=None):' \
    '    print("ngi=" + ngi.__file__)' '    print("ngi_train=" + ngi_train.__file__)' \
    '    print("".join("path=%s\n" % p for p in sys.path), end="")' '    return 0' > "$site/ngi_train/adapt.py"
  stub_paths() {  # PYTHONSAFEPATH PYTHONPATH: the stub adaptation's output, run from $work/cwd
    (cd "$work/cwd" && env PYTHONSAFEPATH="$1" PYTHONPATH="$2" NGI_PYTHON=/usr/bin/python3 "$site/ngi/ngi-cli" adapt) ||
      fail "the stub adaptation: exit code $?"
  }
  first_two() { sed -n 's/^path=//p' "$1" | head -2 | tr '\n' '|'; }
  # Not on sys.path: the installation's folder first, before PYTHONPATH's; never the current folder, also where the
  # interpreter puts it there (an empty PYTHONSAFEPATH counts as unset, as Python < 3.11 ignores it).
  for safe in 1 ""; do
    stub_paths "$safe" "$work/user" > "$work/paths.out"
    grep -qx "ngi=$site/ngi/__init__.py" "$work/paths.out" &&
      grep -qx "ngi_train=$site/ngi_train/__init__.py" "$work/paths.out" ||
      fail "PYTHONSAFEPATH='$safe': ngi or ngi_train is not the installation's: $(cat "$work/paths.out")"
    [ "$(first_two "$work/paths.out")" = "$site|$work/user|" ] ||
      fail "PYTHONSAFEPATH='$safe': sys.path does not start with $site, $work/user: $(cat "$work/paths.out")"
    ! grep -qx -e "path=" -e "path=$work/cwd" "$work/paths.out" ||
      fail "PYTHONSAFEPATH='$safe': the current folder is on sys.path: $(cat "$work/paths.out")"
  done
  # On sys.path already (as a site folder is; here through PYTHONPATH, behind another folder): left in its place,
  # once, and the interpreter's own order untouched, the standard library's included.
  stub_paths 1 "$work/pkgs:$site" > "$work/paths.out"
  (cd "$work/cwd" && PYTHONSAFEPATH=1 PYTHONPATH="$work/pkgs:$site" /usr/bin/python3 -c \
     'import sys; print("".join("path=%s\n" % p for p in sys.path), end="")') > "$work/own.out"
  [ "$(grep '^path=' "$work/paths.out")" = "$(cat "$work/own.out")" ] && [ "$(first_two "$work/paths.out")" = "$work/pkgs|$site|" ] ||
    fail "a folder on sys.path already was moved, or the order changed: $(diff "$work/own.out" <(grep '^path=' "$work/paths.out"))"
else
  echo "cli_adapt: /usr/bin/python3 has no NumPy, PyTorch or tqdm: the sys.path checks skipped"
fi

# 8. The real interpreter (the build's native module is needed to import ngi).
if ! ls "$build"/python/ngi/_ngi*.so > /dev/null 2>&1; then
  echo "cli_adapt: the stand-in interpreter checks passed; no native module in $build/python: real-Python checks skipped"
  exit 0
fi
"$ngi" adapt --help > "$work/adapt_help.out" || fail "ngi adapt --help: exit code $?"
grep -q "^usage: ngi adapt " "$work/adapt_help.out" && grep -q -- "--budget-minutes" "$work/adapt_help.out" ||
  fail "ngi adapt --help: $(head -5 "$work/adapt_help.out")"
# A scene that does not exist: refused before any work (exit 2), nothing written, not even the work folder.
set +e
XDG_CACHE_HOME=$work/cache "$ngi" adapt --scene "$work/missing.vox" --out "$work/m.safetensors" 2> "$work/missing.err"
got=$?; set -e
[ "$got" = 2 ] && grep -q -- "--scene $work/missing.vox: cannot be loaded" "$work/missing.err" ||
  fail "a missing scene: exit code $got, $(cat "$work/missing.err")"
[ ! -e "$work/m.safetensors" ] && [ ! -e "$work/cache" ] && [ ! -e "$source_training/../runs/adapt/missing" ] ||
  fail "a missing scene: something was written"
# An interpreter without NumPy, PyTorch and tqdm (a virtual environment without the system's packages): each named.
if /usr/bin/python3 -m venv --without-pip "$work/venv" 2> /dev/null; then
  set +e; NGI_PYTHON=$work/venv/bin/python3 "$ngi" adapt --help > /dev/null 2> "$work/venv.err"; got=$?; set -e
  [ "$got" = 1 ] && grep -q "cannot import" "$work/venv.err" && grep -q "NumPy" "$work/venv.err" &&
    grep -q "PyTorch (Debian: python3-torch" "$work/venv.err" && grep -q "tqdm" "$work/venv.err" &&
    ! grep -q "training package" "$work/venv.err" || fail "an interpreter without PyTorch: exit code $got, $(cat "$work/venv.err")"
fi
# A copy of the binary outside any build tree or installation finds no ngi_train: named.
set +e; env -u PYTHONPATH "$work/bin/ngi" adapt --help > /dev/null 2> "$work/copy.err"; got=$?; set -e
[ "$got" = 1 ] && grep -q "training package ngi_train" "$work/copy.err" || fail "no ngi_train: exit code $got, $(cat "$work/copy.err")"
echo "cli_adapt: arguments, exit codes, SIGTERM, environment, sys.path and the missing pieces checked"

#!/usr/bin/env bash
# The oclgrind stage of tools/test.sh: runs Catch2 cases in the oclgrind simulator and fails on any diagnostic
# (oclgrind itself always exits 0, so its --log file must stay empty):
#   [oclgrind]        every kernel but the path tracer at small shapes, with --data-races --check-api --uninitialized
#   [oclgrind-small]  the cheapest path-tracer cases, with --data-races --check-api: oclgrind 21.10's
#                     uninitialized-value plugin crashes on the shufflevector instructions clang emits for
#                     3-component vectors in memory, which the tracer's kernels are full of (docs/RELIABILITY.md)
# Usage: tools/ci/oclgrind.sh BUILD_DIR. Writes BUILD_DIR/oclgrind/{*.log,cases}.
#
# Oclgrind presents one device (its own, reported as a GPU), so the GEMM's GPU table entry runs by default; the
# small conv/GEMM cases run the CPU knob sets and both fallback chains explicitly.
set -euo pipefail
build=$(cd "$1" && pwd)
out=$build/oclgrind
rm -rf "$out" && mkdir -p "$out"
# NGI_SELFCHECK=small: the GEMM self-check that Model::load runs uses only its first (small) problem; the
# K = 8192 and M = 1024 problems take minutes per variant in the simulator (ops/gemm_selfcheck.hpp).
export NGI_TEST_DEVICE=oclgrind NGI_CACHE_DIR=$out/cache NGI_SELFCHECK=small
total=0
run() {  # tag, oclgrind options...
  local tag=$1; shift
  local name=${tag//[^a-z-]/}
  local cases
  cases=$("$build/tests/ngi_tests" "$tag" --list-test-names-only | grep -c . || true)
  echo "oclgrind: $cases test cases tagged $tag" >&2
  [ "$cases" -gt 0 ] || { echo "oclgrind: no $tag test cases found" >&2; exit 1; }
  set +e
  oclgrind "$@" --log "$out/$name.log" "$build/tests/ngi_tests" "$tag" --durations yes >&2
  local rc=$?
  set -e
  local diagnostics=0
  [ -f "$out/$name.log" ] && diagnostics=$(grep -c . "$out/$name.log" || true)
  if [ "$diagnostics" -gt 0 ]; then
    echo "oclgrind: $diagnostics lines of diagnostics in $out/$name.log:" >&2
    head -60 "$out/$name.log" >&2
    exit 1
  fi
  [ $rc -eq 0 ] || { echo "oclgrind: $tag tests failed (exit $rc)" >&2; exit 1; }
  echo "oclgrind: $tag: $cases cases, 0 diagnostics" >&2
  total=$((total + cases))
}
run "[oclgrind]" --data-races --check-api --uninitialized
run "[oclgrind-small]" --data-races --check-api
echo "$total" > "$out/cases"

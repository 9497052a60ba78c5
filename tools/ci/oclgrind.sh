#!/usr/bin/env bash
# The oclgrind stage of tools/test.sh: runs the Catch2 cases tagged [oclgrind] (every kernel at small shapes) in
# the oclgrind simulator with out-of-bounds, data-race, uninitialized-value and API checks, and fails on any
# diagnostic. Usage: tools/ci/oclgrind.sh BUILD_DIR. Writes BUILD_DIR/oclgrind/{log,cases}.
#
# Oclgrind presents one device (its own, reported as a GPU), so the GEMM's GPU table entry runs by default; the
# [gemm][oclgrind] cases also run the CPU knob sets explicitly. Oclgrind 21.10 bugs ngi works around are listed
# in docs/RELIABILITY.md.
set -euo pipefail
build=$(cd "$1" && pwd)
out=$build/oclgrind
rm -rf "$out" && mkdir -p "$out"
# NGI_SELFCHECK=small: the GEMM self-check that Model::load runs uses only its first (small) problem; the
# K = 8192 and M = 1024 problems take minutes per variant in the simulator (ops/gemm_selfcheck.hpp).
export NGI_TEST_DEVICE=oclgrind NGI_CACHE_DIR=$out/cache NGI_SELFCHECK=small
cases=$("$build/tests/ngi_tests" "[oclgrind]" --list-test-names-only | grep -c . || true)
echo "oclgrind: $cases test cases tagged [oclgrind]" >&2
[ "$cases" -gt 0 ] || { echo "oclgrind: no [oclgrind] test cases found" >&2; exit 1; }
set +e
oclgrind --data-races --check-api --uninitialized --log "$out/log" "$build/tests/ngi_tests" "[oclgrind]" \
  --durations yes >&2
rc=$?
set -e
diagnostics=0
[ -f "$out/log" ] && diagnostics=$(grep -c . "$out/log" || true)
echo "$cases" > "$out/cases"
if [ "$diagnostics" -gt 0 ]; then
  echo "oclgrind: $diagnostics lines of diagnostics in $out/log:" >&2
  head -60 "$out/log" >&2
  exit 1
fi
[ $rc -eq 0 ] || { echo "oclgrind: tests failed (exit $rc)" >&2; exit 1; }
echo "oclgrind: $cases cases, 0 diagnostics" >&2

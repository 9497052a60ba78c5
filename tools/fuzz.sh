#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ into ./build-fuzz (clang-15, ASan + UBSan) and runs each for a bounded
# time, with the ONNX converter's Python fuzzer (fuzz/fuzz_onnx_convert.py, target onnx_convert) among them. Fails if any target crashes, leaks, times out (> 10 s on one input) or runs out of memory (> 2 GiB RSS).
#
#   tools/fuzz.sh [seconds_per_target] [runs]     defaults: 20 s each, no run limit (0 s = no time limit)
#   tools/fuzz.sh --corpus                        rebuild and rewrite the seed corpora fuzz/corpus/<target>/
#
# Environment: NGI_FUZZ_TARGETS="npy exr ..." runs only those (names without fuzz_); NGI_FUZZ_JOBS=2 runs two
# targets at a time. New inputs go to build-fuzz/corpus/<target>/ (fuzz/corpus/ is read as seeds only); crash
# reproducers to build-fuzz/artifacts/. Prints one line per target: execs, exec/s, peak RSS, result.
# NGI_FUZZ_RECORD_DIR=DIR also writes one JSON record per target run there (target, commit, executions of the one
# run, exec/s, peak RSS, findings): fuzz/records/ holds the committed campaigns.
# NGI_FUZZ_BUILD_DIR=DIR uses a tree already configured with -DNGI_FUZZ=ON (the test command's sanitize tree, which
# builds the fuzz targets beside the tests: one instrumented library instead of two) instead of ./build-fuzz.
set -uo pipefail
cd "$(dirname "$0")/.."
src=$PWD
out=${NGI_FUZZ_BUILD_DIR:-$src/build-fuzz}

if ! command -v clang++-15 >/dev/null; then
    echo "fuzz.sh: clang++-15 not found (apt-get install clang-15 libfuzzer-15-dev)" >&2
    exit 2
fi
mkdir -p "$out"
if [[ -z "${NGI_FUZZ_BUILD_DIR:-}" ]]; then
    # -O1 -gline-tables-only: OSS-Fuzz's flags (line numbers in crash reports; a quicker build than -O2 -g).
    CC=clang-15 CXX=clang++-15 cmake -S . -B "$out" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNGI_FUZZ=ON \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" -DNGI_BUILD_TESTS=OFF -DNGI_BUILD_PERF=OFF >"$out/cmake.log" 2>&1 ||
        { cat "$out/cmake.log" >&2; exit 2; }
elif ! grep -q '^NGI_FUZZ:BOOL=ON' "$out/CMakeCache.txt" 2>/dev/null; then
    echo "fuzz.sh: NGI_FUZZ_BUILD_DIR=$out is not a tree configured with -DNGI_FUZZ=ON" >&2
    exit 2
fi
# ngi_python_files: the pure-Python package (with the generated ngi/_constants.py) that the ONNX converter's fuzzer
# imports from the tree.
cmake --build "$out" -j "$(nproc)" --target fuzz_all ngi_python_files >"$out/fuzz-build.log" 2>&1 ||
    { tail -50 "$out/fuzz-build.log" >&2; exit 2; }

if [[ "${1:-}" == "--corpus" ]]; then
    # ngi_make_corpus replaces only the target folders it writes; vox and mesh keep their seed scripts' files and
    # the reproducers of earlier findings.
    exec "$out/fuzz/ngi_make_corpus" "$src/fuzz/corpus"
fi

seconds=${1:-20}
runs=${2:-}
# The commit a record names is the one the targets were built from (the tree's source folder, which differs from
# this checkout's when NGI_FUZZ_BUILD_DIR is another clone's tree).
built_from=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$out/CMakeCache.txt" 2>/dev/null)
built_from=${built_from:-$src}
# The commits a record names, taken now (before the runs: commits made during a long campaign are not what ran): the
# tree's for libFuzzer targets, this checkout's for Python targets (its script, and with NGI_FUZZ_PYTHONPATH its code).
commit_of() { git -C "$1" rev-parse HEAD 2>/dev/null || echo unknown; }
dirty_of() { git -C "$1" status --porcelain --untracked-files=no 2>/dev/null | head -c 1; }
built_commit=$(commit_of "$built_from") built_dirty=$(dirty_of "$built_from")
src_commit=$(commit_of "$src") src_dirty=$(dirty_of "$src")
declare -A max_len=([npy]=4096 [exr]=16384 [png]=8192 [camera_json]=1024 [dataset_config]=4096 [plan_file]=2048
                    [safetensors]=32768 [frame_folder]=16384 [mesh]=8192 [model_config]=8192)
targets=${NGI_FUZZ_TARGETS:-}
if [[ -z "$targets" ]]; then
    for f in "$src"/fuzz/fuzz_*.cpp "$src"/fuzz/fuzz_*.py; do n=$(basename "${f%.*}"); targets+=" ${n#fuzz_}"; done
fi
jobs=${NGI_FUZZ_JOBS:-1}
mkdir -p "$out/logs" "$out/artifacts"

run_one() {
    local t=$1 log=$out/logs/$1.log
    mkdir -p "$out/corpus/$t"
    local args=(-rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 -max_len="${max_len[$t]:-8192}"
                -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$out/artifacts/$t-")
    [[ -n "$runs" ]] && args+=(-runs="$runs")
    local seeds=()
    [[ -d "$src/fuzz/corpus/$t" ]] && seeds=("$src/fuzz/corpus/$t")
    [[ -f "$src/fuzz/$t.dict" ]] && args+=(-dict="$src/fuzz/$t.dict")
    if [[ -f "$src/fuzz/fuzz_$t.py" ]]; then
        # A Python target (the ONNX converter): libFuzzer's loop written in Python (fuzz/fuzz_onnx_convert.py), with
        # the same limits, corpus and artifact folders and stat:: lines. It imports ngi's pure-Python modules from
        # the tree; NGI_FUZZ_PYTHONPATH=build/python (a tree with the native module) and NGI_FUZZ_LOAD_CHECK=K also
        # load up to K converted models with the C++ loader.
        local py=(-max_total_time="$seconds" -artifact_prefix="$out/artifacts/$t-" --timeout 10 --rss-limit-mb 2048)
        [[ -n "$runs" ]] && py+=(-runs="$runs")
        [[ -n "${NGI_FUZZ_LOAD_CHECK:-}" ]] && py+=(--load-check "$NGI_FUZZ_LOAD_CHECK")
        PYTHONPATH=${NGI_FUZZ_PYTHONPATH:-$out/python} /usr/bin/python3 "$src/fuzz/fuzz_$t.py" "${py[@]}" \
            "$out/corpus/$t" "${seeds[@]}" >"$log" 2>&1
    else
        "$out/fuzz/fuzz_$t" "${args[@]}" "$out/corpus/$t" "${seeds[@]}" >"$log" 2>&1
    fi
    local rc=$?
    local execs rate rss
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
    local result=ok
    if [[ $rc -ne 0 ]]; then
        result="FAILED (exit $rc): $(grep -m1 -E 'ERROR: |==[0-9]+==ERROR|runtime error|Test unit written|==FINDING==' "$log" || tail -1 "$log"); log $log"
    fi
    printf '%-16s execs %10s  exec/s %7s  peak RSS %5s MB  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${rss:-?}" "$result"
    if [[ -n "${NGI_FUZZ_RECORD_DIR:-}" ]]; then  # one JSON record per campaign (issue 51: every figure on file)
        mkdir -p "$NGI_FUZZ_RECORD_DIR"
        local commit=$built_commit dirty=$built_dirty
        # A Python target's code is this checkout's only with NGI_FUZZ_PYTHONPATH (else the tree's copy of its own).
        [[ -f "$src/fuzz/fuzz_$t.py" && -n "${NGI_FUZZ_PYTHONPATH:-}" ]] && commit=$src_commit dirty=$src_dirty
        /usr/bin/python3 - "$NGI_FUZZ_RECORD_DIR" "$t" "${execs:-0}" "${rate:-0}" "${rss:-0}" "$rc" "$result" \
            "$seconds" "${runs:-}" "$commit" "$dirty" <<'PY'
import datetime, json, os, sys
d, t, execs, rate, rss, rc, result, seconds, runs, commit, dirty = sys.argv[1:]
now = datetime.datetime.now(datetime.timezone.utc)
rec = {"target": f"fuzz_{t}", "commit": commit, "tree_modified": bool(dirty), "date": now.isoformat(timespec="seconds"),
       "one_uninterrupted_run": True, "executions": int(execs), "exec_per_s": int(rate), "peak_rss_mb": int(rss),
       "runs_asked": int(runs or 0), "seconds_asked": int(seconds), "exit_code": int(rc),
       "findings": [] if int(rc) == 0 else [result], "cores": os.cpu_count(),
       "command": f"tools/fuzz.sh {seconds} {runs or ''}".strip() + f" (NGI_FUZZ_TARGETS={t})"}
path = os.path.join(d, f"{now:%Y-%m-%d}_fuzz_{t}_{commit[:7]}.json")
with open(path, "w") as f:
    json.dump(rec, f, indent=1)
    f.write("\n")
PY
    fi
    return $rc
}

fail=0
running=0
pids=()
for t in $targets; do
    if [[ ! -x "$out/fuzz/fuzz_$t" && ! -f "$src/fuzz/fuzz_$t.py" ]]; then
        echo "fuzz.sh: no target fuzz_$t" >&2; fail=1; continue
    fi
    run_one "$t" &
    pids+=($!)
    running=$((running + 1))
    if [[ $running -ge $jobs ]]; then
        wait -n || fail=1
        running=$((running - 1))
    fi
done
while [[ $running -gt 0 ]]; do
    wait -n || fail=1
    running=$((running - 1))
done
if [[ $fail -ne 0 ]]; then echo "fuzz.sh: FAILED" >&2; exit 1; fi
echo "fuzz.sh: all targets passed"

"""Check and measure ngi on every OpenCL device present: one JSON report and a proposed tuning-database entry.

For a user with a GPU (or any new device): does ngi compute correctly there, how fast, and which GEMM knobs should
the tuning database give it? For each device that `ngi devices --json` lists (rusticl needs RUSTICL_ENABLE=llvmpipe):

    self_check  ngi's GEMM self-check (the variant in use, the variants refused and why, the driver's loop limit)
    tests       the device's Catch2 cases with NGI_TEST_DEVICE=P:D: "quick" = the op harness ([op_harness]: every
                op against its naive reference, every GEMM knob set), "full" = every case, or any Catch2 filter
    tune        ngi_bench tune: a quick sweep of the device's GEMM knob space (each candidate checked against the
                host reference before it is timed); a winner other than the table's choice is run again beside it
                with more repeats, and only a confirmed gain (CONFIRM_GAIN) goes into OUT/gemm_tuning_proposed.json,
                a copy of kernels/gemm_tuning.json with this device's entry added or replaced (to propose, never
                applied here)
    bench:NAME  the benchmarks of perf/bench_devices.py (GEMM, generators, the whole frame, AO MLP, path tracer)

A device whose self-check fails (no GEMM variant reproduces the host reference) is reported as failed with the
reason; its benchmarks are not run ("not timed: ...") -- a wrong kernel is never timed as if correct. Its tests and
the tuner still run: the tuner may find a knob set that passes, which is the entry to propose.

Every finished step is written to OUT/report.json at once (atomically); a rerun with the same OUT keeps the steps
that passed and redoes the others (the report of another commit is refused). Progress with an ETA on stderr.

    tools/gpu_check.sh --out gpu_check                       # quick: op harness, tuner sweep, quick benchmarks
    tools/gpu_check.sh --out gpu_check --tests full --bench full
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree
from pathlib import Path

from tqdm import tqdm

from bench_devices import benchmarks, write_atomic  # perf/ is the script's folder: first on its path

REPO = Path(__file__).resolve().parent.parent

TEST_FILTERS = {"quick": "[op_harness]", "full": ""}
QUICK_BENCH = ["gemm", "generator_256x128", "frame_n64"]
# The tuner's quick sweep: two shapes small enough for slow devices (llvmpipe) yet past every tile size.
QUICK_TUNE_SHAPES = "512,512,512;128,4096,512"


def git_commit():
    try:
        return subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def tail(text, n=2000):
    return (text or "").strip()[-n:]


def run_step(cmd, env, timeout):
    """subprocess.run with a time limit: a step past it (a hung driver, a device too slow for the step) is killed and
    reported as failed, and the check goes on with the next step."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=REPO, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        return subprocess.CompletedProcess(cmd, -9, e.stdout or "", f"timed out after {timeout} s (--timeout); "
                                                                   f"{tail(e.stderr if isinstance(e.stderr, str) else '')}")


def run_tests(build, spec, filt, logs, env, timeout):
    """The device's Catch2 cases; counts from the JUnit report (Catch2's exit code is the failure count)."""
    xml = logs / f"tests_{spec.replace(':', '_')}.xml"
    cmd = [str(build / "tests" / "ngi_tests")] + ([filt] if filt else []) + ["-r", "junit", "-o", str(xml)]
    proc = run_step(cmd, dict(env, NGI_TEST_DEVICE=spec), timeout)
    if proc.returncode == -9 or not xml.is_file():
        return {"status": "failed", "error": f"exit {proc.returncode}, no report: {tail(proc.stderr)}"}
    root = ElementTree.parse(xml).getroot()
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    # Catch2 v2's JUnit "tests" counts assertions; each leaf section is a <testcase> named "case/section".
    checks = sum(int(s.get("tests", 0)) for s in suites)
    failures = sum(int(s.get("failures", 0)) + int(s.get("errors", 0)) for s in suites)
    names = [c.get("name", "") for c in root.iter("testcase")]
    cases = len({n.split("/", 1)[0] for n in names})
    failed = sorted({c.get("name") for c in root.iter("testcase")
                     if c.find("failure") is not None or c.find("error") is not None})
    ok = proc.returncode == 0 and failures == 0 and cases > 0
    result = {"status": "ok" if ok else "failed", "filter": filt or "(every case)", "cases": cases,
              "checks": checks, "failures": failures, "failed_cases": failed[:50],
              "junit": str(xml.relative_to(logs.parent))}
    if cases == 0:
        result["error"] = f"the filter {filt!r} matched no test case"
    return result


# A sweep's winner is proposed only when a second, longer run of it side by side with the table's choice confirms a
# gain of at least this much: with three repeats of millisecond GEMMs, noise alone moved one knob set 73 -> 177
# GFLOP/s between two runs here.
CONFIRM_GAIN = 1.05


def tune(build, spec, args, env, sets=None, repeats=None, write_db=None):
    """One ngi_bench tune run: (its JSON, None) or (None, a failed step)."""
    cmd = [str(build / "perf" / "ngi_bench"), "tune", "--device", spec, "--shapes", args.tune_shapes,
           "--repeats", str(repeats or args.repeats)]
    cmd += ["--sets", sets] if sets else ["--max", str(args.tune_max)]
    cmd += ["--write-db", str(write_db)] if write_db else []
    proc = run_step(cmd, env, args.timeout)
    if proc.returncode != 0:
        return None, {"status": "failed", "error": f"exit {proc.returncode}: {tail(proc.stderr)}"}
    return json.loads(proc.stdout), None


def run_tune(build, spec, args, proposal, env):
    """The tuner's quick sweep over the device's knob space, then the winner against the table's choice again with
    more repeats; a confirmed winner replaces this device's entry in the proposal file."""
    out, failed = tune(build, spec, args, env)
    if failed:
        return failed
    ranked = out["ranked"]
    passed = [r for r in ranked if "geomean_gflops" in r]
    table = out["device"]["gemm_params"]
    current = next((r for r in ranked if r["params"] == table), None)
    result = {"status": "ok", "shapes": out["shapes"], "candidates": len(ranked), "passed": len(passed),
              "rejected": [{"params": r["params"], "reason": r["rejected"]} for r in ranked if "rejected" in r],
              "winner": passed[0] if passed else None, "table_choice": current, "confirmation": None,
              "entry": None, "proposal": None}
    if not passed or passed[0]["params"] == table:
        return result  # nothing to propose: no set passed, or the table's choice won
    repeats = max(5, 3 * args.repeats)
    again, failed = tune(build, spec, args, env, sets=f"{passed[0]['params']};{table}", repeats=repeats)
    if failed:
        return dict(failed, sweep=result)
    rows = {r["params"]: r.get("geomean_gflops", 0.0) for r in again["ranked"]}
    gain = rows.get(passed[0]["params"], 0.0) / max(rows.get(table, 0.0), 1e-12)
    result["confirmation"] = {"repeats": repeats, "winner_gflops": rows.get(passed[0]["params"]),
                              "table_choice_gflops": rows.get(table), "gain": gain,
                              "confirmed": gain >= CONFIRM_GAIN}
    if gain < CONFIRM_GAIN:
        return result
    _, failed = tune(build, spec, args, env, sets=passed[0]["params"], repeats=1, write_db=proposal)
    if failed:
        return dict(failed, sweep=result)
    dev = out["device"]  # the entry ngi_bench wrote (matched on platform, device and driver)
    for e in json.loads(proposal.read_text())["entries"]:
        m = e.get("match", {})
        if m.get("device") == dev["name"] and m.get("platform") == dev["platform"] and m.get("driver") == dev["driver"]:
            result["entry"], result["proposal"] = e, proposal.name
    return result


def run_bench(argv, spec, env, timeout):
    proc = run_step([str(c) for c in argv] + ["--device", spec], env, timeout)
    if proc.returncode != 0:
        return {"status": "failed", "error": f"exit {proc.returncode}: {tail(proc.stderr)}"}
    return {"status": "ok", "result": json.loads(proc.stdout)}


def device_steps(self_check, tests, tune_max, bench_names):
    """The steps of one device, in order: (name, what runs) with what = "tests" | "tune" | "bench" | a refusal.

    A device whose self-check failed gets its benchmarks as refusals: they are reported, never timed."""
    steps = []
    if tests is not None:
        steps.append(("tests", "tests"))
    if tune_max > 0:
        steps.append(("tune", "tune"))
    for name in bench_names:
        if self_check.get("ok"):
            steps.append((f"bench:{name}", "bench"))
        else:
            steps.append((f"bench:{name}",
                          {"status": "failed", "error": "not timed: the GEMM self-check failed on this device: " +
                           self_check.get("error", "no reason given")}))
    return steps


def list_devices(build, env):
    proc = subprocess.run([str(build / "ngi"), "devices", "--json"], capture_output=True, text=True, env=env)
    try:
        return json.loads(proc.stdout)  # exit 3 with a failed self-check still lists every device
    except json.JSONDecodeError:
        raise SystemExit(f"gpu_check: `ngi devices --json` failed (exit {proc.returncode}): {tail(proc.stderr)}")


def summary_markdown(report):
    lines = ["| device | step | status | figure |", "| --- | --- | --- | --- |"]
    for spec, dev in report["devices"].items():
        name = f"{spec} {dev['info']['name']} ({dev['info']['platform']})"
        sc = dev["self_check"]
        lines.append(f"| {name} | self_check | {'ok' if sc.get('ok') else 'failed'} | "
                     f"{sc.get('gemm_variant', sc.get('error', ''))[:80]} |")
        for step, r in dev["steps"].items():
            figure = ""
            if r.get("status") != "ok":
                figure = r.get("error", "").splitlines()[-1][:80] if r.get("error") else f"{r.get('failures')} failures"
            elif step == "tests":
                figure = f"{r['cases']} cases, {r['checks']} checks, 0 failures, {r['wall_s']} s"
            elif step == "tune" and r.get("winner"):
                w, t, c = r["winner"], r.get("table_choice") or {}, r.get("confirmation")
                figure = (f"sweep: {w['params']} {w['geomean_gflops']:.3g} GFLOP/s, table's choice "
                          f"{t.get('params', '?')} {t.get('geomean_gflops', 0):.3g}")
                if c:
                    figure += (f"; again x{c['repeats']}: gain {c['gain']:.2f} -> "
                               f"{'proposed' if c['confirmed'] else 'not proposed'}")
                elif w["params"] == t.get("params"):
                    figure += " (the table's choice holds)"
            elif step == "bench:gemm":
                figure = f"{r['result']['gemm_1024']['gflops']:.1f} GFLOP/s at 1024^3"
            elif step.startswith("bench:generator"):
                figure = f"{r['result']['ms_median']:.1f} ms"
            elif step == "bench:frame_n64":
                figure = "; ".join(f"N = {s['n']}: {s['device']['median_ms']:.1f} ms" for s in r["result"]["sizes"])
            else:
                figure = f"{r['wall_s']} s"
            lines.append(f"| {name} | {step} | {r.get('status')} | {figure} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=str(REPO / "build"), help="build tree (default: build)")
    ap.add_argument("--out", required=True, help="folder for report.json, report.md, the proposal and logs")
    ap.add_argument("--devices", help="comma-separated P:D specs (default: every device ngi lists)")
    ap.add_argument("--tests", default="quick",
                    help="quick ([op_harness]), full (every case), none, or a Catch2 filter such as '[gemm]'")
    ap.add_argument("--bench", default="quick",
                    help=f"quick ({','.join(QUICK_BENCH)}), full (every benchmark), none, or a comma-separated list")
    ap.add_argument("--tune-max", type=int, default=8, help="knob sets the tuner tries (0: no tuning)")
    ap.add_argument("--tune-shapes", default=QUICK_TUNE_SHAPES, help="the tuner's GEMM shapes, \"M,N,K;...\"")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per benchmark (median)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds one step may take before it is killed and "
                    "reported as failed (a hung driver; llvmpipe runs the 1024^3 GEMM benchmark for many minutes)")
    args = ap.parse_args(argv)
    if args.repeats < 1 or args.tune_max < 0 or not args.timeout > 0:
        ap.error("--repeats must be >= 1, --tune-max >= 0 and --timeout > 0")

    build, out = Path(args.build).resolve(), Path(args.out).resolve()
    for exe in ("ngi", "tests/ngi_tests", "perf/ngi_bench"):
        if not (build / exe).is_file():
            ap.error(f"{build / exe} is missing: build first (bash tools/build.sh)")
    runs = benchmarks(build, args.repeats)
    bench_names = {"none": [], "quick": QUICK_BENCH, "full": list(runs)}.get(args.bench, args.bench.split(","))
    unknown = sorted(set(bench_names) - set(runs))
    if unknown:
        ap.error(f"unknown benchmark(s) {unknown}; choose from {sorted(runs)}")
    tests = None if args.tests == "none" else TEST_FILTERS.get(args.tests, args.tests)

    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", str(out / "cache" / "pocl"))
    env.setdefault("NGI_CACHE_DIR", str(out / "cache" / "ngi"))
    devices = list_devices(build, env)
    if args.devices:
        wanted = args.devices.split(",")
        missing = sorted(set(wanted) - {d["spec"] for d in devices})
        if missing:
            raise SystemExit(f"gpu_check: no device {missing}; ngi lists {[d['spec'] for d in devices]}")
        devices = [d for d in devices if d["spec"] in wanted]
    if not devices:
        raise SystemExit("gpu_check: no OpenCL device (install an ICD; rusticl needs RUSTICL_ENABLE=llvmpipe)")

    out.mkdir(parents=True, exist_ok=True)
    logs = out / "logs"
    logs.mkdir(exist_ok=True)
    commit = git_commit()
    report_path = out / "report.json"
    report = json.loads(report_path.read_text()) if report_path.is_file() else {"commit": commit, "devices": {}}
    if report.get("commit") != commit:
        raise SystemExit(f"gpu_check: {report_path} was written at commit {report.get('commit')}, this is {commit}: "
                         "use another --out (results of two builds are not mixed)")
    proposal = out / "gemm_tuning_proposed.json"
    if not proposal.is_file():
        shutil.copyfile(REPO / "kernels" / "gemm_tuning.json", proposal)

    todo = []
    for d in devices:
        info = {k: v for k, v in d.items() if k != "self_check"}
        entry = report["devices"].setdefault(d["spec"], {"info": info, "steps": {}})
        if entry["info"].get("name") != info["name"]:
            raise SystemExit(f"gpu_check: device {d['spec']} is {info['name']} now, {entry['info'].get('name')} "
                             f"in {report_path}: use another --out")
        entry["self_check"] = d["self_check"]
        for name, what in device_steps(d["self_check"], tests, args.tune_max, bench_names):
            if entry["steps"].get(name, {}).get("status") != "ok":
                todo.append((d["spec"], name, what))
    write_atomic(report_path, report)
    print(f"gpu_check: {len(devices)} device(s), {len(todo)} step(s) to run -> {out}", file=sys.stderr)
    with tqdm(todo, unit="step", file=sys.stderr, mininterval=1) as bar:
        for spec, name, what in bar:
            bar.set_description(f"{spec} {name}")
            t0 = time.monotonic()
            if isinstance(what, dict):
                result = dict(what)
            elif what == "tests":
                result = run_tests(build, spec, tests, logs, env, args.timeout)
            elif what == "tune":
                result = run_tune(build, spec, args, proposal, env)
            else:
                result = run_bench(runs[name.split(":", 1)[1]], spec, env, args.timeout)
            result["wall_s"] = round(time.monotonic() - t0, 1)
            report["devices"][spec]["steps"][name] = result
            write_atomic(report_path, report)
    (out / "report.md").write_text(summary_markdown(report))
    print(summary_markdown(report))
    failed = [(s, n) for s, d in report["devices"].items() for n, r in d["steps"].items() if r.get("status") != "ok"]
    failed += [(s, "self_check") for s, d in report["devices"].items() if not d["self_check"].get("ok")]
    if failed:
        print(f"gpu_check: {len(failed)} failed: {failed}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

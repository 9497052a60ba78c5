"""tools/gpu_check.sh (perf/gpu_check.py): the rule that a device failing the GEMM self-check is never timed, the
resume rule, and one real run on PoCL's CPU device (the op harness's tiny case, a two-set tuner sweep, the whole-frame
benchmark) whose report and tuning proposal are read back. Needs NGI_BUILD (the build tree) and PYTHONPATH with
<build>/python (tests/CMakeLists.txt sets both)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import gpu_check  # pytest puts this file's folder (perf/) on the path

BUILD = Path(os.environ.get("NGI_BUILD", Path(__file__).resolve().parent.parent / "build"))


def test_failed_self_check_means_no_timing():
    failed = {"ok": False, "error": "no GEMM variant passed: 6,16,1,4,1,4,1: wrong result"}
    steps = dict(gpu_check.device_steps(failed, "[op_harness]", 4, ["gemm", "frame_n64"]))
    assert steps["tests"] == "tests" and steps["tune"] == "tune"  # still checked and tuned: the fix may be found
    for name in ("bench:gemm", "bench:frame_n64"):
        assert steps[name]["status"] == "failed"
        assert steps[name]["error"].startswith("not timed: the GEMM self-check failed")
        assert "wrong result" in steps[name]["error"]
    ok = dict(gpu_check.device_steps({"ok": True}, None, 0, ["gemm"]))
    assert ok == {"bench:gemm": "bench"}


def test_a_step_past_its_time_is_killed_and_failed():
    proc = gpu_check.run_step(["sleep", "30"], dict(os.environ), 0.5)
    assert proc.returncode == -9 and "timed out after 0.5 s" in proc.stderr


def run_check(out, *extra):
    cmd = [sys.executable, str(Path(gpu_check.__file__)), "--build", str(BUILD), "--out", str(out), "--devices",
           pocl_spec(), "--tests", "[op_harness][oclgrind]", "--tune-max", "2", "--bench", "frame_n64",
           "--repeats", "1", *extra]
    return subprocess.run(cmd, capture_output=True, text=True)


def pocl_spec():
    devices = json.loads(subprocess.run([str(BUILD / "ngi"), "devices", "--json"], capture_output=True,
                                        text=True).stdout)
    return next(d["spec"] for d in devices if d["platform"] == "Portable Computing Language")


def test_real_run_on_pocl_and_resume(tmp_path):
    out = tmp_path / "check"
    proc = run_check(out)
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads((out / "report.json").read_text())
    (dev,) = report["devices"].values()
    assert dev["self_check"]["ok"] and dev["info"]["type"] == "cpu"
    steps = dev["steps"]
    assert steps["tests"]["status"] == "ok" and steps["tests"]["cases"] >= 2 and steps["tests"]["failures"] == 0
    tune = steps["tune"]
    assert tune["status"] == "ok" and tune["candidates"] == 2 and tune["winner"]["geomean_gflops"] > 0
    # The proposal is the repository's database, plus this device's exact entry only when a winner other than the
    # table's choice kept its gain in the longer run beside it.
    proposal = json.loads((out / "gemm_tuning_proposed.json").read_text())
    repo_db = json.loads((Path(gpu_check.REPO) / "kernels" / "gemm_tuning.json").read_text())
    confirmation = tune["confirmation"]
    if tune["winner"]["params"] == tune["table_choice"]["params"]:
        assert confirmation is None and tune["entry"] is None and proposal == repo_db
    elif confirmation["confirmed"]:
        assert confirmation["gain"] >= gpu_check.CONFIRM_GAIN
        assert tune["entry"] in proposal["entries"] and tune["entry"]["params"] == tune["winner"]["params"]
        assert len(proposal["entries"]) in (len(repo_db["entries"]), len(repo_db["entries"]) + 1)
    else:
        assert confirmation["gain"] < gpu_check.CONFIRM_GAIN and tune["entry"] is None and proposal == repo_db
    frame = steps["bench:frame_n64"]
    assert frame["status"] == "ok" and frame["result"]["sizes"][0]["device"]["median_ms"] > 0
    assert "| tune | ok |" in (out / "report.md").read_text()

    # A rerun keeps what passed; a step that failed is redone.
    steps["tune"] = {"status": "failed", "error": "interrupted"}
    (out / "report.json").write_text(json.dumps(report))
    proc = run_check(out)
    assert proc.returncode == 0, proc.stderr[-3000:]
    again = json.loads((out / "report.json").read_text())["devices"][dev["info"]["spec"]]["steps"]
    assert again["tests"] == steps["tests"] and again["bench:frame_n64"] == frame  # kept as they were
    assert again["tune"]["status"] == "ok"

    # Another commit's report is not mixed with this one.
    report["commit"] = "0" * 40
    (out / "report.json").write_text(json.dumps(report))
    proc = run_check(out)
    assert proc.returncode != 0 and "was written at commit" in proc.stderr


def test_bad_arguments_are_refused(tmp_path):
    proc = run_check(tmp_path / "x", "--bench", "no_such_bench")
    assert proc.returncode == 2 and "unknown benchmark" in proc.stderr
    cmd = [sys.executable, str(Path(gpu_check.__file__)), "--build", str(BUILD), "--out", str(tmp_path / "y"),
           "--devices", "9:9", "--tests", "none", "--tune-max", "0", "--bench", "none"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode != 0 and "no device ['9:9']" in proc.stderr


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q", "-p", "no:cacheprovider"]))

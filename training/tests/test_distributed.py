#!/usr/bin/python3
"""Distributed training and evaluation with torch.distributed (ctest: training_distributed, ~25 s on 2 cores).

    PYTHONPATH=training:build/python /usr/bin/python3 training/tests/test_distributed.py --ngi build/ngi \
        --work build/training_distributed

Renders a tiny dataset with `ngi dataset` (N = 32: 3 train frames, 3 test frames; 3 train frames make the global
batches of 2 straddle epoch boundaries), then, with 2 gloo ranks on this machine started by torchrun
(ngi_train.torchrun, static rendezvous on 127.0.0.1, GLOO_SOCKET_IFNAME=lo: loopback only):

(a) one optimizer step of 2 ranks x 1 image equals one step of 1 process x accumulate 2: the G and D state_dicts
    (weights and BatchNorm running statistics) and both Adam states (whose moments hold the averaged gradients
    themselves, so a wrong scale or a wrong image would show; the first Adam step alone is nearly scale-free),
    the logged losses and the held-out eval line (scored by both ranks, merged in frame order). Dropout off
    (ranks draw their own masks, a single process draws both from one stream). Tolerances below (MOMENT_RTOL ...);
(c) during (a) the rank-1 process wrote nothing into the run folder nor into the merge cache (a Python audit hook
    in each rank records every write-mode open, rename, mkdir, remove under those folders; rank 0's record must
    show its own writes, so the hook demonstrably works), while rank 0 prepared the cache the run started without;
(b) a 2-rank run stopped by SIGTERM (to torchrun, which forwards it: the ranks agree on the step, save, exit) is
    refused when resumed by 1 process with another effective batch, then resumed by 1 process x accumulate 2 to
    k + 4 steps: same number of samples (2 per step) and, within the tolerances, the same Adam states, buffers and
    losses (first k steps from 2 ranks) as one uninterrupted 1 x 2 process; its checkpoint exports (export.py);
(d) one 2-rank step with dropout on runs and the two ranks' RNG streams (dropout masks) differ;
(e) evaluate.py (`ngi lightmap` per frame) on 2 ranks writes the same summary.json and per_frame.json, byte for
    byte, as on 1 process.
"""

import argparse
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
# The commands under test (modules of the package ngi_train; torchrun starts them with --module).
TRAIN_MODULE, EXPORT_MODULE = "ngi_train.generator.train", "ngi_train.generator.export"
EVALUATE_MODULE = "ngi_train.generator.evaluate"

# ---------------------------------------------------------------------------------------------------------------
# Worker mode: `test_distributed.py --audit-worker AUDIT_DIR WATCHED MODULE ARGS...` is what torchrun starts per
# rank: it records the process's file writes under the WATCHED folders (os.pathsep-separated), then runs MODULE
# (as python3 -m MODULE would).
# ---------------------------------------------------------------------------------------------------------------

WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
PATH_EVENTS = {"os.rename": (0, 1), "os.mkdir": (0,), "os.remove": (0,), "os.rmdir": (0,), "os.truncate": (0,),
               "os.utime": (0,), "os.chmod": (0,), "os.link": (0, 1), "os.symlink": (0, 1), "shutil.rmtree": (0,),
               "shutil.copyfile": (1,), "shutil.move": (1,)}


def audit_worker(argv):
    audit_dir, watched, module, *args = argv
    watched = [os.path.realpath(w) for w in watched.split(os.pathsep)]
    writes = []

    def inside(p):
        if not isinstance(p, (str, bytes, os.PathLike)):
            return None  # file descriptors (os.fdopen): their os.open was recorded
        p = os.path.realpath(os.fsdecode(p))
        return p if any(p == w or p.startswith(w + os.sep) for w in watched) else None

    def hook(event, a):
        if event == "open":
            path, mode, flags = a
            if (mode and any(c in mode for c in "wax+")) or (flags or 0) & WRITE_FLAGS:
                p = inside(path)
                if p:
                    writes.append([event, p])
        elif event in PATH_EVENTS:
            for i in PATH_EVENTS[event]:
                p = inside(a[i]) if i < len(a) else None
                if p:
                    writes.append([event, p])

    def report():
        Path(audit_dir, f"rank{os.environ.get('RANK', '0')}.json").write_text(json.dumps(writes))

    import atexit
    import runpy
    atexit.register(report)
    sys.addaudithook(hook)
    sys.argv = [module, *args]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "--audit-worker":
    audit_worker(sys.argv[2:])
    sys.exit(0)

try:
    import numpy  # noqa: F401  (the training modules need it)
    import torch
    import torch.distributed
except ImportError as e:  # pragma: no cover
    # Not a skip: tools/install-deps.sh installs numpy and torch, so their absence is a broken machine.
    print(f"training_distributed: FAILED: cannot import numpy/torch ({e}); run tools/install-deps.sh")
    sys.exit(1)

from ngi_train import distributed, ngi_paths  # noqa: E402
from ngi_train.generator import data  # noqa: E402
from ngi_train.ngi_paths import run  # noqa: E402

# Tolerances of 2 ranks x 1 image against 1 process x accumulate 2. Exact equality is not to be had on every
# machine: the ranks' losses and gradients are averaged by an allreduce (a / 2 + b / 2 in float32) where the single
# process accumulates, and torch's CPU kernels may group sums differently per process; on the 2-core AMD EPYC kind
# of 2026-11 the two differ at float32 rounding (measured: logged losses 3.6e-8 relative, Adam moments 1.7e-6
# relative, BN running statistics 6e-8; where a rounding-level gradient meets Adam's first step, which normalizes
# it to +-lr, a weight moved 1.1e-5 = 0.06 lr). What the test exists to catch is far above that: a wrong image,
# a sum instead of a mean or a missing allreduce changes the moments by 1e-3 relative and more (a factor 2 for the
# scale). So: Adam moments (which hold the averaged gradients themselves) to MOMENT_RTOL relative to each tensor's
# scale, BN buffers to BUFFER_ATOL, logged numbers to LOG_RTOL; weights are reported, not asserted (after one
# Adam step they are a function of the moments; their difference is the normalization's amplified rounding).
MOMENT_RTOL = 1e-4
BUFFER_ATOL = 1e-6
LOG_RTOL = 1e-6

DATASET = {
    "comment": "training_distributed: 3 train frames + 3 test frames at N = 32",
    "n": 32, "feature_spp": 1, "reference_spp": 4, "max_bounces": 2, "frames_per_scene": 3,
    "keyframe_interval": 25,
    "train": [{"family": "room", "seeds": [1], "time": 11}],
    "test": [{"family": "bleed", "seeds": [101], "frames": 3}],
}
TRAIN = {"layout": "surround", "ngf": 4, "num_downs": 5, "ndf": 8, "d_layers": 3, "dropout": False, "steps": 1,
         "checkpoint_every": 1000, "keep_every": 0, "seed": 7, "threads": 1, "eval_every": 1000, "eval_frames": 3}


def check(cond, message):
    if not cond:
        raise SystemExit(f"FAILED: {message}")
    print(f"ok: {message}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def torchrun_cmd(nproc, module, args, audit=None):
    """torchrun (ngi_train.torchrun) of `module` with nproc ranks on this machine, static rendezvous on the
    loopback."""
    cmd = [sys.executable, "-m", "ngi_train.torchrun", "--nnodes", 1, "--nproc_per_node", nproc, "--master_addr",
           "127.0.0.1", "--master_port", free_port(), "--monitor_interval", 0.1, "--max_restarts", 0]
    if audit:
        audit_dir, watched = audit
        return [str(c) for c in cmd + [HERE / "test_distributed.py", "--audit-worker", audit_dir,
                                       os.pathsep.join(map(str, watched)), module, *args]]
    return [str(c) for c in cmd + ["--module", module, *args]]


def dist_env():
    env = ngi_paths.ngi_env()
    env["GLOO_SOCKET_IFNAME"] = "lo"
    return env


def torchrun(nproc, module, args, audit=None):
    cmd = torchrun_cmd(nproc, module, args, audit)
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=dist_env())
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
    return proc, time.monotonic() - t0


def one_process(args):
    """The training command in one process (no torchrun)."""
    return [sys.executable, "-m", TRAIN_MODULE, *args]


def train_args(cfg_path, dataset, run_dir, ngi, *extra):
    return ["--config", cfg_path, "--dataset", dataset, "--run", run_dir, "--ngi", ngi, *map(str, extra)]


def read_log(run_dir, seconds=False):
    lines = [json.loads(s) for s in (Path(run_dir) / "log.jsonl").read_text().splitlines() if s.strip()]
    return [e if seconds else {k: v for k, v in e.items() if k != "seconds"} for e in lines]


def same_log(a, b):
    """Two runs' log lines: the same keys and integers, floats within LOG_RTOL relative."""
    def close(x, y):
        if isinstance(x, dict) and isinstance(y, dict):
            return x.keys() == y.keys() and all(close(x[k], y[k]) for k in x)
        if isinstance(x, float) or isinstance(y, float):
            return abs(x - y) <= LOG_RTOL * max(abs(x), abs(y))
        return x == y
    return len(a) == len(b) and all(close(x, y) for x, y in zip(a, b))


def equivalent(d):
    weights, buffers, moments = d
    return moments <= MOMENT_RTOL and buffers <= BUFFER_ATOL


def describe(d):
    return f"Adam moments {d[2]:.2g} relative (<= {MOMENT_RTOL}), BN buffers {d[1]:.2g} (<= {BUFFER_ATOL}), " \
           f"weights {d[0]:.2g}"


def differences(a, b):
    """(weights, buffers, moments) of two checkpoints: max |a - b| over G's and D's parameters, max |a - b| over
    their buffers (BatchNorm running statistics), and max over both Adam states' moment tensors of
    |a - b| / max |b| (relative to each tensor's scale)."""
    weights = buffers = moments = 0.0
    for net in ("G", "D"):
        sa, sb = a["model"][net], b["model"][net]
        assert sa.keys() == sb.keys()
        for k in sa:
            d = float((sa[k].double() - sb[k].double()).abs().max()) if sa[k].numel() else 0.0
            if k.endswith(("running_mean", "running_var", "num_batches_tracked")):
                buffers = max(buffers, d)
            else:
                weights = max(weights, d)
    for opt in ("opt_G", "opt_D"):
        sa, sb = a["model"][opt]["state"], b["model"][opt]["state"]
        assert sa.keys() == sb.keys()
        for i in sa:
            for k in ("exp_avg", "exp_avg_sq"):
                scale = float(sb[i][k].double().abs().max())
                d = float((sa[i][k].double() - sb[i][k].double()).abs().max())
                moments = max(moments, d / scale if scale > 0 else d)
    return weights, buffers, moments


def load_ckpt(run_dir):
    return torch.load(Path(run_dir) / "checkpoints" / "latest.pt")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN or build*/ngi)")
    ap.add_argument("--work", default="/tmp/ngi_training_distributed", help="scratch folder (emptied first)")
    args = ap.parse_args()
    t_start = time.monotonic()
    check(torch.distributed.is_available() and torch.distributed.is_gloo_available(), "torch.distributed with gloo")
    ngi = ngi_paths.find_ngi(args.ngi)
    work = Path(args.work).resolve()
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)

    (work / "dataset.json").write_text(json.dumps(DATASET))
    dataset = work / "data"
    run([ngi, "dataset", "--config", work / "dataset.json", "--out", dataset])
    check(len(data.list_frames(dataset, "train")) == 3 and len(data.list_frames(dataset, "test")) == 3,
          "ngi dataset rendered 3 + 3 frames")
    cfg_path = work / "train.json"
    cfg_path.write_text(json.dumps(TRAIN))
    cache = data.default_cache_dir(dataset, "surround")

    # (a) + (c): 2 ranks x 1 image (audited; the merge cache does not exist yet) against 1 process x accumulate 2.
    audit = work / "audit"
    audit.mkdir()
    r2 = work / "a_2x1"
    _, secs2 = torchrun(2, TRAIN_MODULE, train_args(cfg_path, dataset, r2, ngi), audit=(audit, [r2, dataset]))
    r1 = work / "a_1x2"
    _, secs1 = run(one_process(train_args(cfg_path, dataset, r1, ngi, "--accumulate", 2)))
    s2, s1 = load_ckpt(r2), load_ckpt(r1)
    diff_a = differences(s1, s2)
    check(s1["step"] == s2["step"] == 1 and s1["samples"] == s2["samples"] == 2
          and s2["world_size"] == 2 and s1["world_size"] == 1 and s1["effective_batch"] == s2["effective_batch"] == 2,
          f"one step: 2 ranks x 1 ({secs2:.1f} s) and 1 x accumulate 2 ({secs1:.1f} s), 2 samples each")
    check(equivalent(diff_a), f"2 ranks x 1 == 1 x accumulate 2: {describe(diff_a)}")
    log2, log1 = read_log(r2), read_log(r1)
    check(same_log(log1, log2) and len(log2) == 2 and log2[0]["batch"] == 2 and log2[1]["eval"]["frames"] == 3,
          "same log: losses averaged over the effective batch, held-out eval split over the ranks")
    run_info = json.loads((r2 / "run.json").read_text())
    check(run_info["world_size"] == 2 and run_info["effective_batch"] == 2 and run_info["backend"] == "gloo",
          "run.json: world_size 2, effective_batch 2, gloo")
    rank0 = json.loads((audit / "rank0.json").read_text())
    rank1 = json.loads((audit / "rank1.json").read_text())
    in_run = lambda w: [e for e in w if Path(e[1]).is_relative_to(r2)]  # noqa: E731
    in_cache = lambda w: [e for e in w if Path(e[1]).is_relative_to(cache)]  # noqa: E731
    check(len(in_run(rank0)) > 0 and len(in_cache(rank0)) > 0,
          f"the audit hook sees rank 0's writes ({len(in_run(rank0))} in the run folder, "
          f"{len(in_cache(rank0))} in the merge cache it prepared)")
    check(rank1 == [], f"rank 1 wrote nothing into the run folder or the dataset / merge cache: {rank1[:3]}")

    # (b) 2 ranks stopped by SIGTERM, resumed by 1 process (effective batch kept: accumulate 2).
    rb = work / "b_resumed"
    cmd = torchrun_cmd(2, TRAIN_MODULE, train_args(cfg_path, dataset, rb, ngi, "--steps", 100000))
    proc = subprocess.Popen(cmd, env=dist_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if (rb / "log.jsonl").is_file() and (rb / "log.jsonl").read_text().count("\n") >= 3:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    stopped = load_ckpt(rb)
    k = stopped["step"]
    check(3 <= k < 100000 and stopped["samples"] == 2 * k and len(read_log(rb)) == k and "stopped at step" in err,
          f"SIGTERM to torchrun: both ranks stopped after step {k}, checkpoint with {2 * k} samples, log of {k} steps")
    check(not torch.equal(stopped["rng_ranks"][0]["cpu"], stopped["rng_ranks"][1]["cpu"]),
          "the checkpoint holds both ranks' RNG states, and they differ")
    target = k + 4
    refused = subprocess.run(one_process(train_args(cfg_path, dataset, rb, ngi, "--steps", target)),
                             capture_output=True, text=True, env=ngi_paths.ngi_env())
    check(refused.returncode != 0 and "effective batch of 2" in refused.stderr and load_ckpt(rb)["step"] == k,
          "resuming with 1 process x accumulate 1 (effective batch 1) is refused: "
          + refused.stderr.strip().splitlines()[-1][:120] + "...")
    run(one_process(train_args(cfg_path, dataset, rb, ngi, "--steps", target, "--accumulate", 2)))
    rc = work / "b_uninterrupted_1x2"
    run(one_process(train_args(cfg_path, dataset, rc, ngi, "--steps", target, "--accumulate", 2)))
    sb, sc = load_ckpt(rb), load_ckpt(rc)
    diff_b = differences(sb, sc)
    check(sb["step"] == sc["step"] == target and sb["samples"] == sc["samples"] == 2 * target
          and sb["world_size"] == 1 and [e["samples"] for e in read_log(rb) if "eval" not in e]
          == [2 * s for s in range(1, target + 1)],
          f"resumed with 1 process to step {target}: {sb['samples']} samples, as an uninterrupted run")
    check(equivalent(diff_b) and same_log(read_log(rb), read_log(rc)),
          f"2 ranks to step {k} + 1 x accumulate 2 to {target} == 1 x accumulate 2 throughout: {describe(diff_b)}, "
          f"same losses")
    model = work / "b.safetensors"
    run([sys.executable, "-m", EXPORT_MODULE, "--run", rb, "--out", model])
    meta = json.loads(run([sys.executable, "-c", "import sys, json, ngi.model_file as m; "
                           "print(json.dumps(m.read_config(sys.argv[1])['training']))", model])[0].stdout)
    check(meta["steps"] == target and meta["samples"] == 2 * target and meta["effective_batch"] == 2,
          f"the resumed checkpoint exports: steps {meta['steps']}, samples {meta['samples']}, "
          f"epochs {meta['epochs']:.2f}")

    # (d) dropout on: two ranks, their own masks.
    cfg_drop = work / "train_dropout.json"
    # num_downs 6: one dropout site (networks.dropout_site_count); the 64 x 128 global view halves 6 times.
    cfg_drop.write_text(json.dumps(dict(TRAIN, dropout=True, num_downs=6, eval_every=0)))
    rd = work / "d_dropout"
    torchrun(2, TRAIN_MODULE, train_args(cfg_drop, dataset, rd, ngi))
    sd = load_ckpt(rd)
    torch.manual_seed(distributed.rank_seed(TRAIN["seed"], 1, 0))
    check(not torch.equal(sd["rng_ranks"][0]["cpu"], sd["rng_ranks"][1]["cpu"])
          and not torch.equal(sd["rng_ranks"][1]["cpu"], torch.get_rng_state()) and sd["samples"] == 2,
          "dropout on, 2 ranks: a step runs; rank 1 drew its masks from its own stream (seeded from the run seed "
          "and the rank), not rank 0's")

    # (e) evaluate.py on 2 ranks == on 1 process.
    e1, e2 = work / "e_eval_1", work / "e_eval_2"
    run([sys.executable, "-m", EVALUATE_MODULE, "--model", model, "--dataset", dataset, "--split", "test",
         "--out", e1, "--ngi", ngi])
    _, secs = torchrun(2, EVALUATE_MODULE, ["--model", model, "--dataset", dataset, "--split", "test",
                                                 "--out", e2, "--ngi", ngi])
    same = all((e1 / f).read_bytes() == (e2 / f).read_bytes() for f in ("summary.json", "per_frame.json"))
    frames = json.loads((e2 / "summary.json").read_text())["frames"]
    check(same and frames == 3 and len(json.loads((e2 / "per_frame.json").read_text())) == 3,
          f"evaluate.py on 2 ranks ({secs:.1f} s): summary.json and per_frame.json byte-identical to 1 process "
          f"({frames} frames)")

    print(f"training_distributed: all checks passed in {time.monotonic() - t_start:.1f} s "
          f"(2 x 1 vs 1 x 2: {describe(diff_a)}; resumed across world sizes: {describe(diff_b)})")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Implicit-convolution knob sets against each other on one generator, per node, interleaved in one run.

Each variant is a knob set for $NGI_CONV_GEMM ("MR,VW,NV,KU,L0,L1[,UNROLL]", kernels/gemm.cl) or "base" (what the
tuning database gives this device), as "[label=]knobs[@bench]": "@bench" runs another ngi_bench build (an A/B of
two builds: "before=base@/path/to/old/ngi_bench"), "label=" names the variant. Every round runs each variant once,
in the same order, as a fresh `ngi_bench generator` process (its warm-up + --calls timed calls: a wall median, and
one profiled run for per-node device times); medians over --rounds. Interleaving rounds, not variants in blocks, keeps this VM's drift (the same
binary 7.4-9.1 ms minutes apart) out of the comparison.

Why it exists: a tuning entry's conv_params are chosen from whole-network times on a noisy machine; this says which
layers a knob set wins or loses, the first thing a user tuning a GPU entry wants to know.

Usage: /usr/bin/python3 perf/conv_knob_ab.py --model models/ladder/gi_surround_n64_ngf16.safetensors --width 256
           --height 128 --variants "base;6,16,1,4,1,16,1" [--rounds 6] [--calls 20] [--device pocl] [--out F.json]
Set POCL_CACHE_DIR / NGI_CACHE_DIR (the subprocesses inherit them).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import bench_record
from tqdm import tqdm


def parse_variant(text, default_bench):
    """[label=]knobs[@bench]; the label names the variant in the output (default: its knobs)."""
    spec, _, bench = text.partition("@")
    label, _, knobs = spec.rpartition("=")
    return {"name": label or knobs, "knobs": knobs, "bench": bench or default_bench}


def run_once(variant, args):
    env = dict(os.environ)
    env.pop("NGI_CONV_GEMM", None)
    if variant["knobs"] != "base":
        env["NGI_CONV_GEMM"] = variant["knobs"]
    cmd = [variant["bench"], "generator", "--model", args.model, "--width", str(args.width), "--height",
           str(args.height), "--repeats", str(args.calls)]
    if args.device:
        cmd += ["--device", args.device]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=bench_record.REPO)
    if p.returncode != 0:
        raise SystemExit(f"conv_knob_ab: {variant['name']}: ngi_bench failed ({p.returncode}): {p.stderr.strip()[-400:]}")
    return json.loads(p.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, required=True)
    ap.add_argument("--variants", required=True, help='";"-separated [label=]knobs[@bench]; knobs: a knob set or "base"')
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--calls", type=int, default=20)
    ap.add_argument("--device", default="")
    ap.add_argument("--bench", default=str(bench_record.REPO / "build/perf/ngi_bench"))
    ap.add_argument("--out")
    args = ap.parse_args()
    variants = [parse_variant(v, args.bench) for v in args.variants.split(";") if v]
    if not variants:
        raise SystemExit("conv_knob_ab: --variants is empty")

    runs = {v["name"]: [] for v in variants}
    load_before = bench_record.load()
    t0 = time.time()
    # tqdm: progress with an ETA; finished rounds stay in `runs` if interrupted (Ctrl-C prints what was measured)
    try:
        for _ in tqdm(range(args.rounds), desc="rounds", file=sys.stderr):
            for v in variants:
                runs[v["name"]].append(run_once(v, args))
    except KeyboardInterrupt:
        bench_record.log("conv_knob_ab: interrupted; reporting the finished rounds")

    result = {"what": "ngi_bench generator per variant, interleaved rounds; medians over rounds",
              "model": bench_record.relative(args.model), "width": args.width, "height": args.height,
              "rounds": min(len(r) for r in runs.values()), "calls_per_run": args.calls,
              "commit": bench_record.git_head(), "load_before": load_before, "load_after": bench_record.load(),
              "seconds": round(time.time() - t0, 1), "variants": {}}
    first = next(iter(runs.values()))
    if not first:
        raise SystemExit("conv_knob_ab: no round finished")
    nodes = [o["name"] for o in first[0]["per_op"]]
    for v in variants:
        rs = runs[v["name"]]
        if not rs:
            continue
        result["variants"][v["name"]] = {
            "bench": bench_record.relative(v["bench"]),
            "conv_knobs": v["knobs"],
            "device": rs[0]["device"],
            "wall_ms_median": statistics.median(r["ms_median"] for r in rs),
            "wall_ms_all": [r["ms_median"] for r in rs],
            "device_ms_median": statistics.median(r["device_ms_total"] for r in rs),
            "node_ms_median": {n: statistics.median(r["per_op"][i]["ms"] for r in rs) for i, n in enumerate(nodes)},
        }
    names = list(result["variants"])
    lines = ["| node | " + " | ".join(names) + " |", "|---|" + "---|" * len(names),
             "| wall | " + " | ".join(f"{result['variants'][n]['wall_ms_median']:.2f}" for n in names) + " |"]
    for node in nodes:
        if node.endswith(".bn"):
            continue
        lines.append(f"| {node} | " + " | ".join(f"{result['variants'][n]['node_ms_median'][node]:.3f}" for n in names) + " |")
    bench_record.log("\n".join(lines))
    bench_record.emit(result, args.out)


if __name__ == "__main__":
    main()

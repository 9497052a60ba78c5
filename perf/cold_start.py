#!/usr/bin/env python3
"""A new process's first lightmap, cold and after `ngi warmup` (issue 48's cold start; PERFORMANCE.md "Process costs
and cold start"): for each model, with empty program caches of its own (NGI_CACHE_DIR, POCL_CACHE_DIR), one `ngi
lightmap --timings` process (cold: every program built), then `ngi warmup --model M --n N`, then --repeats more
lightmap processes (warm: every program loaded). Records each phase the CLI times (open_device, load_model,
pipeline, ...) and the process's wall time; medians over the warm processes.

    build/ngi render --scene room:seed=204 --n 64 --out /tmp/frame204
    /usr/bin/python3 perf/cold_start.py --frame /tmp/frame204 --out perf/cold_start_pocl_2core.json

The frame's reference is scored by `ngi lightmap` too (its metric kernels are not part of an application's frame and
`warmup` does not build them): the `first_lightmap_ms` figure is open_device + load_model + pipeline, what an
application pays before its first lightmap.
"""
import argparse
import os
import re
import statistics
import subprocess
import tempfile
import time

from bench_record import emit, git_head, load, log, relative

TIMINGS = re.compile(r"^timings\s+(.*)$", re.M)
PHASE = re.compile(r"(\w+) ([\d.]+) ms")


def run(cmd, env):
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = (time.perf_counter() - t0) * 1e3
    if proc.returncode != 0:
        raise SystemExit(f"cold_start: {' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return proc, wall


def lightmap(ngi, frame, model, out, env):
    proc, wall = run([ngi, "lightmap", "--frame", frame, "--model", model, "--out", out, "--timings"], env)
    m = TIMINGS.search(proc.stderr)
    if not m:
        raise SystemExit(f"cold_start: no timings line from ngi lightmap:\n{proc.stderr[-2000:]}")
    phases = {k: float(v) for k, v in PHASE.findall(m.group(1))}
    phases["first_lightmap"] = phases["open_device"] + phases["load_model"] + phases["pipeline"]
    phases["process_wall"] = wall
    return phases


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frame", required=True, help="a frame folder (ngi render)")
    p.add_argument("--models", default="ssgi_surround,gi_surround_n64_ngf16")
    p.add_argument("--n", type=int, default=64, help="the frame's face size (for ngi warmup)")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--ngi", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "ngi"))
    p.add_argument("--out", help="also write the JSON here")
    args = p.parse_args()
    result = {"what": "new process -> first lightmap, cold (empty program caches) and after ngi warmup",
              "git_head": git_head(), "load_average_start": load(), "frame": relative(args.frame),
              "device": os.environ.get("NGI_DEVICE", "default"), "repeats": args.repeats, "models": {}}
    for model in args.models.split(","):
        with tempfile.TemporaryDirectory(prefix="ngi-cold-") as tmp:
            env = dict(os.environ, NGI_CACHE_DIR=os.path.join(tmp, "ngi"), POCL_CACHE_DIR=os.path.join(tmp, "pocl"))
            out = os.path.join(tmp, "out")
            log(f"{model}: cold process (empty caches) ...")
            cold = lightmap(args.ngi, args.frame, model, out, env)
            # The cold run filled the caches with what lightmap needed: empty them again so that the warm-up alone
            # fills them, as at install time.
            for sub in ("ngi", "pocl"):
                subprocess.run(["rm", "-rf", os.path.join(tmp, sub)], check=True)
            log(f"{model}: ngi warmup ...")
            _, warmup_ms = run([args.ngi, "warmup", "--model", model, "--n", str(args.n)], env)
            warm = []
            for i in range(args.repeats):
                warm.append(lightmap(args.ngi, args.frame, model, out, env))
                log(f"{model}: warm process {i + 1}/{args.repeats}: first lightmap {warm[-1]['first_lightmap']:.1f} ms")
            med = {k: statistics.median(w[k] for w in warm) for k in warm[0]}
            result["models"][model] = {"cold": cold, "warmup_process_ms": warmup_ms, "warm_median": med,
                                       "warm_runs": warm}
            log(f"{model}: cold first lightmap {cold['first_lightmap']:.0f} ms, after warmup "
                f"{med['first_lightmap']:.1f} ms (median of {args.repeats})")
    result["load_average_end"] = load()
    emit(result, args.out)


if __name__ == "__main__":
    main()

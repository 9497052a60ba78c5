"""Kernel and model microbenchmarks on every OpenCL device present, into one JSON (and a Markdown table).

For each device ngi sees (ngi.devices(); rusticl needs RUSTICL_ENABLE=llvmpipe in the environment) it runs the
benchmarks of build/perf with --device P:D, in one process each (a device's compiled programs are cached on disk,
so the first run of a benchmark pays the compilation and the timed runs do not):

    gemm        ngi_bench gemm: GEMM GFLOP/s at 1024^3 and at the thesis generator's 16 layer shapes
    generator   ngi_bench generator: the shipped surround model at 256 x 128 (its N = 64 frame) and 1024 x 512:
                wall time and the per-op device time (conv, transposed conv, batch norm, ...) of a profiled run
    mlp         ngi_bench mlp --ao: seed 001's AO network (16 x 8) over 1920 x 1080 pixels, device in and out
    frame       frame_bench: the whole surround frame path at N = 64 (device in, device out)
    render      render_bench: the path tracer, one scene, N = 64, 16 spp

Each finished (device, benchmark) result is written to --out at once (atomically), and a rerun with the same
--out skips what is there, so an interrupted sweep loses nothing finished. Progress with an ETA on stderr.

    PYTHONPATH=build/python RUSTICL_ENABLE=llvmpipe /usr/bin/python3 perf/bench_devices.py \\
        --build build --out perf/devices_2core.json --markdown
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tqdm import tqdm

import ngi

REPO = Path(__file__).resolve().parent.parent


def benchmarks(build, repeats):
    """name -> argv (without --device) of each benchmark."""
    # Models by their path relative to the repository (the benchmarks run there): the JSON names no machine path.
    bench, models = build.resolve() / "perf" / "ngi_bench", Path("models")
    r = str(repeats)
    return {
        "gemm": [bench, "gemm", "--repeats", r],
        "generator_256x128": [bench, "generator", "--model", models / "surround.safetensors", "--width", "256",
                              "--height", "128", "--repeats", r],
        "generator_1024x512": [bench, "generator", "--model", models / "surround.safetensors", "--width", "1024",
                               "--height", "512", "--repeats", r],
        "mlp_ao_1080p": [bench, "mlp", "--ao", "--model", models / "ao_sculpture_16x8.safetensors", "--repeats", r],
        "frame_n64": [build.resolve() / "perf" / "frame_bench", "--model", models / "surround.safetensors", "--n", "64",
                      "--runs", r],
        "render_n64": [build.resolve() / "perf" / "render_bench", "--n", "64", "--spp", "16", "--scenes", "room:seed=1"],
    }


def write_atomic(path, data):
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    os.replace(tmp, path)


def summary_rows(result):
    """(benchmark, figure) pairs of one device's results for the Markdown table."""
    rows = []
    g = result.get("gemm")
    if g:
        rows.append(("GEMM 1024³ (GFLOP/s)", f"{g['gemm_1024']['gflops']:.1f}"))
        rows.append(("GEMM, thesis generator's 16 layers (GFLOP/s)", f"{g['generator_gemm_total']['gflops']:.1f}"))
    for size in ("256x128", "1024x512"):
        gen = result.get(f"generator_{size}")
        if gen:
            rows.append((f"surround generator {size.replace('x', ' × ')} (ms)", f"{gen['ms_median']:.1f}"))
            kinds = {}
            for op in gen.get("per_op", []):
                kinds[op["kind"]] = kinds.get(op["kind"], 0.0) + op["ms"]
            for kind, ms in sorted(kinds.items(), key=lambda kv: -kv[1]):
                rows.append((f"  {kind} at {size.replace('x', ' × ')}, device time (ms)", f"{ms:.1f}"))
    m = result.get("mlp_ao_1080p")
    if m:
        rows.append(("AO network 16 × 8, 1920 × 1080 (ms)", f"{m['ms_median']:.1f}"))
    f = result.get("frame_n64")
    if f:
        for s in f.get("sizes", []):
            rows.append((f"whole frame N = {s['n']}, device in/out (ms)", f"{s['device']['median_ms']:.1f}"))
    r = result.get("render_n64")
    if r:
        for s in r.get("results", []):
            rows.append((f"path tracer {s['scene']}, N = 64, {s['reference_spp']} spp (Mrays/s)",
                         f"{s['rays_per_second'] / 1e6:.1f}"))
    for name, res in result.items():
        if isinstance(res, dict) and "error" in res:
            rows.append((f"{name}: failed", res["error"].splitlines()[-1][:80]))
    return rows


def markdown(data):
    devices = data["devices"]
    names = [f"{d['info']['name']} ({d['info']['platform']})" for d in devices]
    table = {}
    order = []
    for i, d in enumerate(devices):
        for label, value in summary_rows(d["results"]):
            if label not in table:
                table[label] = [""] * len(devices)
                order.append(label)
            table[label][i] = value
    lines = ["| benchmark | " + " | ".join(names) + " |", "| --- |" + " --- |" * len(devices)]
    for label in order:
        lines.append(f"| {label} | " + " | ".join(table[label]) + " |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=str(REPO / "build"), help="build tree with perf/ (default: build)")
    ap.add_argument("--out", required=True, help="JSON file (reused: finished results are kept)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per benchmark (median)")
    ap.add_argument("--only", help="comma-separated benchmark names (default: all)")
    ap.add_argument("--markdown", action="store_true", help="also print the device x benchmark table")
    args = ap.parse_args(argv)

    build, out = Path(args.build), Path(args.out)
    runs = benchmarks(build, args.repeats)
    if args.only:
        unknown = set(args.only.split(",")) - set(runs)
        if unknown:
            ap.error(f"unknown benchmark(s) {sorted(unknown)}; choose from {sorted(runs)}")
        runs = {k: v for k, v in runs.items() if k in args.only.split(",")}
    data = json.loads(out.read_text()) if out.is_file() else {"devices": []}
    known = {d["index"]: d for d in data["devices"]}
    devices = ngi.devices()
    for info in devices:
        if info["index"] not in known:
            known[info["index"]] = {"index": info["index"], "info": info, "results": {}}
            data["devices"].append(known[info["index"]])
    todo = [(d["index"], name) for d in devices for name in runs if name not in known[d["index"]]["results"]]
    print(f"bench_devices: {len(devices)} device(s), {len(todo)} benchmark runs to do "
          f"({sum(len(d['results']) for d in data['devices'])} already in {out})", file=sys.stderr)
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", "/tmp/pocl-cache")
    env.setdefault("NGI_CACHE_DIR", "/tmp/ngi-cache")
    with tqdm(todo, unit="run", file=sys.stderr, mininterval=1) as bar:
        for index, name in bar:
            bar.set_description(f"{index} {name}")
            t0 = time.monotonic()
            cmd = [str(c) for c in runs[name]] + ["--device", index]
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=REPO)
            if proc.returncode != 0:
                result = {"error": f"exit {proc.returncode}: {proc.stderr.strip()[-2000:]}"}
            else:
                result = json.loads(proc.stdout)
            result["wall_s"] = round(time.monotonic() - t0, 1)
            known[index]["results"][name] = result
            write_atomic(out, data)
    if args.markdown:
        print(markdown(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())

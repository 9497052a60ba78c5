#!/usr/bin/python3
"""Issue 29's cases side by side in one run: the sizes a real-time host runs, ngi against PyTorch's fastest CPU path.

Cases (each side runs in blocks of --block calls, the sides alternating block by block for --repeats rounds after
warm-ups; the first call of a block is a warm-up too: medians of the rest, --repeats x (--block - 1) per side).
Why blocks, not run by run: on this 2-core machine PoCL's worker threads and PyTorch's OpenMP threads slow each
other down right after a switch (measured: PyTorch's fastest mlp 26-40 ms alone, 30-177 ms when every call
alternates with ngi's; ngi's 13-31 ms alone, 13-58 ms alternating), which says more about the switch than either side.
  generator     the shipped rungs at N = 64 (--rungs; default the two indirect-light rungs and the ngf 32 surround
                rung), their own F16 weights and bn_mode, one random input of the rung's size (surround: the 2:1
                global view 4N x 2N; single view: N x N): ngi.Model.run (NumPy in and out) against PyTorch eager
                (ngi.reference_models.load_generator, train-mode BN for per_image) and fastest (torch.jit.script +
                freeze + optimize_for_inference, per-image BN as InstanceNorm2d: perf/torch_generator.py); plus one
                `ngi_bench generator` run for the per-node device times (profiled run) and its own wall median.
  voxel_sh      seed 004's three networks on a 10,000-voxel synthetic scene (perf/side_by_side_voxel_sh.py's cases)
  neural_gi     seed 002's default network at N = 64 (perf/side_by_side_neural_gi.py's model, weights and inputs)
  frame         `frame_bench --n 64` with the ngf 32 surround rung: SurroundPipeline::run (host planes in, lightmap +
                final + display out) and ::enqueue (device in and out), in process; then the whole `ngi lightmap`
                command on a path-traced N = 64 frame (--frame, or one rendered here), --repeats times with the
                program cache warm, wall time from process start to exit, and `ngi lightmap --timings`' phases of
                one run; and `ngi devices --no-check` (process start + OpenCL platform and device discovery)
  launch        the floor: an empty kernel on the same device through pyopencl (no ngi code): enqueue + finish one at
                a time, and 1,000 enqueues followed by one finish (per launch)
Targets (issue 29; ratio = ngi / PyTorch fastest): generator rungs <= 0.35, voxel_sh and neural_gi <= 0.8, frame
in process <= 8 ms on PoCL, the command <= 2x the in-process time.

Prints one JSON object on stdout (and to --out) and a Markdown summary on stderr.
Usage: PYTHONPATH=training:build/python /usr/bin/python3 perf/small_shapes.py [--device pocl] [--repeats 15]
           [--only generator,voxel_sh,neural_gi,frame,launch] [--out FILE.json]
Set POCL_CACHE_DIR / NGI_CACHE_DIR (the subprocesses inherit them); on rusticl: RUSTICL_ENABLE=llvmpipe.
"""
import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# PyTorch's OpenMP threads may spin after each call and compete with the OpenCL device's threads in the
# alternation; passive waiting is asked for before torch loads its OpenMP runtime (as the other side-by-sides).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np
import torch

import ngi.model_file as model_file
import ngi.reference_models as reference_models

import side_by_side_neural_gi as nsbs
import side_by_side_voxel_sh as vsbs
import torch_generator
from bench_record import emit, git_head, load, log, relative

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
N = 64
RUNGS = ["models/ladder/gi_surround_n64_ngf16.safetensors", "models/ladder/gi_single_view_n64_ngf16.safetensors",
         "models/ladder/surround_n64_ngf32.safetensors"]
FRAME_RUNG = "models/ladder/surround_n64_ngf32.safetensors"
TARGETS = {"generator": 0.35, "voxel_sh": 0.8, "neural_gi": 0.8, "frame_in_process_ms": 8.0,
           "command_over_in_process": 2.0}


def run_json(cmd, env=None):
    log("$ " + " ".join(str(c) for c in cmd))
    done = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE, check=True, text=True, env=env)
    return json.loads(done.stdout)


def alternate_blocks(runs, args):
    """Each callable of `runs` (name -> fn) in blocks of args.block calls, the names in turn, args.repeats rounds
    after args.warmups calls of each; the first call of every block is not timed. Returns the times per name and
    each one's last result as float64."""
    times = {k: [] for k in runs}
    results = {}
    with torch.no_grad():
        for k, f in runs.items():
            for _ in range(args.warmups):
                f()
        for _ in range(args.repeats):
            for k, f in runs.items():
                for i in range(args.block):
                    t0 = time.perf_counter()
                    r = f()
                    dt = (time.perf_counter() - t0) * 1e3
                    if i > 0:
                        times[k].append(dt)
                results[k] = np.asarray(r, dtype=np.float64)
    return times, results


def summarize(times, results=None, reference=None, metric=None):
    med = {k: statistics.median(v) for k, v in times.items()}
    row = {"ms_median": med, "ms_all": times, "ngi_over_fastest": med["ngi"] / med["pytorch_fastest"],
           "ngi_over_eager": med["ngi"] / med["pytorch_eager"]}
    if reference is not None:
        row["max_diff_vs_float64"] = {k: metric(v, reference) for k, v in results.items()}
    return row


def max_abs(y, reference):
    return float(np.abs(np.asarray(y, np.float64) - reference).max())


def generator_cases(args, ngi, dev):
    rows = []
    for rung in args.rungs:
        tensors, config = model_file.read_model(str(REPO / rung))
        surround = config["input_nc"] == 12
        w, h = (4 * N, 2 * N) if surround else (N, N)
        bn_mode = config["bn_mode"]
        log(f"== generator {Path(rung).name} at {w}x{h} ({bn_mode}; load {load()})")
        net = reference_models.load_generator(tensors, config).eval()
        x = torch.rand(1, config["input_nc"], h, w, generator=torch.Generator().manual_seed(3)) * 2 - 1
        x_np = np.ascontiguousarray(x.numpy())
        eager = reference_models.load_generator(tensors, config)
        reference_models.set_bn_mode(eager, bn_mode)
        fastest = torch_generator.fastest_generator(net, bn_mode)
        m = ngi.Model(dev, str(REPO / rung))
        runs = {"ngi": lambda: m.run(x_np), "pytorch_eager": lambda: eager(x), "pytorch_fastest": lambda: fastest(x)}
        times, results = alternate_blocks(runs, args)
        reference = reference_models.run_reference(net, x, bn_mode).numpy()
        row = {"case": Path(rung).stem, "model": rung, "input_shape": [1, config["input_nc"], h, w],
               "bn_mode": bn_mode, "ngf": config["ngf"], "num_downs": config["num_downs"],
               **summarize(times, results, reference, max_abs)}
        del m
        # The per-node profile (device time of one profiled run) and ngi_bench's own wall median in process.
        gen = run_json([args.bench, "generator", "--model", REPO / rung, "--width", w, "--height", h, "--repeats",
                        args.runs, "--device", args.device])
        row["bench"] = {k: gen[k] for k in ("ms_median", "ms_all", "device_ms_total", "gflop_total", "memory_mib",
                                             "per_op")}
        row["bench"]["launches"] = gen.get("launches")
        rows.append(row)
        log(f"{row['case']}: ngi {row['ms_median']['ngi']:.2f} ms, fastest {row['ms_median']['pytorch_fastest']:.2f}"
            f" ms, ratio {row['ngi_over_fastest']:.2f}; bench wall {gen['ms_median']:.2f}, device "
            f"{gen['device_ms_total']:.2f} ms")
    return rows


def voxel_cases(args, ngi, dev):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for arch, parameters, runs, y64 in vsbs.cases(ngi, dev, tmp, args.voxels):
            log(f"== voxel_sh {arch} (load {load()})")
            times, results = alternate_blocks(runs, args)
            row = {"case": arch, "parameters": parameters, "voxels": args.voxels,
                   **summarize(times, results, y64, max_abs)}
            rows.append(row)
            log(f"{arch}: ngi {row['ms_median']['ngi']:.2f} ms, fastest {row['ms_median']['pytorch_fastest']:.2f} "
                f"ms, ratio {row['ngi_over_fastest']:.2f}")
    return rows


def neural_gi_case(args, ngi, dev):
    model = nsbs.round_to_f16(nsbs.build_model())
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "neural_gi.safetensors")
        nsbs.neural_gi.export_model(model, path, bn_mode="per_image", half=True, scene_box=nsbs.SCENE_BOX,
                                    source="perf/small_shapes.py: random weights (parity test's), seed 1")
        m = ngi.Model(dev, path)
        x = nsbs.parity.random_inputs(N, N, torch.Generator().manual_seed(nsbs.SEED + N))
        x_np = np.ascontiguousarray(x.numpy(), dtype=np.float32)
        eager = nsbs.copy.deepcopy(model).train()
        fastest = nsbs.fastest_form(model, x)
        log(f"== neural_gi N {N} (load {load()})")
        runs = {"ngi": lambda: m.run(x_np), "pytorch_eager": lambda: eager(x), "pytorch_fastest": lambda: fastest(x)}
        times, results = alternate_blocks(runs, args)
        with torch.no_grad():
            reference = nsbs.copy.deepcopy(model).double().train()(x.double()).numpy()
        row = {"case": f"neural_gi N {N}", "input_shape": list(x.shape),
               **summarize(times, results, reference, nsbs.max_relative)}
        row["bench"] = run_json([args.bench, "neural-gi", "--model", path, "--frames", f"{N}:1", "--repeats",
                                 args.runs, "--device", args.device])
        del m
    log(f"neural_gi: ngi {row['ms_median']['ngi']:.2f} ms, fastest {row['ms_median']['pytorch_fastest']:.2f} ms, "
        f"ratio {row['ngi_over_fastest']:.2f}")
    return [row]


def wall_ms(cmd, env):
    t0 = time.perf_counter()
    subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    return (time.perf_counter() - t0) * 1e3


def frame_case(args):
    env = dict(os.environ, NGI_DEVICE=args.device)
    bench = run_json([args.frame_bench, "--model", REPO / FRAME_RUNG, "--n", N, "--runs", args.runs, "--device",
                      args.device])
    if "model" in bench:
        bench["model"] = relative(bench["model"])  # frame_bench prints the absolute path it was given
    row = {"case": f"frame N {N} {Path(FRAME_RUNG).stem}", "model": FRAME_RUNG, "frame_bench": bench}
    with tempfile.TemporaryDirectory() as tmp:
        frame = args.frame
        if not frame:
            frame = os.path.join(tmp, "frame")
            subprocess.run([args.ngi, "render", "--scene", "room:seed=204", "--frame", "45", "--path-frames", "100",
                            "--face", str(N), "--spp", "16", "--out", frame], check=True, stdout=subprocess.DEVNULL,
                           env=env)
        cmd = [args.ngi, "lightmap", "--frame", frame, "--model", REPO / FRAME_RUNG, "--device", args.device]
        out_i = 0

        def lightmap(extra=()):
            nonlocal out_i
            out_i += 1
            return cmd + ["--out", os.path.join(tmp, f"out{out_i}"), *extra]
        wall_ms(lightmap(), env)  # warm the program caches
        command, devices = [], []
        for _ in range(args.runs):
            command.append(wall_ms(lightmap(), env))
            devices.append(wall_ms([args.ngi, "devices", "--no-check"], env))
        # --timings: the phases of one run (a build from before the option has none: recorded as empty).
        done = subprocess.run([str(c) for c in lightmap(["--timings"])], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env)
        timings = [line for line in done.stderr.splitlines() if line.startswith("timings")]
    row["command_ms_median"], row["command_ms_all"] = statistics.median(command), command
    row["devices_ms_median"], row["devices_ms_all"] = statistics.median(devices), devices
    row["command_timings"] = timings
    in_process = bench["sizes"][0]["host"]["median_ms"]
    row["in_process_ms"] = in_process
    row["command_over_in_process"] = row["command_ms_median"] / in_process
    log(f"frame: in process {in_process:.2f} ms (device path {bench['sizes'][0]['device']['median_ms']:.2f}), "
        f"command {row['command_ms_median']:.1f} ms, ngi devices {row['devices_ms_median']:.1f} ms")
    return [row]


def launch_floor(args):
    """An empty kernel through pyopencl on the device ngi would open for --device (matched by platform name)."""
    import pyopencl as cl
    want = {"pocl": "Portable Computing Language", "rusticl": "rusticl"}.get(args.device, args.device)
    platforms = [p for p in cl.get_platforms() if want.lower() in p.name.lower()]
    if not platforms:
        return [{"case": "launch floor", "skipped": f"no platform matching {want!r}"}]
    device = platforms[0].get_devices()[0]
    ctx = cl.Context([device])
    queue = cl.CommandQueue(ctx)
    kernel = cl.Program(ctx, "kernel void empty(global float* x) { }").build().empty
    buf = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 64)
    kernel.set_args(buf)
    for _ in range(50):
        cl.enqueue_nd_range_kernel(queue, kernel, (1,), (1,)).wait()
    single, batched = [], []
    for _ in range(args.runs):
        t0 = time.perf_counter()
        for _ in range(200):
            cl.enqueue_nd_range_kernel(queue, kernel, (1,), (1,))
            queue.finish()
        single.append((time.perf_counter() - t0) / 200 * 1e6)
        t0 = time.perf_counter()
        for _ in range(1000):
            cl.enqueue_nd_range_kernel(queue, kernel, (1,), (1,))
        queue.finish()
        batched.append((time.perf_counter() - t0) / 1000 * 1e6)
    row = {"case": "launch floor", "platform": platforms[0].name, "device": device.name,
           "enqueue_finish_us_median": statistics.median(single), "enqueue_batched_us_median": statistics.median(batched)}
    log(f"launch floor: {row['enqueue_finish_us_median']:.1f} us enqueue+finish, {row['enqueue_batched_us_median']:.1f}"
        f" us per launch batched")
    return [row]


def table(result):
    lines = ["| case | ngi ms | PyTorch eager ms | PyTorch fastest ms | ngi / fastest (target) | max diff vs float64 |",
             "|---|---|---|---|---|---|"]
    for group in ("generator", "voxel_sh", "neural_gi"):
        for r in result["cases"].get(group, []):
            m = r["ms_median"]
            lines.append(f"| {group} {r['case']} | {m['ngi']:.2f} | {m['pytorch_eager']:.2f} | {m['pytorch_fastest']:.2f}"
                         f" | **{r['ngi_over_fastest']:.2f}** (<= {TARGETS[group]}) "
                         f"| {r['max_diff_vs_float64']['ngi']:.1e} |")
    for r in result["cases"].get("frame", []):
        s = r["frame_bench"]["sizes"][0]
        lines += ["", f"frame ({r['case']}): in process run() {s['host']['median_ms']:.2f} ms, enqueue() "
                      f"{s['device']['median_ms']:.2f} ms (target <= {TARGETS['frame_in_process_ms']}); `ngi lightmap` "
                      f"{r['command_ms_median']:.1f} ms = {r['command_over_in_process']:.1f}x in process (target <= "
                      f"{TARGETS['command_over_in_process']}); `ngi devices --no-check` {r['devices_ms_median']:.1f} ms"]
    for r in result["cases"].get("launch", []):
        if "skipped" not in r:
            lines.append(f"launch floor ({r['platform']}): {r['enqueue_finish_us_median']:.1f} us enqueue + finish, "
                         f"{r['enqueue_batched_us_median']:.1f} us per launch when batched")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="pocl", help="ngi device spec (pocl, rusticl, cpu, P:D)")
    ap.add_argument("--build", default=str(REPO / "build"), help="the build tree (ngi, perf/ngi_bench, perf/frame_bench)")
    ap.add_argument("--only", default="generator,voxel_sh,neural_gi,frame,launch")
    ap.add_argument("--rungs", nargs="+", default=RUNGS)
    ap.add_argument("--voxels", type=int, default=10000)
    ap.add_argument("--frame", help="an N = 64 frame folder for `ngi lightmap` (default: one rendered here)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--warmups", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=5, help="rounds of blocks")
    ap.add_argument("--block", type=int, default=6, help="calls per block (the first one untimed)")
    ap.add_argument("--out", help="also write the JSON here")
    args = ap.parse_args()
    args.runs = args.repeats * (args.block - 1)  # timed calls per side; the subprocess benchmarks' repeats too
    build = Path(args.build)
    args.ngi, args.bench, args.frame_bench = build / "ngi", build / "perf" / "ngi_bench", build / "perf" / "frame_bench"
    only = set(args.only.split(","))
    import ngi

    start, start_load = time.time(), load()
    torch.set_num_threads(args.threads)
    result = {"date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
              "git_head": git_head(), "targets": TARGETS,
              "machine": {"cpus": os.cpu_count(), "torch": torch.__version__, "torch_threads": torch.get_num_threads(),
                          "blas": torch_generator.blas_info(), "omp_wait_policy": os.environ["OMP_WAIT_POLICY"]},
              "settings": {"device": args.device, "warmups": args.warmups, "repeats": args.repeats, "block": args.block,
                           "build": relative(args.build), "rusticl_enable": os.environ.get("RUSTICL_ENABLE"),
                           # knob overrides (the tuning database's choice otherwise: ngi_device's gemm entry)
                           "ngi_gemm": os.environ.get("NGI_GEMM"), "ngi_conv_gemm": os.environ.get("NGI_CONV_GEMM")},
              "load_average": {"start": start_load}, "cases": {}}
    with ngi.Device(args.device) as dev:
        info = dev.info
        result["ngi_device"] = {k: info[k] for k in ("platform", "name", "driver_version", "compute_units",
                                                               "native_float_vector_width")}
        if "generator" in only:
            result["cases"]["generator"] = generator_cases(args, ngi, dev)
        if "voxel_sh" in only:
            result["cases"]["voxel_sh"] = voxel_cases(args, ngi, dev)
        if "neural_gi" in only:
            result["cases"]["neural_gi"] = neural_gi_case(args, ngi, dev)
    if "frame" in only:
        result["cases"]["frame"] = frame_case(args)
    if "launch" in only:
        result["cases"]["launch"] = launch_floor(args)
    result["load_average"]["end"] = load()
    result["wall_seconds"] = time.time() - start
    result["summary_table"] = table(result)
    emit(result, args.out)
    log("\n".join(result["summary_table"]))
    log(f"load {start_load} -> {result['load_average']['end']}; {result['wall_seconds']:.0f} s")


if __name__ == "__main__":
    main()

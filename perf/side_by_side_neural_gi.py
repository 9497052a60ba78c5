#!/usr/bin/python3
"""Seed 002's network: ngi (model family neural_gi, through the Python bindings) vs PyTorch CPU in one run, same
weights, same inputs; with --bench also whole frames with and without joint bilateral upsampling (`ngi_bench
neural-gi`, the same model file on the same device). Prints one JSON object (and writes it to --out).

Network: ngi.neural_gi.NeuralGI with its defaults (U-Net buffer: C_B 16, ngf 32, num_downs 6 or --num-downs; MLP
8 x 256 with the input re-injected at layer 4; Eq. 3 encoding, 378 channels), random weights drawn as
tests/parity/make_neural_gi_parity.py draws them (He-scaled so that activations stay O(1) and the exp-decoded
output spans orders of magnitude; seeded), exported as training exports a model (ngi.neural_gi.export_model: F16
weights, bn_mode per_image, scene box [0, 16]^3). PyTorch runs the F16-rounded weights, so all sides compute the
same function. Inputs [1, 18, N, N]: ngi.neural_gi.assemble_inputs on random G-buffers (seeded), N = --sizes.

Per N:
  ngi               ngi.Model(dev, file).run(x): the input guard and the whole network as one graph on --device,
                    NumPy in and out
  PyTorch eager     NeuralGI in train mode (batch norm with the image's statistics = bn_mode per_image at batch 1),
                    torch.no_grad(), torch.set_num_threads(--threads)
  PyTorch fastest   the same with every BatchNorm2d as the equivalent InstanceNorm2d (perf/torch_generator.py),
                    torch.jit.trace + torch.jit.freeze + torch.jit.optimize_for_inference up to the MLP's raw
                    output, then the exp decoding of its 3 channels eagerly (fastest_form says why)
  each --warmups times, then the three alternating run by run, --repeats rounds; medians; ratio ngi / fastest.
  parity: max over pixels and channels of |y - y64| / y64 for ngi and both PyTorch paths, y64 the same model in
  float64 (the output is exp(raw) > 0, so this is the raw output's absolute error).
--bench build/perf/ngi_bench: `ngi_bench neural-gi` on the same model file, device and --repeats (--frames N:K,...
  passed on): NeuralGiRenderer::run per frame of face size N with the network at N/K and joint bilateral
  upsampling to N (K = 1: none), the network alone at N/K and the upsampling alone (perf/ngi_bench.cpp, on a
  synthetic room frame); its JSON goes under "frame". PyTorch has no counterpart of the frame path: the table
  sets each frame beside PyTorch's fastest network at the frame's full size N.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/side_by_side_neural_gi.py [--device pocl] [--sizes 64 128 256]
           [--repeats 7] [--warmups 2] [--threads 2] [--bench build/perf/ngi_bench] [--frames 128:1,256:4]
           [--out FILE.json]
Mesa rusticl (llvmpipe): RUSTICL_ENABLE=llvmpipe ... --device rusticl --sizes 64 --repeats 1 --warmups 0
  [--bench ... --frames 256:4]: this network took ~1000x PoCL's time there (120 s per run at N = 64 on the 2-core
  machine of docs/PERFORMANCE.md), so keep sizes and repeats small. Set POCL_CACHE_DIR / NGI_CACHE_DIR to keep the
  kernel caches apart; ngi_bench inherits them.
"""
import argparse
import copy
import datetime
import importlib.util
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

# PyTorch's OpenMP threads may spin after each call (active wait) and compete with the OpenCL device's threads in
# the alternation; passive waiting is asked for before torch loads its OpenMP runtime (as side_by_side_voxel_sh.py).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np
import torch

import ngi.neural_gi as neural_gi
from bench_record import emit, git_head, load, log, relative

import torch_generator  # perf/, beside this script: time_ms, blas_info, instance_norm_equivalent

HERE = Path(__file__).resolve().parent
REPO = HERE.parent


def _load_parity_module():
    """The parity test's weights and inputs (tests/parity/make_neural_gi_parity.py), loaded from its file: the
    script is not a package module, and nothing here edits sys.path (training/tests/test_package_layout.py)."""
    path = REPO / "tests" / "parity" / "make_neural_gi_parity.py"
    spec = importlib.util.spec_from_file_location("make_neural_gi_parity", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


parity = _load_parity_module()

SCENE_BOX = ((0.0, 0.0, 0.0), (16.0, 16.0, 16.0))  # what parity.random_inputs normalizes positions with
SEED = 1


def build_model(num_downs=neural_gi.DEFAULT_NUM_DOWNS):
    """The default NeuralGI (num_downs: 5 for the shipped N = 32 models) with the parity test's random weights, rounded
    to F16 as the exported file stores them."""
    g = torch.Generator().manual_seed(SEED)
    torch.manual_seed(SEED)
    model = neural_gi.NeuralGI(num_downs=num_downs)
    parity.randomize(model, g)
    return model


def round_to_f16(model):
    with torch.no_grad():
        for t in list(model.parameters()) + list(model.buffers()):
            if t.is_floating_point():
                t.copy_(t.half().float())
    return model


class RawOutput(torch.nn.Module):
    """NeuralGI without its exp decoding: the MLP's linear output."""

    def __init__(self, model):
        super().__init__()
        self.model = model

    def forward(self, inputs):
        return self.model.raw_output(inputs)


def fastest_form(model, x):
    """PyTorch's fastest CPU inference form at x's size: per-image batch norm as InstanceNorm2d (freezing needs eval
    mode), traced (the encoding is a Python loop over bands; tracing unrolls it), frozen, optimized. The decoding
    exp(min(raw, 88)) stays outside, eager, on the 3 output channels: with it inside, torch 1.13's
    optimize_for_inference stops with "isDouble() INTERNAL ASSERT FAILED" (its pass that fuses a clamp into the
    convolution before it meets a clamp with a max and no min)."""
    raw = RawOutput(torch_generator.instance_norm_equivalent(model)).eval()
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore", torch.jit.TracerWarning)  # check_inputs' shape tests become constants
        frozen = torch.jit.optimize_for_inference(torch.jit.freeze(torch.jit.trace(raw, x)))
    return lambda inputs: neural_gi.decode_indirect(frozen(inputs))


def max_relative(y, reference):
    y = np.asarray(y, np.float64)
    return float((np.abs(y - reference) / np.maximum(reference, 1e-300)).max())


def run_size(args, ngi_model, model, n):
    x = parity.random_inputs(n, n, torch.Generator().manual_seed(SEED + n))
    x_np = np.ascontiguousarray(x.numpy(), dtype=np.float32)
    eager = copy.deepcopy(model).train()  # per-image statistics (updates only this copy's running statistics)
    fastest = fastest_form(model, x)
    runs = {"ngi": lambda: ngi_model.run(x_np), "pytorch_eager": lambda: eager(x), "pytorch_fastest": lambda: fastest(x)}
    times = {k: [] for k in runs}
    outputs = {}
    log(f"N {n}: {args.warmups} warm-ups + {args.repeats} alternating runs of each (load {load()}) ...")
    with torch.no_grad():
        for i in range(args.warmups + args.repeats):
            for k, f in runs.items():
                ms = torch_generator.time_ms(lambda: outputs.__setitem__(k, f()))
                if i >= args.warmups:
                    times[k].append(ms)
        log(f"N {n}: float64 reference ...")
        reference = copy.deepcopy(model).double().train()(x.double()).numpy()
    med = {k: statistics.median(v) for k, v in times.items()}
    row = {
        "n": n, "input_shape": [1, neural_gi.INPUT_CHANNELS, n, n],
        "ms_median": med, "ms_all": times,
        "ngi_over_fastest": med["ngi"] / med["pytorch_fastest"],
        "ngi_over_eager": med["ngi"] / med["pytorch_eager"],
        "max_relative_diff_vs_float64": {k: max_relative(v, reference) for k, v in outputs.items()},
        "reference_output": {"min": float(reference.min()), "median": float(np.median(reference)),
                             "max": float(reference.max())},
        "load_after": load(),
    }
    log(f"N {n}: " + ", ".join(f"{k} {v:.1f} ms" for k, v in med.items()) +
        f"; ngi / fastest {row['ngi_over_fastest']:.2f}; max rel diff ngi {row['max_relative_diff_vs_float64']['ngi']:.1e}")
    return row


def run_bench(args, model_path):
    cmd = [args.bench, "neural-gi", "--model", model_path, "--repeats", str(args.repeats), "--device", args.device]
    if args.frames:
        cmd += ["--frames", args.frames]
    log("$ " + " ".join(cmd))
    done = subprocess.run(cmd, stdout=subprocess.PIPE, check=True, text=True)
    return json.loads(done.stdout)


def table(result):
    lines = ["| N | ngi ms | PyTorch eager ms | PyTorch fastest ms | ngi / fastest | max rel. diff vs float64 (ngi) |",
             "|---|---|---|---|---|---|"]
    for r in result["network"]:
        m = r["ms_median"]
        lines.append(f"| {r['n']} | {m['ngi']:.1f} | {m['pytorch_eager']:.1f} | {m['pytorch_fastest']:.1f} "
                     f"| {r['ngi_over_fastest']:.2f} | {r['max_relative_diff_vs_float64']['ngi']:.1e} |")
    frame = result.get("frame")
    if frame:
        fastest = {r["n"]: r["ms_median"]["pytorch_fastest"] for r in result["network"]}
        lines += ["", "| frame N | upsample K | network at | frame ms | network alone ms | upsampling alone ms "
                      "| frame / PyTorch fastest network at N |", "|---|---|---|---|---|---|---|"]
        for c in frame["cases"]:
            if "skipped" in c:
                lines.append(f"| {c['n']} | {c['upsample']} | skipped: {c['skipped']} | | | | |")
                continue
            ratio = f"{c['frame_ms_median'] / fastest[c['n']]:.2f}" if c["n"] in fastest else "-"
            jbu = f"{c['jbu_ms_median']:.1f}" if "jbu_ms_median" in c else "-"
            lines.append(f"| {c['n']} | {c['upsample']} | {c['network_side']} | {c['frame_ms_median']:.1f} "
                         f"| {c['network_ms_median']:.1f} | {jbu} | {ratio} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="pocl", help="ngi device spec (pocl, rusticl, cpu, gpu, P:D)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 256],
                    help="network sides N (multiples of 2^num_downs)")
    ap.add_argument("--num-downs", type=int, default=neural_gi.DEFAULT_NUM_DOWNS,
                    help="the U-Net's depth (default 6; the shipped per-scene models at N = 32 use 5)")
    ap.add_argument("--threads", type=int, default=2, help="torch.set_num_threads")
    ap.add_argument("--warmups", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--bench", help="ngi_bench: also time whole frames (ngi_bench neural-gi) with the same model")
    ap.add_argument("--frames", help="ngi_bench neural-gi --frames N:K,... (default: ngi_bench's)")
    ap.add_argument("--out", help="also write the JSON here")
    args = ap.parse_args()
    if args.num_downs < 5:
        ap.error("--num-downs must be >= 5 (UnetGenerator's fixed outer levels)")
    if any(n % 2 ** args.num_downs for n in args.sizes):
        ap.error(f"--sizes must be multiples of 2^{args.num_downs}")
    import ngi

    start, start_load = time.time(), load()
    torch.set_num_threads(args.threads)
    model = round_to_f16(build_model(args.num_downs))
    result = {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "git_head": git_head(),
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "torch": torch.__version__,
                    "torch_threads": torch.get_num_threads(), "blas": torch_generator.blas_info(),
                    "omp_wait_policy": os.environ["OMP_WAIT_POLICY"]},
        "settings": {"device": args.device, "sizes": args.sizes, "num_downs": args.num_downs, "warmups": args.warmups, "repeats": args.repeats,
                     "bench": relative(args.bench) if args.bench else None, "frames": args.frames,
                     "rusticl_enable": os.environ.get("RUSTICL_ENABLE")},
        "model": {"config": model.config(), "parameters": neural_gi.parameter_counts(model), "weights": "F16",
                  "bn_mode": "per_image", "scene_box": SCENE_BOX,
                  "weights_from": "tests/parity/make_neural_gi_parity.py randomize, seed 1"},
        "load_average": {"start": start_load},
        "network": [],
    }
    with tempfile.TemporaryDirectory() as tmp, ngi.Device(args.device) as dev:
        info = dev.info
        result["ngi_device"] = {k: info[k] for k in ("platform", "name", "vendor", "driver_version", "device_version",
                                                     "type", "compute_units")}
        model_path = os.path.join(tmp, "neural_gi_default.safetensors")
        neural_gi.export_model(model, model_path, bn_mode="per_image", half=True, scene_box=SCENE_BOX,
                               source="perf/side_by_side_neural_gi.py: random weights (parity test's), seed 1")
        ngi_model = ngi.Model(dev, model_path)
        for n in args.sizes:
            result["network"].append(run_size(args, ngi_model, model, n))
        del ngi_model
        if args.bench:
            result["frame"] = run_bench(args, model_path)
    result["load_average"]["end"] = load()
    result["wall_seconds"] = time.time() - start
    result["summary_table"] = table(result)
    emit(result, args.out)
    log("\n".join(result["summary_table"]))
    log(f"load {start_load} -> {result['load_average']['end']}; {result['wall_seconds']:.0f} s")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""ngi's per-pixel MLPs vs PyTorch CPU, side by side in one run (issue 9's benchmark; docs/PERFORMANCE.md).

Cases (same weights on both sides; inputs random in [-1, 1], the same shapes):
  ao 16x8 / 32x16 / 64x32   seed 001's AO networks (the shipped models/ao_sculpture_*.safetensors), 48 -> X tanh ->
                            Y tanh -> 1, over 1920 x 1080 pixels
  mlp 8x256                 Neural GI's rendering MLP shape: 64 -> 8 x 256 ReLU -> 3 over 256 x 256 pixels
ngi: `ngi_bench mlp` (device in, device out, median of --repeats after a warm-up) on the fused and dense paths,
and `--ao` for the whole AO network (ring gather + MLP + clamp). PyTorch: torch.set_num_threads(2), the model
scripted, torch.jit.freeze + torch.jit.optimize_for_inference (its fastest CPU inference path), input [items, C]
(its natural layout), median of --repeats after two warm-ups. The GEMM roof: `ngi_bench gemm` (ngi's packed GEMM
at 1024^3) and torch.mm at 1024^3, in the same run.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/mlp_side_by_side.py --bench build/perf/ngi_bench [--repeats 5]
           [--out FILE.json]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import torch

import ngi.model_file as model_file
from bench_record import emit

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def run_json(cmd):
    print("$ " + " ".join(cmd), file=sys.stderr)
    return json.loads(subprocess.run(cmd, stdout=subprocess.PIPE, check=True, text=True).stdout)


def torch_mlp(tensors, layers, input_nc):
    mods, in_f = [], input_nc
    for i, l in enumerate(layers):
        lin = torch.nn.Linear(in_f, l["out"])
        lin.weight.data = torch.from_numpy(np.asarray(tensors[f"layers.{i}.weight"], np.float32))
        lin.bias.data = torch.from_numpy(np.asarray(tensors[f"layers.{i}.bias"], np.float32))
        mods.append(lin)
        mods += {"tanh": [torch.nn.Tanh()], "relu": [torch.nn.ReLU()], "none": []}[l["activation"]]
        in_f = l["out"]
    return torch.nn.Sequential(*mods).eval()


def time_torch(model, x, repeats):
    with torch.no_grad():
        m = torch.jit.optimize_for_inference(torch.jit.freeze(torch.jit.script(model)))
        for _ in range(2):
            m(x)
        ms = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            m(x)
            ms.append((time.perf_counter() - t0) * 1e3)
    return ms


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", required=True)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--device", default="")
    ap.add_argument("--out")
    a = ap.parse_args()
    torch.set_num_threads(2)
    dev = ["--device", a.device] if a.device else []
    rep = ["--repeats", str(a.repeats)]
    result = {"torch_threads": torch.get_num_threads(), "torch_version": torch.__version__, "cases": []}

    gemm = run_json([a.bench, "gemm"] + dev + rep)
    x = torch.rand(1024, 1024)
    y = torch.rand(1024, 1024)
    torch.mm(x, y)
    mm = []
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        torch.mm(x, y)
        mm.append((time.perf_counter() - t0) * 1e3)
    result["gemm_roof"] = {"ngi_gflops": gemm["gemm_1024"]["gflops"],
                           "torch_gflops": 2 * 1024 ** 3 / (statistics.median(mm) * 1e-3) / 1e9}
    result["device"] = gemm["device"]

    with tempfile.TemporaryDirectory() as tmp:
        cases = []
        for size in ("16x8", "32x16", "64x32"):
            cases.append((f"ao {size}", os.path.join(REPO, "models", f"ao_sculpture_{size}.safetensors"), 1920, 1080))
        rng = np.random.default_rng(1)
        layers = [{"out": 256, "activation": "relu"} for _ in range(8)] + [{"out": 3, "activation": "none"}]
        tensors, in_f = {}, 64
        for i, l in enumerate(layers):
            bound = 1 / np.sqrt(in_f)
            tensors[f"layers.{i}.weight"] = rng.uniform(-bound, bound, (l["out"], in_f)).astype(np.float32)
            tensors[f"layers.{i}.bias"] = rng.uniform(-bound, bound, l["out"]).astype(np.float32)
            in_f = l["out"]
        big = os.path.join(tmp, "mlp_8x256.safetensors")
        model_file.write_model(big, tensors, {"format_version": 1, "family": "mlp", "input_nc": 64, "layers": layers})
        cases.append(("mlp 8x256", big, 256, 256))

        for name, path, w, h in cases:
            tensors, config = model_file.read_model(path)
            items = w * h
            row = {"case": name, "width": w, "height": h, "items": items}
            for p in ("fused", "dense"):
                try:
                    r = run_json([a.bench, "mlp", "--model", path, "--width", str(w), "--height", str(h), "--path", p]
                                 + dev + rep)
                    row[f"ngi_{p}_ms"], row["gflop"] = r["ms_median"], r["gflop"]
                except subprocess.CalledProcessError:
                    row[f"ngi_{p}_ms"] = None  # e.g. wider than the fused kernel's limit
            if config.get("ao"):
                row["ngi_ao_network_ms"] = run_json([a.bench, "mlp", "--ao", "--model", path, "--width", str(w),
                                                     "--height", str(h)] + dev + rep)["ms_median"]
            print(f"torch {name} ...", file=sys.stderr)
            xt = torch.rand(items, config["input_nc"]) * 2 - 1
            tm = time_torch(torch_mlp(tensors, config["layers"], config["input_nc"]), xt, a.repeats)
            row["torch_ms"] = statistics.median(tm)
            best = min(v for v in (row.get("ngi_fused_ms"), row.get("ngi_dense_ms")) if v is not None)
            row["ngi_best_ms"] = best
            row["speedup_vs_torch"] = row["torch_ms"] / best
            row["ngi_gflops"] = row["gflop"] / (best * 1e-3)
            row["torch_gflops"] = row["gflop"] / (row["torch_ms"] * 1e-3)
            row["fraction_of_ngi_gemm_roof"] = row["ngi_gflops"] / result["gemm_roof"]["ngi_gflops"]
            result["cases"].append(row)
    emit(result, a.out)


if __name__ == "__main__":
    main()

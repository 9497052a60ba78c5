#!/usr/bin/python3
"""Seed 004's networks: ngi (model family voxel_sh, through the Python bindings) vs PyTorch CPU in one run, same
weights, same scene. Prints one JSON object.

Per architecture (mlp 3 x 128, set 128/128 + 256/128, resnet 128 x 10 blocks; the widths of
training/ngi_train/voxel_sh/experiment.sh) on one synthetic scene of --voxels voxels (ngi_train.voxel_sh.data; the
timing does not depend on the values):
  ngi               ngi.Model.run([V, 10] raw attributes) -> [V, 27]: standardization, guard, network on the device
  PyTorch eager     ngi.voxel_sh.VoxelSh (the same math) under torch.no_grad(), torch.set_num_threads(--threads)
  PyTorch fastest   the same traced, torch.jit.freeze + torch.jit.optimize_for_inference
Each after --warmups runs, the three alternating run by run; medians of --repeats, and the ratio ngi / fastest.
max |diff| of ngi and PyTorch against PyTorch float64 on the same weights.
Usage: PYTHONPATH=training:build/python /usr/bin/python3 perf/side_by_side_voxel_sh.py [--device pocl] [--voxels 10000]
"""
import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

# PyTorch's OpenMP threads may spin after each call (active wait) and compete with PoCL's threads in the alternation;
# passive waiting is asked for (before torch loads its OpenMP runtime). Runs still vary: ngi's mlp took 30-58 ms
# across runs here, 30 ms alone (ngi probe-gi): compare ratios of one run, and docs/PERFORMANCE.md says which.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np
import torch

import ngi.voxel_sh as networks  # noqa: E402  (after OMP_WAIT_POLICY)

from ngi_train.voxel_sh import data, export  # noqa: E402

ARCHS = {"mlp": {"hidden": [128, 128, 128]}, "set": {"phi": [128, 128], "rho": [256, 128]},
         "resnet": {"width": 128, "blocks": 10}}


class Values(torch.nn.Module):
    """VoxelSh without the sanitized count (an int the tracer cannot keep): the traced function is the output."""

    def __init__(self, model):
        super().__init__()
        self.model = model

    def forward(self, raw):
        return self.model(raw)


def cases(ngi, dev, tmp, voxels):
    """One synthetic scene of `voxels` voxels, and per architecture: (name, parameters, the three runs as
    callables, the float64 reference output). perf/small_shapes.py runs the same cases."""
    data.make_synthetic_scene(Path(tmp) / "scene", voxels=voxels, seed=1)
    scene = data.load_scene(Path(tmp) / "scene")
    stats = data.Stats.from_scenes([scene])
    x = scene.attributes.astype(np.float32)
    xt = torch.from_numpy(x)
    out = []
    for arch, widths in ARCHS.items():
        net = networks.build(arch, **widths).eval()
        path = Path(tmp) / f"{arch}.safetensors"
        export.export(net, arch, widths, stats, scene.grid, path)
        std = networks.Standardization(stats.input_lo, stats.input_hi, stats.output_mean, stats.output_std)
        model = Values(networks.VoxelSh(net, std)).eval()
        with torch.no_grad():
            fastest = torch.jit.optimize_for_inference(torch.jit.freeze(torch.jit.trace(model, xt)))
            ref = Values(networks.VoxelSh(networks.build(arch, **widths).double(), std.double())).eval()
            ref.load_state_dict(model.state_dict())
            y64 = ref(xt.double()).numpy()
        m = ngi.Model(dev, str(path))
        runs = {"ngi": lambda m=m: m.run(x), "pytorch_eager": lambda model=model: model(xt),
                "pytorch_fastest": lambda fastest=fastest: fastest(xt)}
        out.append((arch, networks.parameter_count(net), runs, y64))
    return out


def alternate(runs, warmups, repeats):
    """Each callable of `runs` in turn, run by run: --warmups rounds untimed, then `repeats` timed. Returns the
    times (ms) per name and each one's last result as float64."""
    times = {k: [] for k in runs}
    results = {}
    with torch.no_grad():
        for i in range(warmups + repeats):
            for k, f in runs.items():
                t0 = time.perf_counter()
                r = f()
                dt = (time.perf_counter() - t0) * 1e3
                if i >= warmups:
                    times[k].append(dt)
                results[k] = np.asarray(r, dtype=np.float64)
    return times, results


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--voxels", type=int, default=10000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--warmups", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    import ngi

    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    out = {"omp_wait_policy": os.environ["OMP_WAIT_POLICY"], "device": args.device, "voxels": args.voxels, "threads": args.threads, "repeats": args.repeats,
           "torch": torch.__version__, "cases": {}}
    with tempfile.TemporaryDirectory() as tmp, ngi.Device(args.device) as dev:
        for arch, parameters, runs, y64 in cases(ngi, dev, tmp, args.voxels):
            times, results = alternate(runs, args.warmups, args.repeats)
            med = {k: statistics.median(v) for k, v in times.items()}
            out["cases"][arch] = {
                "parameters": parameters,
                "ms_median": med,
                "ngi_over_fastest": med["ngi"] / med["pytorch_fastest"],
                "ngi_over_eager": med["ngi"] / med["pytorch_eager"],
                "max_abs_diff_vs_float64": {k: float(np.abs(v - y64).max()) for k, v in results.items()},
            }
            print(f"{arch}: " + ", ".join(f"{k} {v:.1f} ms" for k, v in med.items()), file=sys.stderr, flush=True)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

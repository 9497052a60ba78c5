#!/usr/bin/python3
"""Generate PyTorch parity data for ngi's "voxel_sh" model family (docs/MODEL_FORMAT.md "voxel_sh").

For each architecture (mlp, set, resnet at ngi.voxel_sh's default widths) and weight dtype
(F32, F16): a network with random weights and random standardization statistics (one constant input channel,
hi == lo), written with ngi.model_file.write_voxel_sh_model, and its float64 output on raw voxel attributes of
V = 1, 37 and 1001 voxels (positions, albedo, sparse emission, voxel ids; some values outside the training range).
The reference is ngi.voxel_sh (the networks training trains) in float64 on the stored (for F16: rounded)
weights; the set network's reference is the literal broadcast-and-concatenate form (forward_concat), not the split
ngi and the training use.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 tests/parity/make_voxel_sh_parity.py --out DIR
Writes DIR/<model>.safetensors, DIR/<case>_input.npy, DIR/<case>_expected.npy and DIR/cases.json. Deterministic.
"""

import argparse
import json
import os

import numpy as np
import torch

import ngi.model_file as model_file
import ngi.voxel_sh as networks

GRID = [32, 32, 32]
SIZES = (1, 37, 1001)


def random_stats(g):
    lo = np.array([0.0, 0.0, 0.0, 0.02, 0.02, 0.02, 0.0, 0.0, 0.0, 0.0])
    hi = np.array([1.0, 1.0, 1.0, 0.98, 0.98, 0.98, 10.0, 8.0, 0.0, GRID[0] * GRID[1] * GRID[2] - 1.0])
    jitter = torch.rand(10, generator=g, dtype=torch.float64).numpy() * 0.05
    lo, hi = lo + np.where(hi > lo, jitter, 0.0), hi - np.where(hi > lo, jitter, 0.0)  # channel 8: hi == lo
    mean = (torch.randn(27, generator=g, dtype=torch.float64) * 0.7).numpy()
    std = (torch.rand(27, generator=g, dtype=torch.float64) * 1.9 + 0.1).numpy()
    return lo, hi, mean, std


def random_voxels(g, n):
    pos = torch.rand((n, 3), generator=g, dtype=torch.float64)
    albedo = torch.rand((n, 3), generator=g, dtype=torch.float64)
    lit = (torch.rand((n, 1), generator=g) < 0.1).double()
    emission = torch.rand((n, 3), generator=g, dtype=torch.float64) * 12 * lit  # a little beyond the range
    ids = torch.randint(0, GRID[0] * GRID[1] * GRID[2], (n, 1), generator=g).double()
    return torch.cat([pos, albedo, emission, ids], dim=1).float()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    torch.set_num_threads(1)
    cases = []
    for a, arch in enumerate(networks.ARCHITECTURES):
        widths = networks.widths_of(arch)
        for half in (False, True):
            seed = 10 * a + int(half)
            torch.manual_seed(seed)
            g = torch.Generator().manual_seed(seed)
            net = networks.build(arch, **widths).double()
            with torch.no_grad():
                for p in net.parameters():
                    p.mul_(1.5)  # livelier than nn.Linear's default init: more of tanh's range
                    # The reference uses exactly the values the file stores (F16 or F32).
                    p.copy_(p.half().double() if half else p.float().double())
            lo, hi, mean, std = random_stats(g)
            config = model_file.make_voxel_sh_config(
                arch, grid=GRID, input_lo=lo, input_hi=hi, output_mean=mean, output_std=std,
                source=f"tests/parity/make_voxel_sh_parity.py {arch}", **widths)
            name = f"{arch}_{'f16' if half else 'f32'}"
            model_file.write_voxel_sh_model(os.path.join(args.out, f"{name}.safetensors"), net.state_dict(), config,
                                            half=half)
            standardize = networks.Standardization(lo, hi, mean, std).double()
            for n in SIZES:
                raw = random_voxels(g, n)
                with torch.no_grad():
                    x, _ = networks.guard(standardize.inputs(raw.double()))
                    y = standardize.outputs(net.forward_concat(x) if arch == "set" else net(x))
                case = f"{name}_v{n}"
                np.save(os.path.join(args.out, f"{case}_input.npy"), raw.numpy())
                np.save(os.path.join(args.out, f"{case}_expected.npy"), y.float().numpy())
                print(f"{case:20s} input {tuple(raw.shape)} output {tuple(y.shape)} max|y| {y.abs().max().item():.3f}")
                cases.append({"name": case, "architecture": arch, "model": f"{name}.safetensors",
                              "dtype": "F16" if half else "F32", "voxels": n, "input": f"{case}_input.npy",
                              "expected": f"{case}_expected.npy"})
    with open(os.path.join(args.out, "cases.json"), "w") as f:
        json.dump(cases, f, indent=2)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {args.out}")


if __name__ == "__main__":
    main()

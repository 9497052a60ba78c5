#!/usr/bin/python3
"""Time the thesis generator in PyTorch on the CPU: the baseline ngi is compared against.

junyanz UnetGenerator(12, 3, num_downs=8, ngf=64) on one 1024x512 image
(N=1, C=12, H=512, W=1024), torch.no_grad(), dropout off. Also measures a
1024^3 SGEMM through torch.mm, to tell how fast this torch's BLAS is.

--path eager (default): the nn.Module as is (per_image: train-mode BatchNorm).
--path fastest: PyTorch's fastest CPU inference path (fastest_generator):
torch.jit.script + torch.jit.freeze + torch.jit.optimize_for_inference (folds
BatchNorm into the convolutions before it, runs them through oneDNN/MKLDNN);
per_image first swaps every BatchNorm2d for the equivalent InstanceNorm2d
(instance_norm_equivalent), since freezing needs eval mode.

Also the helpers perf/side_by_side.py shares: time_ms, sgemm_gflops,
blas_info, blas_library, instance_norm_equivalent, fastest_generator.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/torch_generator.py [--bn-mode per_image|running]
           [--path eager|fastest] [--repeats 5] [--threads 2] [--width 1024 --height 512]
Prints one JSON object on stdout; progress goes to stderr.
"""

import argparse
import copy
import json
import os
import re
import statistics
import sys
import time

import torch
import torch.nn as nn

import ngi.reference_models as reference_models


def blas_info():
    """The BLAS torch was built against: BLAS_INFO in torch.__config__.show().

    Searching the text for "MKL" would be wrong: it also mentions MKL-DNN
    (oneDNN) and "LAPACK ... usually provided by MKL" whatever the BLAS is.
    """
    match = re.search(r"BLAS_INFO=([^,\s]+)", torch.__config__.show())
    if match is None:
        return None
    names = {"mkl": "MKL", "open": "OpenBLAS", "openblas": "OpenBLAS"}
    return names.get(match.group(1).lower(), match.group(1))


def blas_library():
    """The BLAS shared library actually mapped into this process (Linux only).

    A 'generic' BLAS build (e.g. Debian's) dispatches to whatever libblas the
    system provides - reference BLAS or OpenBLAS differ by orders of magnitude.
    """
    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps if "blas" in line.lower() and "/" in line}
    except OSError:
        return None
    return sorted(os.path.realpath(path) for path in paths) or None


def time_ms(fn):
    start = time.perf_counter()
    fn()
    return (time.perf_counter() - start) * 1e3


def sgemm_gflops(n=1024, repeats=10):
    a, b = torch.randn(n, n), torch.randn(n, n)
    torch.mm(a, b)  # warm-up: thread pool start, page faults
    seconds = statistics.median(time_ms(lambda: torch.mm(a, b)) for _ in range(repeats)) / 1e3
    return 2.0 * n ** 3 / seconds / 1e9


def instance_norm_equivalent(model):
    """A copy of `model` in eval mode whose every BatchNorm2d is an InstanceNorm2d(affine, no running
    statistics, same eps) with the same weight and bias.

    For a batch of one image, training-mode BatchNorm normalizes each channel by that image's mean and biased
    variance over H x W: exactly what InstanceNorm2d does, in eval mode too (track_running_stats=False). So this
    is ngi's bn_mode "per_image" in a form torch.jit.freeze accepts (it needs eval mode). Batch 1 only.
    """
    def swap(module):
        for name, child in module.named_children():
            if isinstance(child, nn.BatchNorm2d):
                norm = nn.InstanceNorm2d(child.num_features, eps=child.eps, affine=True, track_running_stats=False)
                with torch.no_grad():
                    norm.weight.copy_(child.weight)
                    norm.bias.copy_(child.bias)
                setattr(module, name, norm)
            else:
                swap(child)

    swapped = copy.deepcopy(model)
    swap(swapped)
    return swapped.eval()


def fastest_generator(model, bn_mode):
    """PyTorch's fastest CPU inference form of `model` (left untouched) under `bn_mode`: eval mode (running) or
    instance_norm_equivalent (per_image), then torch.jit.script + freeze + optimize_for_inference.

    The result is specialized on first use (the profiling executor): run it a few times before timing it.
    """
    if bn_mode == "per_image":
        model = instance_norm_equivalent(model)
    elif bn_mode == "running":
        model = copy.deepcopy(model).eval()
    else:
        raise ValueError(f"bn_mode must be 'running' or 'per_image', got {bn_mode!r}")
    with torch.no_grad():
        return torch.jit.optimize_for_inference(torch.jit.freeze(torch.jit.script(model)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bn-mode", choices=("per_image", "running"), default="per_image")
    parser.add_argument("--path", choices=("eager", "fastest"), default="eager")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--width", type=int, default=1024)
    parser.add_argument("--height", type=int, default=512)
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    # Weights do not change the cost; PyTorch's default init is fine.
    model = reference_models.UnetGenerator(12, 3, num_downs=8, ngf=64, dropout="off")
    reference_models.set_bn_mode(model, args.bn_mode)
    if args.path == "fastest":
        model = fastest_generator(model, args.bn_mode)
    x = torch.rand(1, 12, args.height, args.width) * 2 - 1

    times = []
    with torch.no_grad():
        for run in range(2 + args.repeats):
            ms = time_ms(lambda: model(x))
            if run >= 2:  # the first two runs are warm-up
                times.append(ms)
            print(f"{'warm-up' if run < 2 else 'run'} {run}: {ms:.1f} ms", file=sys.stderr)
        print("sgemm 1024^3 ...", file=sys.stderr)
        gflops = sgemm_gflops()

    print(json.dumps({
        "torch_version": torch.__version__,
        "threads": torch.get_num_threads(),
        "bn_mode": args.bn_mode,
        "path": args.path,
        "input_shape": [1, 12, args.height, args.width],
        "blas": blas_info(),
        "blas_library": blas_library(),
        "generator_ms_median": statistics.median(times),
        "generator_ms_all": times,
        "sgemm_1024_gflops": gflops,
    }))


if __name__ == "__main__":
    main()

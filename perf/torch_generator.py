#!/usr/bin/python3
"""Time the thesis generator in PyTorch on the CPU: the baseline ngi is compared against.

junyanz UnetGenerator(12, 3, num_downs=8, ngf=64) on one 1024x512 image
(N=1, C=12, H=512, W=1024), torch.no_grad(), dropout off. Also measures a
1024^3 SGEMM through torch.mm, to tell how fast this torch's BLAS is.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/torch_generator.py [--bn-mode per_image|running]
           [--repeats 5] [--threads 2] [--width 1024 --height 512]
Prints one JSON object on stdout; progress goes to stderr.
"""

import argparse
import json
import os
import re
import statistics
import sys
import time

import torch

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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bn-mode", choices=("per_image", "running"), default="per_image")
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
        "input_shape": [1, 12, args.height, args.width],
        "blas": blas_info(),
        "blas_library": blas_library(),
        "generator_ms_median": statistics.median(times),
        "generator_ms_all": times,
        "sgemm_1024_gflops": gflops,
    }))


if __name__ == "__main__":
    main()

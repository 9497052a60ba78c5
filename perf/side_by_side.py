#!/usr/bin/python3
"""ngi vs PyTorch CPU on the same machine, in the same run, with the same weights and input.

1. Builds the thesis generator (junyanz UnetGenerator 12 -> 3, ngf 64, 8 downs, per-image BN, dropout off) with
   PyTorch's default init, writes it as an ngi model file and a 1024x512 input.
2. Times ngi (`ngi_bench generator`, median of --repeats, per-op breakdown) and checks its output against
   PyTorch's on that input.
3. Times PyTorch (torch.set_num_threads(2), no_grad, median of --repeats) on the same model and input.
4. Times GEMM: ngi's packed GEMM at 1024^3 and the generator's layer shapes (`ngi_bench gemm`) and OpenBLAS
   SGEMM through torch.mm at 1024^3.
Prints one JSON object with both sides and the ratios. Progress goes to stderr.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/side_by_side.py --bench build/perf/ngi_bench [--repeats 5]
           [--out FILE.json]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np
import torch

import ngi.convert as convert
import ngi.model_file as model_file
import ngi.reference_models as reference_models

import torch_generator


def run_json(cmd):
    print("$ " + " ".join(cmd), file=sys.stderr)
    done = subprocess.run(cmd, stdout=subprocess.PIPE, check=True, text=True)
    return json.loads(done.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", required=True, help="path to the ngi_bench executable")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--width", type=int, default=1024)
    parser.add_argument("--height", type=int, default=512)
    parser.add_argument("--device", default="cpu", help="ngi device spec (cpu, gpu, P:D)")
    parser.add_argument("--out", help="also write the JSON here")
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    model = reference_models.build_generator("pix2pix_unet", 12, 3, 64, 8)
    reference_models.set_bn_mode(model, "per_image")
    x = torch.rand(1, 12, args.height, args.width) * 2 - 1

    with tempfile.TemporaryDirectory() as tmp:
        model_path = os.path.join(tmp, "thesis_generator.safetensors")
        config = model_file.make_config("pix2pix_unet", bn_mode="per_image", input_nc=12, output_nc=3, ngf=64,
                                        num_downs=8, source="perf/side_by_side.py: PyTorch default init")
        model_file.write_model(model_path, convert.validate_state_dict(model.state_dict(), config), config)
        np.save(os.path.join(tmp, "input.npy"), x.numpy())

        ngi_gen = run_json([args.bench, "generator", "--model", model_path, "--input", os.path.join(tmp, "input.npy"),
                            "--output", os.path.join(tmp, "output.npy"), "--repeats", str(args.repeats),
                            "--width", str(args.width), "--height", str(args.height), "--device", args.device])
        ngi_out = np.load(os.path.join(tmp, "output.npy"))

    print("pytorch generator ...", file=sys.stderr)
    times = []
    with torch.no_grad():
        for run in range(2 + args.repeats):
            ms = torch_generator.time_ms(lambda: model(x))
            if run >= 2:
                times.append(ms)
        torch_out = model(x).numpy()
    max_diff = float(np.abs(ngi_out - torch_out).max())

    ngi_gemm = run_json([args.bench, "gemm", "--repeats", str(max(3, args.repeats)), "--device", args.device])
    print("openblas sgemm 1024^3 ...", file=sys.stderr)
    blas_gflops = torch_generator.sgemm_gflops()

    torch_ms = statistics.median(times)
    result = {
        "machine": {"cpus": os.cpu_count(), "torch": torch.__version__, "threads": torch.get_num_threads(),
                    "blas": torch_generator.blas_info(), "blas_library": torch_generator.blas_library()},
        "generator": {
            "shape": [1, 12, args.height, args.width],
            "ngi_ms_median": ngi_gen["ms_median"], "ngi_ms_all": ngi_gen["ms_all"],
            "torch_ms_median": torch_ms, "torch_ms_all": times,
            "ngi_over_torch_time": ngi_gen["ms_median"] / torch_ms,
            "max_abs_diff_vs_torch": max_diff,
            "ngi_memory_mib": ngi_gen["memory_mib"],
            "ngi_device_ms_total": ngi_gen["device_ms_total"], "gflop": ngi_gen["gflop_total"],
        },
        "gemm_1024": {"ngi_gflops": ngi_gemm["gemm_1024"]["gflops"], "openblas_gflops": blas_gflops,
                      "ngi_over_openblas": ngi_gemm["gemm_1024"]["gflops"] / blas_gflops},
        "ngi_device": ngi_gen["device"],
        "ngi_per_op": ngi_gen["per_op"],
        "ngi_gemm_layers": ngi_gemm["generator_layers"],
        "ngi_gemm_generator_total": ngi_gemm["generator_gemm_total"],
    }
    text = json.dumps(result, indent=2)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    g = result["generator"]
    print(f"generator: ngi {g['ngi_ms_median']:.0f} ms vs torch {torch_ms:.0f} ms (ratio {g['ngi_over_torch_time']:.2f}), "
          f"max |diff| {max_diff:.2e}; gemm 1024^3: ngi {result['gemm_1024']['ngi_gflops']:.0f} vs openblas "
          f"{blas_gflops:.0f} GFLOP/s", file=sys.stderr)


if __name__ == "__main__":
    main()

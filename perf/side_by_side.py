#!/usr/bin/python3
"""ngi vs PyTorch CPU (eager and its fastest inference path), same machine, same run, same weights and input.

Cases (every one in both BN modes; --quick: the small ones only, repeats 1):
  thesis            pix2pix UnetGenerator 12 -> 3, ngf 64, 8 downs, one 1024 x 512 input    (--quick: 256 x 256)
  shipped 256x128   the shipped model's architecture (models/surround.safetensors' config through
                    ngi.model_file.read_config: 12 -> 3, ngf 32, 7 downs), one 256 x 128 input
  shipped 1024x512  the same at 1024 x 512                                                  (not with --quick)
BN modes (ngi's model config "bn_mode"): "running" = eval-mode BatchNorm with running statistics; "per_image" =
BatchNorm with the statistics of the single image (train-mode BatchNorm at batch 1). Dropout off.

Weights: PyTorch's default init for the convolutions; every BatchNorm gets a random affine (weight in [0.5, 1.5],
bias in [-0.2, 0.2]) and running statistics calibrated on another random input (one train-mode pass at momentum
1), so "running" is not an identity. The same weights go, per size, to PyTorch and (ngi.convert +
ngi.model_file, one file per BN mode) to ngi; the input is random in [-1, 1], the same for all three.

Per case:
  ngi               `ngi_bench generator` (median of --repeats after a warm-up; weights / arena / scratch device
                    memory; per-op device time and GFLOP of one profiled run)
  PyTorch eager     the nn.Module (per_image: train mode), torch.no_grad(), torch.set_num_threads(--threads)
  PyTorch fastest   torch.jit.script + torch.jit.freeze + torch.jit.optimize_for_inference (BatchNorm folded into
                    the convolutions before it, convolutions through oneDNN/MKLDNN; torch 1.13 leaves the
                    ConvTranspose2d layers as they are: slow_conv_transpose2d, im2col + BLAS). per_image: freezing needs
                    eval mode, so each BatchNorm2d becomes InstanceNorm2d(affine, no running stats, same eps,
                    same weight and bias) - the same function at batch 1; checked here against the train-mode
                    model (max |diff|, float32, and float64 where the float64 reference runs)
  eager and fastest alternate run by run after --warmups each; medians of --repeats.
  max |diff| of ngi (and of both PyTorch paths) against the float64 PyTorch reference of the model
  (ngi.reference_models.run_reference; --reference float32: PyTorch eager float32 instead).
  GFLOP/s of ngi over the whole network (ngi's GFLOP count / its median time) beside ngi's packed GEMM at 1024^3
  (`ngi_bench gemm` at the start and at the end of the run; the higher one is the roof), plus torch.mm at 1024^3.
Targets (GitHub issue 14): ngi <= 0.6 x PyTorch fastest on the thesis generator, <= 0.3 x on the shipped sizes;
whole-network GFLOP/s >= 75% of ngi's GEMM at 1024^3. The load average (os.getloadavg) is recorded at the start,
before each case and at the end: timings taken while other jobs run are noisy.

Prints one JSON object on stdout (and to --out) and a Markdown summary table on stderr with the progress.
ngi_bench runs from a private copy made at the start (a rebuild during the run changes nothing; the JSON says if one
happened). Set POCL_CACHE_DIR / NGI_CACHE_DIR in the environment to keep its kernel caches apart; it inherits them.

Usage: PYTHONPATH=build/python /usr/bin/python3 perf/side_by_side.py --bench build/perf/ngi_bench [--repeats 5]
           [--quick] [--reference float64|float32] [--threads 2] [--device cpu] [--out FILE.json]
"""

import argparse
import copy
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import tempfile
import time

import numpy as np
import torch
import torch.nn as nn

import ngi.convert as convert
import ngi.model_file as model_file
import ngi.reference_models as reference_models

import torch_generator
from bench_record import emit, git_head, load, log, relative

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
SHIPPED_MODEL = os.path.join(REPO, "models", "surround.safetensors")
BN_MODES = ("running", "per_image")
TARGET_RATIO = {"thesis": 0.6, "shipped": 0.3}   # ngi / PyTorch fastest, at most
TARGET_ROOF_FRACTION = 0.75                       # whole-network GFLOP/s / ngi GEMM 1024^3, at least


def run_json(cmd):
    log("$ " + " ".join(cmd))
    done = subprocess.run(cmd, stdout=subprocess.PIPE, check=True, text=True)
    return json.loads(done.stdout)


def fingerprint(path):
    """A binary's identity (sha256, mtime): ngi_bench embeds its kernels at build time."""
    with open(path, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    return {"path": path, "sha256": digest, "mtime": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(
        os.path.getmtime(path)))}


def snapshot(path, dest):
    """Copy the executable `path` to `dest` once it is not being written (unchanged across the copy and older
    than 5 s, as a linker in another build may be writing it); return its fingerprint."""
    for _ in range(60):
        before = fingerprint(path)
        shutil.copyfile(path, dest)
        os.chmod(dest, 0o755)
        if fingerprint(path) == before == dict(fingerprint(dest), path=path, mtime=before["mtime"]) \
                and time.time() - os.path.getmtime(path) > 5:
            return before
        time.sleep(5)
    raise RuntimeError(f"{path} kept changing; is a build writing it?")


def cases(quick):
    shipped = model_file.read_config(SHIPPED_MODEL)
    arch = {k: shipped[k] for k in ("family", "input_nc", "output_nc", "ngf", "num_downs")}
    thesis = {"family": "pix2pix_unet", "input_nc": 12, "output_nc": 3, "ngf": 64, "num_downs": 8}
    if quick:
        return [("thesis", thesis, 256, 256), ("shipped", arch, 256, 128)]
    return [("thesis", thesis, 1024, 512), ("shipped", arch, 256, 128), ("shipped", arch, 1024, 512)]


def build_weights(arch, width, height):
    """The generator with the weights described in the module docstring, in eval mode."""
    torch.manual_seed(0)
    model = reference_models.build_generator(arch["family"], arch["input_nc"], arch["output_nc"], arch["ngf"],
                                             arch["num_downs"])
    gen = torch.Generator().manual_seed(1)
    norms = [m for m in model.modules() if isinstance(m, nn.BatchNorm2d)]
    with torch.no_grad():
        for m in norms:
            m.weight.copy_(torch.rand(m.num_features, generator=gen) + 0.5)
            m.bias.copy_((torch.rand(m.num_features, generator=gen) * 2 - 1) * 0.2)
            m.momentum = 1.0
        calibration = torch.rand(1, arch["input_nc"], height, width, generator=gen) * 2 - 1
        model.train()
        model(calibration)
    for m in norms:
        m.momentum = 0.1
    return model.eval()


def time_alternating(fns, warmups, repeats):
    """Median-ready ms lists for each fn: warm-ups of each, then the fns run in turn, `repeats` rounds."""
    with torch.no_grad():
        for fn in fns:
            for _ in range(warmups):
                fn()
        times = [[] for _ in fns]
        for _ in range(repeats):
            for fn, ts in zip(fns, times):
                ts.append(torch_generator.time_ms(fn))
    return times


def max_diff(a, b):
    return float(np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64)).max())


def run_case(args, tmp, kind, arch, width, height, gemm_roof):
    name = f"{kind} {width}x{height}"
    log(f"== {name}: weights, input, references ...")
    model = build_weights(arch, width, height)
    x = torch.rand(1, arch["input_nc"], height, width, generator=torch.Generator().manual_seed(3)) * 2 - 1
    input_path = os.path.join(tmp, "input.npy")
    np.save(input_path, x.numpy())
    rows = []
    for bn_mode in BN_MODES:
        row = {"case": name, "kind": kind, "bn_mode": bn_mode, "width": width, "height": height,
               "shape": [1, arch["input_nc"], height, width],
               "arch": {k: arch[k] for k in ("input_nc", "output_nc", "ngf", "num_downs")}, "load_before": load()}
        log(f"-- {name} {bn_mode} (load {row['load_before']})")
        config = model_file.make_config(arch["family"], bn_mode=bn_mode, input_nc=arch["input_nc"],
                                        output_nc=arch["output_nc"], ngf=arch["ngf"], num_downs=arch["num_downs"],
                                        source="perf/side_by_side.py: default init, random BatchNorm")
        model_path = os.path.join(tmp, f"generator_{bn_mode}.safetensors")
        model_file.write_model(model_path, convert.validate_state_dict(model.state_dict(), config), config)

        output_path = os.path.join(tmp, "output.npy")
        gen = run_json([args.bench, "generator", "--model", model_path, "--input", input_path, "--output",
                        output_path, "--repeats", str(args.repeats), "--width", str(width), "--height",
                        str(height), "--device", args.device])
        assert gen["model"]["bn_mode"] == bn_mode, gen["model"]
        ngi_out = np.load(output_path)
        os.remove(model_path)

        log(f"pytorch eager + fastest, {args.warmups} warm-ups + {args.repeats} runs each ...")
        eager = copy.deepcopy(model)
        reference_models.set_bn_mode(eager, bn_mode)     # per_image: train mode (updates this copy's stats only)
        fastest = torch_generator.fastest_generator(model, bn_mode)
        eager_ms, fastest_ms = time_alternating([lambda: eager(x), lambda: fastest(x)], args.warmups, args.repeats)
        with torch.no_grad():
            eager_out = eager(x).numpy()
            fastest_out = fastest(x).numpy()

        if args.reference == "float64":
            log("float64 reference ...")
            reference = reference_models.run_reference(model, x, bn_mode).numpy()
        else:
            reference = eager_out
        diffs = {"ngi_vs_reference": max_diff(ngi_out, reference),
                 "ngi_vs_torch_fastest": max_diff(ngi_out, fastest_out),
                 "torch_eager_vs_reference": max_diff(eager_out, reference),
                 "torch_fastest_vs_reference": max_diff(fastest_out, reference)}
        if bn_mode == "per_image":
            # The InstanceNorm2d form against the train-mode BatchNorm model: float32 (frozen + optimized vs
            # eager), and in float64 (the function itself, without float32 rounding), where that reference runs.
            diffs["instance_norm_vs_train_bn_float32"] = max_diff(fastest_out, eager_out)
            if args.reference == "float64":
                inorm = torch_generator.instance_norm_equivalent(model).double()
                with torch.no_grad():
                    diffs["instance_norm_vs_train_bn_float64"] = max_diff(inorm(x.double()).numpy(), reference)
                del inorm

        ngi_ms, eager_med, fastest_med = gen["ms_median"], statistics.median(eager_ms), statistics.median(fastest_ms)
        mem = gen["memory_mib"]
        ngi_gflops = gen["gflop_total"] / (ngi_ms * 1e-3)
        row.update({
            "gflop": gen["gflop_total"],
            "ngi_ms_median": ngi_ms, "ngi_ms_all": gen["ms_all"],
            "torch_eager_ms_median": eager_med, "torch_eager_ms_all": eager_ms,
            "torch_fastest_ms_median": fastest_med, "torch_fastest_ms_all": fastest_ms,
            "ngi_over_torch_fastest": ngi_ms / fastest_med, "ngi_over_torch_eager": ngi_ms / eager_med,
            "torch_fastest_over_eager": fastest_med / eager_med,
            "target_ngi_over_torch_fastest": TARGET_RATIO[kind],
            "ratio_target_met": ngi_ms / fastest_med <= TARGET_RATIO[kind],
            "ngi_gflops": ngi_gflops, "torch_fastest_gflops": gen["gflop_total"] / (fastest_med * 1e-3),
            "ngi_gflops_over_gemm_1024": ngi_gflops / gemm_roof,
            "roof_target_met": ngi_gflops / gemm_roof >= TARGET_ROOF_FRACTION,
            "max_abs_diff": diffs, "reference": args.reference,
            "reference_output": {"abs_max": float(np.abs(reference).max()), "std": float(np.std(reference))},
            "ngi_memory_mib": dict(mem, device_total=mem["weights"] + mem["arena"] + mem["scratch"]),
            "ngi_device_ms_total": gen["device_ms_total"], "ngi_per_op": gen["per_op"],
            "load_after": load(),
        })
        log(f"{name} {bn_mode}: ngi {ngi_ms:.1f} ms, eager {eager_med:.1f} ms, fastest {fastest_med:.1f} ms, "
            f"ngi/fastest {row['ngi_over_torch_fastest']:.2f}, max |diff| {diffs['ngi_vs_reference']:.2e}")
        rows.append(row)
    return rows, gen["device"]


def table(result):
    roof = result["gemm_1024"]["ngi_roof_gflops"]
    lines = ["| case | BN | ngi ms | eager ms | fastest ms | ngi / fastest (target) | ngi max diff | "
             "ngi GFLOP/s (of GEMM roof %.0f) | ngi weights + arena + scratch MiB |" % roof,
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in result["cases"]:
        m = r["ngi_memory_mib"]
        lines.append(f"| {r['case']} | {r['bn_mode']} | {r['ngi_ms_median']:.1f} | {r['torch_eager_ms_median']:.1f} "
                     f"| {r['torch_fastest_ms_median']:.1f} | {r['ngi_over_torch_fastest']:.2f} "
                     f"(<= {r['target_ngi_over_torch_fastest']}: {'met' if r['ratio_target_met'] else 'not met'}) "
                     f"| {r['max_abs_diff']['ngi_vs_reference']:.1e} "
                     f"| {r['ngi_gflops']:.0f} ({100 * r['ngi_gflops_over_gemm_1024']:.0f}%) "
                     f"| {m['weights']:.1f} + {m['arena']:.1f} + {m['scratch']:.1f} = {m['device_total']:.1f} |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", required=True, help="path to the ngi_bench executable")
    parser.add_argument("--repeats", type=int, help="timed runs per case and side (default 5; --quick: 1)")
    parser.add_argument("--warmups", type=int, default=2, help="PyTorch warm-up runs per path (ngi_bench: 1)")
    parser.add_argument("--threads", type=int, default=2, help="torch.set_num_threads")
    parser.add_argument("--device", default="cpu", help="ngi device spec (cpu, gpu, P:D)")
    parser.add_argument("--quick", action="store_true", help="smoke run: small sizes, repeats 1")
    parser.add_argument("--reference", choices=("float64", "float32"), default="float64",
                        help="what the max |diff| is measured against: PyTorch in float64, or PyTorch eager float32")
    parser.add_argument("--out", help="also write the JSON here")
    args = parser.parse_args()
    if args.repeats is None:
        args.repeats = 1 if args.quick else 5

    start, start_load = time.time(), load()
    torch.set_num_threads(args.threads)
    log(f"load average at start: {start_load}")
    rows, device = [], None
    with tempfile.TemporaryDirectory() as tmp:
        # Run a private copy (the binary is self-contained, kernels embedded): a rebuild of --bench during the
        # run then changes nothing here. The original's fingerprint at the start and the end tells if one happened.
        args.bench_original, args.bench = args.bench, os.path.join(tmp, "ngi_bench")
        bench_start = snapshot(args.bench_original, args.bench)
        gemm_cmd = [args.bench, "gemm", "--repeats", str(max(3, args.repeats)), "--device", args.device]
        gemm_start = run_json(gemm_cmd)
        log("torch.mm 1024^3 ...")
        torch_mm_gflops = torch_generator.sgemm_gflops()
        roof = gemm_start["gemm_1024"]["gflops"]

        for kind, arch, width, height in cases(args.quick):
            case_rows, device = run_case(args, tmp, kind, arch, width, height, roof)
            rows += case_rows

        gemm_end = run_json(gemm_cmd)
    bench_end = fingerprint(args.bench_original)
    if bench_end["sha256"] != bench_start["sha256"]:
        log(f"note: {args.bench_original} was rebuilt during the run ({bench_start['mtime']} -> "
            f"{bench_end['mtime']}); this run used a copy of the one from the start")
    roof = max(roof, gemm_end["gemm_1024"]["gflops"])
    for r in rows:  # against the higher of the two GEMM measurements
        r["ngi_gflops_over_gemm_1024"] = r["ngi_gflops"] / roof
        r["roof_target_met"] = r["ngi_gflops_over_gemm_1024"] >= TARGET_ROOF_FRACTION

    result = {
        "machine": {"cpus": os.cpu_count(), "torch": torch.__version__, "threads": torch.get_num_threads(),
                    "mkldnn": torch.backends.mkldnn.is_available(), "blas": torch_generator.blas_info(),
                    "blas_library": torch_generator.blas_library()},
        "ngi_bench": {"used": bench_start, "at_end": bench_end,
                      "rebuilt_during_run": bench_end["sha256"] != bench_start["sha256"]},
        "git_head": git_head(),
        "settings": {"quick": args.quick, "repeats": args.repeats, "torch_warmups": args.warmups,
                     "reference": args.reference, "ngi_device_spec": args.device,
                     "pocl_cache_dir": relative(os.environ["POCL_CACHE_DIR"]) if "POCL_CACHE_DIR" in os.environ
                     else None,
                     "ngi_cache_dir": relative(os.environ["NGI_CACHE_DIR"]) if "NGI_CACHE_DIR" in os.environ
                     else None},
        "targets": {"ngi_over_torch_fastest": TARGET_RATIO, "ngi_gflops_over_gemm_1024": TARGET_ROOF_FRACTION},
        "load_average": {"start": start_load, "end": load()},
        "wall_seconds": time.time() - start,
        "ngi_device": device,
        "gemm_1024": {"ngi_gflops_start": gemm_start["gemm_1024"]["gflops"],
                      "ngi_gflops_end": gemm_end["gemm_1024"]["gflops"], "ngi_roof_gflops": roof,
                      "torch_mm_gflops": torch_mm_gflops},
        "cases": rows,
        "ngi_gemm_layers": gemm_start["generator_layers"],
        "ngi_gemm_generator_total": gemm_start["generator_gemm_total"],
    }
    result["summary_table"] = table(result)
    emit(result, args.out)
    log("\n".join(result["summary_table"]))
    log(f"gemm 1024^3: ngi {result['gemm_1024']['ngi_gflops_start']:.0f} / {result['gemm_1024']['ngi_gflops_end']:.0f}"
        f" GFLOP/s (start / end), torch.mm {torch_mm_gflops:.0f}; load {start_load} -> "
        f"{result['load_average']['end']}; {result['wall_seconds']:.0f} s")


if __name__ == "__main__":
    main()

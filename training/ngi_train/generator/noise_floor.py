#!/usr/bin/python3
"""The noise floor of a path-traced reference: two independent renders of the same frame (same camera, light and
spp; different random seeds), scored against each other exactly like `ngi lightmap` scores a model (tone-mapped
final images = lighting x albedo + emission + env, ACES, sRGB, data range 1; linear lightmaps, data range = the
first render's maximum). No model can be measured more finely than this against such a reference.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.noise_floor \\
        --dataset DATA --frames 5 --out noise.json

For every test scene of DATA, its first --frames frames are rendered again with `ngi render --seed` (the
dataset's seed + 7919) at the split's reference spp and compared with the dataset's reference; the two renders'
direct-light features (at the dataset's feature_spp) measure that feature's noise too (relative RMS noise of one
estimate, over all six faces). Each second render is kept under --work, so an interrupted run resumes.
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.scoring as scoring
from ngi_train import ngi_paths


def compare_frames(device, a_dir, b_dir):
    """Scores of frame b's reference against frame a's (the same frame, rendered twice)."""
    a, b = ngi.read_frame(a_dir), ngi.read_frame(b_dir)
    pipe = ngi.Pipeline(device, a.n)
    fa, fb = scoring.display(pipe, a, a.reference), scoring.display(pipe, a, b.reference)
    final = ngi.compare_images(device, fb, fa, 1.0)
    peak = float(np.max(a.reference))
    light = ngi.compare_images(device, b.reference, a.reference, max(peak, 1e-12))
    # The direct-light feature's noise (all six faces): the RMS difference of two independent estimates is
    # sqrt(2) x the per-estimate noise; relative to the mean direct light.
    da, db = a.feature("direct"), b.feature("direct")
    rel = float(np.sqrt(np.mean((da.astype(np.float64) - db) ** 2) / 2.0) / max(float(np.mean(da)), 1e-12))
    return {"final_ldr": {k: final[k] for k in ("mse", "psnr", "ssim")},
            "lightmap_linear": {k: light[k] for k in ("mse", "psnr", "ssim")},
            "direct_feature_relative_noise": rel}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", required=True, type=Path)
    ap.add_argument("--frames", type=int, default=5, help="frames per test scene")
    ap.add_argument("--work", type=Path, default=None, help="second renders (default DATASET/noise_floor)")
    ap.add_argument("--out", type=Path, required=True, help="JSON summary")
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None, help="the ngi binary (default: found by ngi_paths)")
    args = ap.parse_args(argv)
    cfg = json.loads((args.dataset / "dataset.json").read_text())
    spp = cfg.get("test_reference_spp") or cfg["reference_spp"]
    work = args.work or args.dataset / "noise_floor"
    work.mkdir(parents=True, exist_ok=True)
    jobs = []
    for scene_dir in sorted((args.dataset / "test").iterdir()):
        info = json.loads((scene_dir / "scene.json").read_text())
        for fi in info["frame_info"][: args.frames]:
            jobs.append((scene_dir, info, fi))
    dev = ngi.Device(args.device)
    rows = []
    for scene_dir, info, fi in tqdm.tqdm(jobs, desc="noise floor", unit="frame"):
        a = scene_dir / f"{fi['frame']:04d}"
        b = work / scene_dir.name / f"{fi['frame']:04d}"
        if not (b / "camera.json").exists():
            b.parent.mkdir(parents=True, exist_ok=True)
            subprocess.run([ngi_paths.find_ngi(args.ngi), "render", "--scene", info["spec"], "--out", str(b),
                            "--frame", str(fi["frame"]), "--path-frames", str(info["frames"]),
                            "--face", str(cfg["n"]), "--spp", str(spp), "--feature-spp", str(cfg["feature_spp"]),
                            "--bounces", str(cfg["max_bounces"]), "--time", str(fi["time"]),
                            "--seed", str((fi["seed"] + 7919) % 2147483647), "--device", args.device],
                           check=True, stdout=subprocess.DEVNULL, env=ngi_paths.ngi_env())
        rows.append({"scene": scene_dir.name, "frame": fi["frame"], **compare_frames(dev, a, b)})
    mean = lambda key, m: float(np.mean([r[key][m] for r in rows]))
    summary = {"dataset": str(args.dataset), "n": cfg["n"], "reference_spp": spp, "frames": len(rows),
               "seed_offset": 7919,
               "final_ldr": {m: mean("final_ldr", m) for m in ("mse", "psnr", "ssim")},
               "lightmap_linear": {m: mean("lightmap_linear", m) for m in ("mse", "psnr", "ssim")},
               "feature_spp": cfg["feature_spp"],
               "direct_feature_relative_noise": float(np.mean([r["direct_feature_relative_noise"] for r in rows])),
               "per_frame": rows, "written": time.strftime("%Y-%m-%dT%H:%M:%S")}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: summary[k] for k in ("n", "reference_spp", "frames", "final_ldr", "lightmap_linear",
                                              "feature_spp", "direct_feature_relative_noise")}))


if __name__ == "__main__":
    sys.exit(main())

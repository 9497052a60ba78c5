#!/usr/bin/python3
"""Held-out evaluation: in PyTorch (during training and for export's bn_mode choice) and with ngi itself.

heldout_scores() runs the generator as ngi will (ngi.reference_models.UnetGenerator, bn_mode running or per_image,
dropout off or seeded) over held-out frames and scores its front view (in the indirect output mode: the composed
lightmap direct + indirect, encoded like the target; lightmap_loss.py) against the target:
  l1          mean |G(x)_front - y| in the model's [-1, 1] output encoding (the L1 term of the training loss)
  psnr_enc    PSNR of the same, on the [0, 1] Reinhard-encoded scale (data range 1)
  mse_linear  mean squared error of the decoded linear lightmaps (x = e / (1 - e)), capped at 65504 like ngi

As a command, it evaluates an exported model with the C++ pipeline end to end: `ngi lightmap` on every frame
of a split, and a summary of the per-frame metrics.json files (tone-mapped final images and linear lightmaps,
the network against the direct-only baseline):

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.evaluate \\
        --model M.safetensors --dataset DATA \\
        --split test --out DIR

Under torchrun (`/usr/bin/python3 -m ngi_train.torchrun --nproc_per_node W --module ngi_train.generator.evaluate
...`) the
frames are split round robin over the W ranks and rank 0 writes the merged summary.json and per_frame.json,
identical to a single process's.
"""

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import torch

import ngi.reference_models as reference_models
from ngi import _constants

from ngi_train import distributed, ngi_paths
from ngi_train.generator import data, gan, lightmap_loss, networks

LIGHT_MAX = _constants.LIGHT_MAX  # compose.cl's cap of decoded light


def decode(v):
    """front_lightmap's decoding (kernels/compose.cl decode_lightmap) in float64, output range [-1, 1]."""
    e = np.clip((np.asarray(v, np.float64) + 1.0) / 2.0, 0.0, 1.0)
    with np.errstate(divide="ignore"):
        return np.where(e < 1.0, np.minimum(e / np.maximum(1.0 - e, 1e-300), LIGHT_MAX), LIGHT_MAX)


def heldout_scores(state_dict, cfg, dataset, n, bn_mode, dropout="off", dropout_seed=0, max_frames=0, dist=None):
    """Scores (see the module doc) of generator weights `state_dict` on a FrameDataset, averaged over frames.
    dist (distributed.Dist, collective): the frames are split round robin over the ranks and the per-frame scores
    gathered and summed in frame order, so every rank gets exactly what one process computes."""
    d = dist or distributed.Dist()
    g = networks.inference_generator({k: v.cpu() for k, v in state_dict.items()}, data.input_nc(cfg["layout"]), 3,
                                     cfg["ngf"], cfg["num_downs"], dropout=dropout, dropout_seed=dropout_seed)
    reference_models.set_bn_mode(g, bn_mode)
    count = len(dataset) if not max_frames else min(max_frames, len(dataset))
    mine = []
    with torch.no_grad():
        for i in d.shard(range(count)):
            x, y, _ = dataset[i]
            out = data.crop_front(gan.residual_output(g(x[None]), x[None], cfg["layout"]), n, cfg["layout"])[0]
            mode = cfg.get("output_mode", "lightmap")
            if mode != "lightmap":
                direct = dataset.front(i)[data.FRONT["direct"]].double()
                out = lightmap_loss.encode(lightmap_loss.lightmap(out.double(), direct, mode))
            out = out.numpy().astype(np.float64)
            y = y.numpy().astype(np.float64)
            mine.append((np.abs(out - y).mean(), (((out - y) / 2.0) ** 2).mean(),
                         ((decode(out) - decode(y)) ** 2).mean()))
    l1 = mse_enc = mse_lin = 0.0
    for a, b, c in d.unshard(d.all_gather(mine), count):
        l1 += a
        mse_enc += b
        mse_lin += c
    l1, mse_enc, mse_lin = l1 / count, mse_enc / count, mse_lin / count
    return {"frames": count, "l1": l1, "psnr_enc": 10 * math.log10(1.0 / mse_enc) if mse_enc > 0 else None,
            "mse_linear": mse_lin}


# --------------------------------------------------------------------------
# End to end with ngi lightmap
# --------------------------------------------------------------------------

def _mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


WHO = ("network", "direct_only")
SPACES = ("final_ldr", "lightmap_linear")
METRICS = ("mse", "psnr", "ssim")


def summarize(metrics_list):
    """Mean of every metric over a list of `ngi lightmap` metrics.json dicts: {who: {space: {metric: mean}}}.
    PSNR is averaged per frame (None, i.e. identical images, is left out), like the thesis's per-frame means."""
    return {who: {space: {m: _mean([f[who][space][m] for f in metrics_list]) for m in METRICS} for space in SPACES}
            for who in WHO}


def run_lightmap(ngi, frame_dir, model, dest, device=None, resume=False):
    """`ngi lightmap` of one frame into `dest`; returns (its metrics.json as a dict, wall seconds or None when
    resume found the frame done: dest/metrics.json exists, written last by ngi lightmap)."""
    dest = Path(dest)
    if resume and (dest / "metrics.json").is_file():
        return json.loads((dest / "metrics.json").read_text()), None
    cmd = [ngi, "lightmap", "--frame", str(frame_dir), "--model", str(model), "--out", str(dest)]
    if device:
        cmd += ["--device", device]
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=ngi_paths.ngi_env())
    seconds = time.monotonic() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stdout}{proc.stderr}")
    return json.loads((dest / "metrics.json").read_text()), seconds


def evaluate_with_ngi(ngi, model, dataset_dir, split, out_dir, max_frames=0, device=None, log=sys.stderr,
                      resume=False, on_frame=None, dist=None):
    """`ngi lightmap` on every frame of a split (or max_frames spread evenly over it) into out_dir/<frame>/, then
    out_dir/summary.json and per_frame.json. resume: frames whose metrics.json exists are not run again.
    on_frame(k, total, rel, seconds) replaces the per-frame log line (seconds is None for a resumed frame).
    dist (distributed.Dist, collective): rank r runs the frames r, r + W, ... (each frame folder is written by one
    rank); rank 0 gathers the metrics, puts them back in frame order and alone writes summary.json and
    per_frame.json, the same files one process writes. Every rank returns the summary."""
    d = dist or distributed.Dist()
    frames = data.select_frames(data.list_frames(dataset_dir, split), max_frames)
    out_dir = Path(out_dir)
    mine = []
    for k, rel in enumerate(d.shard(frames)):
        metrics, seconds = run_lightmap(ngi, Path(dataset_dir) / rel, model, out_dir / rel, device, resume)
        mine.append(metrics)
        if on_frame:
            on_frame(k + 1, len(frames), rel, seconds)
        else:
            who = f"rank {d.rank}: " if d.enabled else ""
            print(f"{who}lightmap {d.rank + k * d.world + 1}/{len(frames)} {rel}", file=log, flush=True)
    per_frame = dict(zip(frames, d.unshard(d.all_gather(mine), len(frames))))
    summary = {"model": str(model), "dataset": str(dataset_dir), "split": split, "frames": len(frames)}
    summary.update(summarize(list(per_frame.values())))
    if d.main:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        (out_dir / "per_frame.json").write_text(json.dumps(per_frame, indent=1) + "\n")
    return summary


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True, help="exported .safetensors model")
    ap.add_argument("--dataset", required=True, help="dataset folder (ngi dataset --out)")
    ap.add_argument("--split", default="test")
    ap.add_argument("--out", required=True, help="folder for per-frame outputs, summary.json, per_frame.json")
    ap.add_argument("--max-frames", type=int, default=0, help="K frames spread evenly over the split (0 = all)")
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN or build*/ngi)")
    ap.add_argument("--device", help="ngi --device")
    ap.add_argument("--resume", action="store_true", help="keep frames whose OUT/<frame>/metrics.json exists")
    args = ap.parse_args()
    d = distributed.init()  # under torchrun: the frames split over the ranks, one merged JSON (rank 0)
    try:
        summary = evaluate_with_ngi(ngi_paths.find_ngi(args.ngi), args.model, args.dataset, args.split, args.out,
                                    args.max_frames, args.device, resume=args.resume, dist=d)
    finally:
        d.close()
    if not d.main:
        return
    print(f"{'':12s} {'final_ldr (SSIM / MSE / PSNR)':>36s}   {'lightmap_linear (SSIM / PSNR)':>30s}")
    for who in ("network", "direct_only"):
        f, l = summary[who]["final_ldr"], summary[who]["lightmap_linear"]
        fmt = lambda v, spec: "-" if v is None else format(v, spec)  # noqa: E731
        print(f"{who:12s} {fmt(f['ssim'], '.5f'):>12s} {fmt(f['mse'], '.5f'):>10s} {fmt(f['psnr'], '.3f'):>10s}   "
              f"{fmt(l['ssim'], '.5f'):>14s} {fmt(l['psnr'], '.3f'):>14s}")
    print(f"summary: {Path(args.out) / 'summary.json'}")


if __name__ == "__main__":
    main()

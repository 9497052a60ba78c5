#!/usr/bin/python3
"""Train seed 002's network (ngi.neural_gi.NeuralGI) on one static scene of an `ngi dataset` and export it.

    PYTHONPATH=training:build/python nice -n 10 /usr/bin/python3 -m ngi_train.neural_gi.train \\
        --dataset data/neural_gi_bleed --work /tmp/ngi_bleed --out models/neural_gi_bleed.safetensors --steps 100000

Data (data.py): the scene's frames, front face only; by default its last --test-frames frames are held out (the
dataset generator keeps one scene in one split, see data.split_frames; --test-split takes another split's frames
instead). Sky pixels (planar depth >= 5e3, the renderer writes 1e4) are left out of the loss; their inputs are
assembled like every other pixel's, as ngi's kernel does (data.py). Frames are decoded once into --cache (default WORK/cache) as .npy.

Training (the paper's section 3.7): Adam, lr 1e-4, betas (0.9, 0.999), batch 1 image, loss = log-L1 (Eq. 6,
ngi.neural_gi.log_l1_loss) of final = L_d + L* against the reference over the surface pixels. Each epoch visits
every training frame once in an order that depends only on (seed, epoch). BatchNorm trains in PyTorch's training
mode (batch 1: per-image statistics) and the file is exported with bn_mode "per_image", which is how ngi runs it;
held-out losses are computed the same way (per-image statistics, the running statistics left untouched).

--unet-only: the paper's "[72]-net" baseline, ngi's pix2pix U-Net alone (linear, 3 channels, exp decoding) on the same
inputs and data, exported as an exactly equivalent neural_gi file (networks.py: buffer = the U-Net with C_B 3, an MLP
of 6 ReLU units that passes it through).

--no-buffer: the baseline without the CNN neural buffer (the MLP on [I, Gamma(I)] only, Table 4's "MLP only").
It is exported as an exactly equivalent neural_gi file (networks.py): a 1-channel U-Net (ngf 8, num_downs 5) whose
channel the MLP gives zero weight (so the buffer's value never matters), because the neural_gi family has no
buffer-less form.

The work folder holds checkpoint.pt (every --checkpoint-every steps, at the end and on SIGINT / SIGTERM: the
step finishes, a checkpoint is written atomically (ngi_train.checkpoint), exit 130 / 143), run.json and
log.jsonl (every --log-every steps: {"step", "train_loss" (mean of those steps), "seconds" (training wall time)};
every --eval-every steps also "heldout_loss" over --eval-frames fixed held-out frames and "train_eval_loss" over
as many fixed training frames). Running the same command again resumes, bit for bit on the same machine and
thread count; --steps, the logging and checkpoint cadences and --threads may change on resume, nothing else.
At the end: the F16 model file (ngi.neural_gi.export_model; --f32 for F32) with the scene box [0,0,0]..grid size
(metres; see data.py): as neural_gi.scene_box {"min", "max"} when export_model takes a scene_box (the version
whose NeuralGiRenderer reads it), else under the config's "training" object (training.scene_box); the run's
settings and the sky threshold under "training" either way.
"""

import argparse
import contextlib
import inspect
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from tqdm import tqdm

import ngi.neural_gi as ng

from ngi_train import checkpoint, ngi_paths
from ngi_train.neural_gi import data
from ngi_train.neural_gi.networks import build, no_buffer_as_neural_gi, unet_as_neural_gi

RESUMABLE = {"steps", "log_every", "eval_every", "checkpoint_every", "threads"}


@contextlib.contextmanager
def per_image_bn(net):
    """Evaluation as ngi runs a bn_mode "per_image" file: BatchNorm with this image's statistics, the running
    statistics neither used nor updated; no grad."""
    bns = [m for m in net.modules() if isinstance(m, nn.modules.batchnorm._BatchNorm)]
    saved = [(m.training, m.track_running_stats) for m in bns]
    was = net.training
    net.eval()
    for m in bns:
        m.training, m.track_running_stats = True, False
    try:
        with torch.no_grad():
            yield
    finally:
        net.train(was)
        for m, (t, r) in zip(bns, saved):
            m.training, m.track_running_stats = t, r


def mean_loss(net, items):
    if not items:
        return None
    total = 0.0
    with per_image_bn(net):
        for x, direct, ref, mask in items:
            final, _ = net.render(x, direct)
            total += float(data.masked_log_l1(final, ref, mask))
    return total / len(items)


def select(items, count):
    """`count` items spread evenly over the list (all when count is 0 or >= len)."""
    if not count or count >= len(items):
        return list(range(len(items)))
    if count == 1:
        return [0]
    return [round(i * (len(items) - 1) / (count - 1)) for i in range(count)]


def scene_metadata(bbox_min, bbox_max):
    return {"scene_box": {"min": list(map(float, bbox_min)), "max": list(map(float, bbox_max)),
                          "source": "the dataset scene's scene.json size (grid blocks = metres), min = origin"},
            "sky": {"depth_min": data.SKY_DEPTH_MIN, "inputs": "assembled as on surfaces (depth 1e4)",
                    "note": "pixels with planar depth >= depth_min are out of the loss; lighting there is 0"}}


def export(net, config, bbox_min, bbox_max, out, half, source, extra=None):
    """Write the model file; returns its config as written."""
    if config.get("unet_only"):
        full = unet_as_neural_gi(net)
    else:
        full = no_buffer_as_neural_gi(net) if config["no_buffer"] else net
    meta = dict(scene_metadata(bbox_min, bbox_max),
                run=dict(extra or {}, no_buffer=config["no_buffer"], unet_only=bool(config.get("unet_only"))))
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    if "scene_box" in inspect.signature(ng.export_model).parameters:  # the box as a field of the format
        full.scene = None
        ng.export_model(full, str(out), bn_mode="per_image", half=half, source=source,
                        scene_box=(bbox_min, bbox_max), training=meta)
    else:  # older ngi.neural_gi: through config(), which file_config keeps under "training"
        full.scene = meta
        ng.export_model(full, str(out), bn_mode="per_image", half=half, source=source)
    return full


def box_of_config(config):
    """(min, max) of a model file's config: neural_gi.scene_box, else training.scene_box; None if neither."""
    box = config.get("neural_gi", {}).get("scene_box") or config.get("training", {}).get("scene_box")
    return (box["min"], box["max"]) if box else None


# --------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------

def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, type=Path, help="an `ngi dataset` folder")
    ap.add_argument("--scene", help="scene folder name (default: the split's only scene)")
    ap.add_argument("--split", default="train")
    ap.add_argument("--test-frames", type=int, default=100, help="the scene's last frames held out (default 100)")
    ap.add_argument("--test-split", help="take the held-out frames from this split's scene folder instead")
    ap.add_argument("--work", required=True, type=Path, help="checkpoints and logs (resumed when it has one)")
    ap.add_argument("--cache", type=Path, help="decoded frames (default WORK/cache)")
    ap.add_argument("--out", required=True, type=Path, help="the ngi model file written at the end")
    ap.add_argument("--f32", action="store_true", help="store F32 weights (default F16)")
    ap.add_argument("--steps", type=int, default=100000)
    ap.add_argument("--lr", type=float, default=1e-4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--buffer-channels", type=int, default=ng.DEFAULT_BUFFER_CHANNELS)
    ap.add_argument("--ngf", type=int, default=ng.DEFAULT_NGF)
    ap.add_argument("--num-downs", type=int, default=ng.DEFAULT_NUM_DOWNS)
    ap.add_argument("--mlp-width", type=int, default=ng.DEFAULT_MLP_WIDTH)
    ap.add_argument("--mlp-depth", type=int, default=ng.DEFAULT_MLP_DEPTH)
    ap.add_argument("--skip-layer", type=int, default=ng.DEFAULT_SKIP_LAYER, help="0: no re-injection")
    ap.add_argument("--no-buffer", action="store_true", help="baseline: the MLP without the CNN neural buffer")
    ap.add_argument("--unet-only", action="store_true",
                    help="baseline: ngi's U-Net alone on the same inputs (the paper's [72]-net; --ngf, --num-downs; "
                         "the buffer and MLP options are not used)")
    ap.add_argument("--log-every", type=int, default=100)
    ap.add_argument("--eval-every", type=int, default=1000)
    ap.add_argument("--eval-frames", type=int, default=8, help="held-out (and training) frames of the curve")
    ap.add_argument("--checkpoint-every", type=int, default=500)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    if a.no_buffer and a.unet_only:
        ap.error("--no-buffer and --unet-only are two different baselines: pass one")
    if a.steps < 0 or a.log_every < 1 or a.eval_every < 1 or a.checkpoint_every < 1:
        ap.error("--steps must be >= 0; --log-every, --eval-every and --checkpoint-every >= 1")
    return a


def main(argv=None):
    a = parse_args(argv)
    torch.set_num_threads(a.threads)
    torch.use_deterministic_algorithms(True)
    scene_dir, train_frames, test_frames = data.split_frames(a.dataset, a.scene, a.test_frames, a.split,
                                                             a.test_split)
    cache = a.cache or a.work / "cache"
    train_data = data.SceneData(train_frames, scene_dir, cache, "train")
    test_data = data.SceneData(test_frames, scene_dir, cache, "test") if test_frames else None
    arch = {"buffer_channels": a.buffer_channels, "ngf": a.ngf, "num_downs": a.num_downs, "mlp_width": a.mlp_width,
            "mlp_depth": a.mlp_depth, "skip_layer": a.skip_layer}
    config = {"arch": arch, "no_buffer": a.no_buffer, "lr": a.lr, "seed": a.seed, "half": not a.f32,
              "steps": a.steps, "log_every": a.log_every, "eval_every": a.eval_every,
              "eval_frames": a.eval_frames, "checkpoint_every": a.checkpoint_every, "threads": a.threads,
              "scene": str(scene_dir.resolve()), "train_frames": [f.name for f in train_frames],
              "test_frames": [f"{f.parent.parent.name}/{f.name}" for f in test_frames]}
    if a.unet_only:  # only when set: checkpoints of the other models resume unchanged
        config["unet_only"] = True

    a.work.mkdir(parents=True, exist_ok=True)
    ckpt = a.work / "checkpoint.pt"
    net = build(config)
    net.train()
    opt = torch.optim.Adam(net.parameters(), lr=a.lr, betas=(0.9, 0.999))
    step, train_seconds = 0, 0.0
    if ckpt.is_file():
        state = checkpoint.load(ckpt)
        checkpoint.check_resumable(state["config"], config, RESUMABLE, a.work)
        net.load_state_dict(state["model"])
        opt.load_state_dict(state["optimizer"])
        torch.set_rng_state(state["torch_rng"])
        step, train_seconds = state["step"], state["train_seconds"]

    n_params = sum(p.numel() for p in net.parameters())
    eval_train = [train_data[i] for i in select(train_data.frames, a.eval_frames)]
    eval_test = [test_data[i] for i in select(test_data.frames, a.eval_frames)] if test_data else []
    run = {"config": config, "parameters": n_params, "n": train_data.n, "scene_box": [train_data.bbox_min,
           train_data.bbox_max], "train": len(train_data), "test": len(test_data) if test_data else 0,
           "threads": torch.get_num_threads(), "torch": torch.__version__}
    (a.work / "run.json").write_text(json.dumps(run, indent=1) + "\n")
    log_path = a.work / "log.jsonl"
    checkpoint.rewrite_log(log_path, step)

    def save(step):
        checkpoint.save(ckpt, {"model": net.state_dict(), "optimizer": opt.state_dict(), "step": step,
                               "train_seconds": train_seconds, "torch_rng": torch.get_rng_state(),
                               "config": config, "scene_box": [train_data.bbox_min, train_data.bbox_max]})

    kind = "no-buffer MLP" if a.no_buffer else "U-Net only" if a.unet_only else "NeuralGI"
    print(f"neural_gi {kind}: {n_params:,} parameters; {scene_dir.name}: {len(train_data)} train frames, "
          f"{run['test']} held out, N = {train_data.n}; {torch.get_num_threads()} thread(s); "
          + (f"resuming at step {step}" if step else "from scratch") + f", {a.steps} steps",
          file=sys.stderr, flush=True)
    losses = []

    def advance(step, stop):
        nonlocal train_seconds, losses
        epoch, k = divmod(step, len(train_data))
        x, direct, ref, mask = train_data[int(checkpoint.epoch_order(a.seed, epoch, len(train_data))[k])]
        t0 = time.monotonic()
        opt.zero_grad(set_to_none=True)
        final, _ = net.render(x, direct)
        loss = data.masked_log_l1(final, ref, mask)
        loss.backward()
        opt.step()
        train_seconds += time.monotonic() - t0
        step += 1
        value = loss.item()
        if not math.isfinite(value):
            raise FloatingPointError(f"step {step}: the loss is {value}")
        losses.append(value)
        if step % a.log_every == 0 or step % a.eval_every == 0 or step == a.steps:
            line = {"step": step, "train_loss": float(np.mean(losses)), "seconds": round(train_seconds, 3)}
            if step % a.eval_every == 0 or step == a.steps:
                line["heldout_loss"] = mean_loss(net, eval_test)
                line["train_eval_loss"] = mean_loss(net, eval_train)
                bar.set_postfix({"heldout": f"{line['heldout_loss'] or float('nan'):.4f}"}, refresh=False)
            log.write(json.dumps(line) + "\n")
            log.flush()
            losses = []
        bar.update(step - bar.n)
        return stop.requested

    with open(log_path, "a") as log, tqdm(total=a.steps, initial=min(step, a.steps), unit="step",
                                          desc=f"neural_gi {scene_dir.name}", **ngi_paths.progress_options()) as bar:
        step, exit_code = checkpoint.run_steps(step, a.steps, advance, save, a.checkpoint_every, ckpt)
    if exit_code:
        return exit_code
    if not ckpt.is_file():
        save(step)

    result = {"step": step, "train_seconds": round(train_seconds, 3),
              "steps_per_second": step / train_seconds if train_seconds > 0 else None,
              "heldout_loss": mean_loss(net, eval_test), "train_eval_loss": mean_loss(net, eval_train),
              "out": str(a.out)}
    flag = " --no-buffer" if a.no_buffer else " --unet-only" if a.unet_only else ""
    export(net, config, train_data.bbox_min, train_data.bbox_max, a.out, not a.f32,
           f"ngi_train.neural_gi.train{flag} on {scene_dir.name} ({step} steps)",
           extra={"dataset_scene": scene_dir.name, "steps": step, "lr": a.lr, "seed": a.seed,
                  "train_frames": len(train_data), "heldout_frames": run["test"], "heldout_loss": result["heldout_loss"],
                  "train_seconds": result["train_seconds"]})
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

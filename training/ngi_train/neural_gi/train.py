#!/usr/bin/python3
"""Train seed 002's network (ngi.neural_gi.NeuralGI) on one static scene of an `ngi dataset` and export it.

    PYTHONPATH=build/python nice -n 10 /usr/bin/python3 training/neural_gi/train.py \\
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
inputs and data, exported as an exactly equivalent neural_gi file (buffer = the U-Net with C_B 3, an MLP of 6 ReLU
units that passes it through: unet_as_neural_gi).

--no-buffer: the baseline without the CNN neural buffer (the MLP on [I, Gamma(I)] only, Table 4's "MLP only").
It is exported as an exactly equivalent neural_gi file: a 1-channel U-Net (ngf 8, num_downs 5) whose channel the
MLP gives zero weight (so the buffer's value never matters), because the neural_gi family has no buffer-less form.

The work folder holds checkpoint.pt (every --checkpoint-every steps, at the end and on SIGINT / SIGTERM: the
step finishes, a checkpoint is written atomically by training/checkpoint.py, exit 130 / 143), run.json and
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
import signal
import sys
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from tqdm import tqdm

import data
import ngi.neural_gi as ng

sys.path.append(str(Path(__file__).resolve().parents[1]))  # training/checkpoint.py (appended: data = ours)
import checkpoint  # noqa: E402

RESUMABLE = {"steps", "log_every", "eval_every", "checkpoint_every", "threads"}


# --------------------------------------------------------------------------
# Networks
# --------------------------------------------------------------------------

class SceneNeuralGI(ng.NeuralGI):
    """NeuralGI whose config() also carries the scene box and the sky convention (export_model stores config()
    under the file's "training" object)."""

    scene = None

    def config(self):
        c = super().config()
        if self.scene is not None:
            c.update(self.scene)
        return c


class IndirectFromRaw(nn.Module):
    """A baseline's forward and render as NeuralGI's: indirect = exp decoding of raw_output; final = direct + it."""

    def forward(self, inputs):
        return ng.decode_indirect(self.raw_output(inputs))

    def render(self, inputs, direct):
        indirect = self(inputs)
        return ng.sanitize_radiance(direct) + indirect, indirect


class NoBufferGI(IndirectFromRaw):
    """The baseline without the neural buffer: R on [I, Gamma(I)] (378 channels), exp decoding."""

    def __init__(self, mlp_width=ng.DEFAULT_MLP_WIDTH, mlp_depth=ng.DEFAULT_MLP_DEPTH,
                 skip_layer=ng.DEFAULT_SKIP_LAYER):
        super().__init__()
        self.mlp = ng.RenderingMLP(ng.ENCODED_CHANNELS, mlp_width, mlp_depth, skip_layer)

    def check_inputs(self, inputs):
        if inputs.dim() != 4 or inputs.shape[1] != ng.INPUT_CHANNELS:
            raise ValueError(f"inputs must be [N, {ng.INPUT_CHANNELS}, H, W], got {tuple(inputs.shape)}")

    def raw_output(self, inputs):
        self.check_inputs(inputs)
        return self.mlp(ng.positional_encoding(inputs))


def no_buffer_as_neural_gi(net, seed=0):
    """An exactly equivalent SceneNeuralGI: a 1-channel U-Net (ngf 8, num_downs 5) whose output the MLP weighs
    by 0 (first layer and the re-injection layer), every MLP weight copied."""
    torch.manual_seed(seed)
    m = net.mlp
    full = SceneNeuralGI(buffer_channels=1, ngf=8, num_downs=5, mlp_width=m.output.in_channels,
                         mlp_depth=len(m.layers), skip_layer=m.skip_layer)
    e = ng.ENCODED_CHANNELS
    with torch.no_grad():
        for i, (src, dst) in enumerate(zip(m.layers, full.mlp.layers)):
            dst.bias.copy_(src.bias)
            if i == 0:
                dst.weight.zero_()
                dst.weight[:, :e] = src.weight
            elif i == m.skip_layer:  # input [h, z] with z = [Gamma, B]
                w = src.weight.shape[1] - e
                dst.weight.zero_()
                dst.weight[:, :w + e] = src.weight
            else:
                dst.weight.copy_(src.weight)
        full.mlp.output.load_state_dict(m.output.state_dict())
    return full


class UnetOnlyGI(IndirectFromRaw):
    """The paper's "[72]-net" baseline: ngi's pix2pix U-Net alone (linear output, 3 channels) on the same 18 inputs,
    no encoding, no MLP; exp decoding as NeuralGI's, so the loss, data and schedule are the same."""

    def __init__(self, ngf=ng.DEFAULT_NGF, num_downs=ng.DEFAULT_NUM_DOWNS):
        super().__init__()
        if num_downs < 5:
            raise ValueError(f"num_downs must be >= 5 (UnetGenerator's fixed outer levels), got {num_downs}")
        self.ngf, self.num_downs = ngf, num_downs
        self.buffer = ng.LinearUnetGenerator(ng.INPUT_CHANNELS, 3, num_downs, ngf)

    def check_inputs(self, inputs):
        m = 2 ** self.num_downs
        if inputs.dim() != 4 or inputs.shape[1] != ng.INPUT_CHANNELS or inputs.shape[2] % m or inputs.shape[3] % m:
            raise ValueError(f"inputs must be [N, {ng.INPUT_CHANNELS}, H, W] with H, W multiples of {m}, "
                             f"got {tuple(inputs.shape)}")

    def raw_output(self, inputs):
        self.check_inputs(inputs)
        return self.buffer(inputs)


# The U-Net baseline's MLP in its neural_gi file: 6 ReLU units carry +B and -B, the output takes their difference.
UNET_PASS_WIDTH = 6


def unet_as_neural_gi(net):
    """An exactly equivalent SceneNeuralGI: buffer = the U-Net (C_B 3), MLP = 1 hidden layer of 6 units that passes
    the buffer through unchanged: h = relu([B, -B]), raw = h[0:3] - h[3:6] = B (weights 0 / +-1 and zero biases
    are exact in F16, and relu(b) - relu(-b) = b exactly), so the file runs the baseline in ngi as it trained."""
    full = SceneNeuralGI(buffer_channels=3, ngf=net.ngf, num_downs=net.num_downs, mlp_width=UNET_PASS_WIDTH,
                         mlp_depth=1, skip_layer=None)
    e = ng.ENCODED_CHANNELS
    with torch.no_grad():
        full.buffer.load_state_dict(net.buffer.state_dict())
        first, out = full.mlp.layers[0], full.mlp.output
        first.weight.zero_()
        first.bias.zero_()
        out.weight.zero_()
        out.bias.zero_()
        for c in range(3):
            first.weight[c, e + c, 0, 0] = 1.0
            first.weight[3 + c, e + c, 0, 0] = -1.0
            out.weight[c, c, 0, 0] = 1.0
            out.weight[c, 3 + c, 0, 0] = -1.0
    return full


def build(config):
    torch.manual_seed(config["seed"])
    a = config["arch"]
    if config.get("unet_only"):
        return UnetOnlyGI(a["ngf"], a["num_downs"])
    if config["no_buffer"]:
        return NoBufferGI(a["mlp_width"], a["mlp_depth"], a["skip_layer"] or None)
    return SceneNeuralGI(a["buffer_channels"], a["ngf"], a["num_downs"], a["mlp_width"], a["mlp_depth"],
                         a["skip_layer"] or None)


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


# --------------------------------------------------------------------------
# Logging helpers
# --------------------------------------------------------------------------

def progress_options():
    tty = sys.stderr.isatty()
    interval = 0.25 if tty else 30.0
    return {"file": sys.stderr, "mininterval": interval, "maxinterval": max(10.0, interval), "ascii": not tty,
            "dynamic_ncols": tty}


def frame_order(seed, epoch, count):
    return np.random.default_rng([seed, epoch]).permutation(count)


def select(items, count):
    """`count` items spread evenly over the list (all when count is 0 or >= len)."""
    if not count or count >= len(items):
        return list(range(len(items)))
    if count == 1:
        return [0]
    return [round(i * (len(items) - 1) / (count - 1)) for i in range(count)]


def rewrite_log(path, max_step):
    if not path.is_file():
        return
    kept = []
    for line in path.read_text().splitlines():
        try:
            if line.strip() and json.loads(line).get("step", math.inf) <= max_step:
                kept.append(line)
        except ValueError:
            pass  # a line cut short by a hard kill
    path.write_text("".join(line + "\n" for line in kept))


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
        old = state["config"]
        changed = sorted(k for k in set(old) | set(config) if old.get(k) != config.get(k) and k not in RESUMABLE)
        if changed:
            raise SystemExit(f"{a.work}: the checkpoint was trained with other settings or data: "
                             + ", ".join(f"{k} {str(old.get(k))[:60]!r} -> {str(config.get(k))[:60]!r}"
                                         for k in changed) + " (use another --work folder)")
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
    rewrite_log(log_path, step)

    def save():
        checkpoint.save(ckpt, {"model": net.state_dict(), "optimizer": opt.state_dict(), "step": step,
                               "train_seconds": train_seconds, "torch_rng": torch.get_rng_state(),
                               "config": config, "scene_box": [train_data.bbox_min, train_data.bbox_max]})

    kind = "no-buffer MLP" if a.no_buffer else "U-Net only" if a.unet_only else "NeuralGI"
    print(f"neural_gi {kind}: {n_params:,} parameters; {scene_dir.name}: {len(train_data)} train frames, "
          f"{run['test']} held out, N = {train_data.n}; {torch.get_num_threads()} thread(s); "
          + (f"resuming at step {step}" if step else "from scratch") + f", {a.steps} steps",
          file=sys.stderr, flush=True)
    stop = checkpoint.StopSignal()
    bar = tqdm(total=a.steps, initial=min(step, a.steps), unit="step", desc=f"neural_gi {scene_dir.name}",
               **progress_options())
    losses = []
    stopped = False
    try:
        with open(log_path, "a") as log:
            while step < a.steps:
                epoch, k = divmod(step, len(train_data))
                x, direct, ref, mask = train_data[int(frame_order(a.seed, epoch, len(train_data))[k])]
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
                if step % a.checkpoint_every == 0 or step == a.steps or stop.signum is not None:
                    save()
                if stop.signum is not None:
                    stopped = True
                    break
    finally:
        stop.restore()
        bar.close()
    if stopped:
        print(f"stopped at step {step}; checkpoint {ckpt} (run the same command to resume)", file=sys.stderr)
        return 128 + (stop.signum or signal.SIGTERM)
    if not ckpt.is_file():
        save()

    result = {"step": step, "train_seconds": round(train_seconds, 3),
              "steps_per_second": step / train_seconds if train_seconds > 0 else None,
              "heldout_loss": mean_loss(net, eval_test), "train_eval_loss": mean_loss(net, eval_train),
              "out": str(a.out)}
    flag = " --no-buffer" if a.no_buffer else " --unet-only" if a.unet_only else ""
    export(net, config, train_data.bbox_min, train_data.bbox_max, a.out, not a.f32,
           f"training/neural_gi/train.py{flag} on {scene_dir.name} ({step} steps)",
           extra={"dataset_scene": scene_dir.name, "steps": step, "lr": a.lr, "seed": a.seed,
                  "train_frames": len(train_data), "heldout_frames": run["test"], "heldout_loss": result["heldout_loss"],
                  "train_seconds": result["train_seconds"]})
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

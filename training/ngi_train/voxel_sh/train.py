#!/usr/bin/python3
"""Train one of seed 004's networks (voxel attributes -> 27 SH coefficients) and export it for ngi.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.voxel_sh.train --arch set \\
        --train data/vox/train/* --test data/vox/test/* --steps 3000 \\
        --work /tmp/voxel_sh_set --out models/voxel_sh_set.safetensors --card models/voxel_sh_set.md

One step = one whole training scene (the set network pools over the scene), scenes in a shuffled order per epoch
that depends only on (seed, epoch) (checkpoint.epoch_order). Inputs and targets are standardized with statistics of
the training scenes (data.py); the loss is seed 004's Eq. 31, mean((y' - t')^2) + lambda ||W||^2: the mean squared error of the
standardized coefficients plus --weight-decay times the sum of squares of every weight matrix (biases excluded),
added to the loss explicitly; Adam's own weight_decay is not used (it would add lambda w to the gradient, i.e.
(lambda / 2) ||w||^2, biases included).

The work folder (keep it outside the repository) holds checkpoint.pt (every --checkpoint-every steps, at the end
and on Ctrl-C / SIGTERM), run.json and log.jsonl (every --log-every steps: the mean training loss of those steps
and the train and test MSE of the standardized coefficients over all voxels, comparable to seed 004's Table 1).
Running the same command again resumes from the checkpoint, bit for bit on the same machine and thread count;
--steps may change on resume, nothing else. A tqdm progress bar with ETA goes to stderr. At the end the model is
written to --out (F32, or F16 with --half) through ngi.model_file and the model card to --card.
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

import ngi.voxel_sh as networks

from ngi_train import checkpoint, ngi_paths
from ngi_train.voxel_sh import data, export

# Keys of the run config that may change when a run is resumed (they do not change what a step computes).
RESUMABLE = {"steps", "log_every", "checkpoint_every", "threads"}


@torch.no_grad()
def mse(net, items):
    """Mean squared error of the standardized coefficients over all voxels and coefficients of `items`."""
    if not items:
        return None
    total, count = 0.0, 0
    for x, t in items:
        total += float(((net(x) - t) ** 2).sum())
        count += t.numel()
    return total / count


def parse_widths(text):
    return [int(v) for v in text.split(",")] if text else None


def write_card(path, run, result):
    r, c = result, run["config"]
    lines = [
        f"# voxel_sh {c['arch']} (seed 004)",
        "",
        f"- **Architecture**: {c['arch']} {json.dumps(c['widths'])}, tanh hidden layers, linear output; "
        f"{run['parameters']:,} parameters",
        f"- **Data**: grid {'x'.join(map(str, run['grid']))}; train {len(run['train_scenes'])} scenes "
        f"({sum(v for _, v in run['train_scenes']):,} voxels): {', '.join(n for n, _ in run['train_scenes'])}; "
        f"test {len(run['test_scenes'])} scenes ({sum(v for _, v in run['test_scenes']):,} voxels): "
        f"{', '.join(n for n, _ in run['test_scenes']) or '-'}",
        "- **Standardization**: inputs to [-1, 1] by the training scenes' min / max, coefficients by their mean / std "
        "(stored in the model file, applied by ngi on the device)",
        f"- **Training**: {r['step']} steps (one scene per step), Adam lr {c['lr']}, loss MSE + {c['weight_decay']} "
        f"||W||^2 (Eq. 31, weights only, explicit in the loss), seed {c['seed']}, {run['threads']} threads, "
        f"torch {torch.__version__}",
        f"- **Wall time**: {r['train_seconds']:.1f} s of steps ({r['steps_per_second']:.2f} steps/s), "
        f"{r['wall_seconds']:.1f} s with evaluation",
        f"- **Standardized MSE** (all voxels x 27 coefficients; seed 004 Table 1's unit): train "
        f"{_fmt(r['train_mse'])}, test {_fmt(r['test_mse'])}",
        f"- **File**: {Path(r['out']).name} ({'F16' if c['half'] else 'F32'} weights)",
        "",
    ]
    Path(path).write_text("\n".join(lines))


def _fmt(v):
    return "-" if v is None else f"{v:.5f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="+", required=True, help="training scene folders")
    ap.add_argument("--test", nargs="*", default=[], help="test scene folders (same grid)")
    ap.add_argument("--arch", choices=networks.ARCHITECTURES, required=True)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--weight-decay", type=float, default=1e-4, help="lambda of Eq. 31 (0: no regularization)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--hidden", help="mlp hidden widths, e.g. 128,128,128")
    ap.add_argument("--phi", help="set: phi widths, e.g. 128,128")
    ap.add_argument("--rho", help="set: rho hidden widths, e.g. 256,128")
    ap.add_argument("--width", type=int, help="resnet width")
    ap.add_argument("--blocks", type=int, help="resnet residual blocks")
    ap.add_argument("--work", required=True, help="checkpoints and logs (created; resumed when it has one)")
    ap.add_argument("--out", required=True, help="the ngi model file written at the end")
    ap.add_argument("--card", help="the model card (markdown) written at the end")
    ap.add_argument("--half", action="store_true", help="store F16 weights")
    ap.add_argument("--log-every", type=int, default=100)
    ap.add_argument("--checkpoint-every", type=int, default=200)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args(argv)
    if a.steps < 0 or a.log_every < 1 or a.checkpoint_every < 1:
        raise SystemExit("--steps must be >= 0, --log-every and --checkpoint-every >= 1")
    torch.set_num_threads(a.threads)
    torch.use_deterministic_algorithms(True)

    train_scenes = data.load_scenes(a.train)
    grid = train_scenes[0].grid
    test_scenes = data.load_scenes(a.test, grid=grid) if a.test else []
    stats = data.Stats.from_scenes(train_scenes)  # training scenes only
    standardize = networks.Standardization(stats.input_lo, stats.input_hi, stats.output_mean, stats.output_std)

    def items(scenes):
        return [(standardize.inputs(torch.from_numpy(s.attributes)), standardize.targets(torch.from_numpy(s.sh)))
                for s in scenes]

    train_items, test_items = items(train_scenes), items(test_scenes)
    widths = networks.widths_of(a.arch, hidden=parse_widths(a.hidden), phi=parse_widths(a.phi),
                                rho=parse_widths(a.rho), width=a.width, blocks=a.blocks)
    config = {"arch": a.arch, "widths": widths, "lr": a.lr, "weight_decay": a.weight_decay, "seed": a.seed,
              "half": a.half, "steps": a.steps, "log_every": a.log_every, "checkpoint_every": a.checkpoint_every,
              "threads": a.threads, "data_digest": data.digest(train_scenes + test_scenes)}

    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    ckpt = work / "checkpoint.pt"
    torch.manual_seed(a.seed)
    net = networks.build(a.arch, **widths)
    opt = torch.optim.Adam(net.parameters(), lr=a.lr)
    step, train_seconds = 0, 0.0
    if ckpt.is_file():
        state = checkpoint.load(ckpt)
        checkpoint.check_resumable(state["config"], config, RESUMABLE, work)
        net.load_state_dict(state["model"])
        opt.load_state_dict(state["optimizer"])
        torch.set_rng_state(state["torch_rng"])
        step, train_seconds = state["step"], state["train_seconds"]

    run = {"config": config, "grid": list(grid), "parameters": networks.parameter_count(net),
           "train_scenes": [(s.name, s.voxels) for s in train_scenes],
           "test_scenes": [(s.name, s.voxels) for s in test_scenes], "stats": stats.to_dict(),
           "threads": torch.get_num_threads(), "torch": torch.__version__}
    (work / "run.json").write_text(json.dumps(run, indent=1) + "\n")
    log_path = work / "log.jsonl"
    checkpoint.rewrite_log(log_path, step)

    def save(step):
        checkpoint.save(ckpt, {"model": net.state_dict(), "optimizer": opt.state_dict(), "step": step,
                           "train_seconds": train_seconds, "torch_rng": torch.get_rng_state(), "config": config,
                           "stats": stats.to_dict(), "grid": list(grid), "train_scenes": run["train_scenes"],
                           "test_scenes": run["test_scenes"]})

    print(f"voxel_sh {a.arch} {json.dumps(widths)}: {run['parameters']:,} parameters; {len(train_scenes)} train "
          f"scenes ({sum(s.voxels for s in train_scenes):,} voxels), {len(test_scenes)} test; grid "
          f"{'x'.join(map(str, grid))}; {torch.get_num_threads()} threads; "
          + (f"resuming at step {step}" if step else "from scratch") + f", {a.steps} steps",
          file=sys.stderr, flush=True)
    wall0 = time.monotonic()
    losses = []

    def advance(step, stop):
        nonlocal train_seconds, losses
        epoch, k = divmod(step, len(train_items))
        x, t = train_items[int(checkpoint.epoch_order(a.seed, epoch, len(train_items))[k])]
        t0 = time.monotonic()
        opt.zero_grad(set_to_none=True)
        fit = torch.mean((net(x) - t) ** 2)
        loss = fit + a.weight_decay * networks.l2_weights(net) if a.weight_decay else fit
        loss.backward()
        opt.step()
        train_seconds += time.monotonic() - t0
        step += 1
        if not math.isfinite(loss.item()):
            raise FloatingPointError(f"step {step}: the loss is {loss.item()}")
        losses.append(fit.item())
        if step % a.log_every == 0 or step == a.steps:
            line = {"step": step, "train_batch_mse": float(np.mean(losses)), "train_mse": mse(net, train_items),
                    "test_mse": mse(net, test_items), "seconds": round(train_seconds, 3)}
            log.write(json.dumps(line) + "\n")
            log.flush()
            losses = []
            bar.set_postfix({"train": _fmt(line["train_mse"]), "test": _fmt(line["test_mse"])}, refresh=False)
        bar.update(step - bar.n)
        return stop.requested

    with open(log_path, "a") as log, tqdm(total=a.steps, initial=min(step, a.steps), unit="step",
                                          desc=f"voxel_sh {a.arch}", **ngi_paths.progress_options()) as bar:
        step, exit_code = checkpoint.run_steps(step, a.steps, advance, save, a.checkpoint_every, ckpt)
    if exit_code:
        return exit_code
    if not ckpt.is_file():
        save(step)

    result = {"step": step, "train_seconds": train_seconds, "wall_seconds": time.monotonic() - wall0,
              "steps_per_second": step / train_seconds if train_seconds > 0 else float("nan"),
              "train_mse": mse(net, train_items), "test_mse": mse(net, test_items), "out": str(a.out)}
    training = {"arch": a.arch, "steps": step, "lr": a.lr, "weight_decay": a.weight_decay, "seed": a.seed,
                "train_seconds": round(train_seconds, 1), "train_mse": result["train_mse"],
                "test_mse": result["test_mse"], "train_scenes": run["train_scenes"],
                "test_scenes": run["test_scenes"], "parameters": run["parameters"]}
    export.export(net, a.arch, widths, stats, grid, a.out, half=a.half, training=training,
                  source=f"ngi_train.voxel_sh.train --arch {a.arch} ({step} steps)")
    if a.card:
        write_card(a.card, run, result)
    print(json.dumps({k: v for k, v in result.items()}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

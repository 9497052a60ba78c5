#!/usr/bin/python3
"""Train a pix2pix generator for ngi on a rendered dataset (training/README.md has the whole recipe).

    PYTHONPATH=build/python /usr/bin/python3 training/train.py --config training/configs/surround.json \\
        --dataset DATA --run runs/surround

The run folder holds run.json (the resolved config), checkpoints/latest.pt (every checkpoint_every steps, at
the end and on Ctrl-C / SIGTERM), checkpoints/step_<k>.pt (every keep_every steps) and log.jsonl (one line of
losses per step, eval lines every eval_every steps). Running the same command again resumes from latest.pt
bit for bit (same machine and thread count); --steps S extends or shortens a run. A progress bar with ETA
(tqdm, with the smoothed losses) goes to stderr.

Config keys (JSON; training/configs/*.json): layout ("surround" | "single_view"), ngf, num_downs, dropout
(bool, pix2pix's nn.Dropout(0.5) in training), ndf, d_layers, lambda_l1, lr, beta1, beta2, steps,
decay_steps (linear decay of lr to 0 over the last decay_steps), seed, checkpoint_every, keep_every,
eval_every, eval_frames, threads (0 = all cores), train_split, eval_split, max_frames (0 = all), cache_dir
(null = DATA/merge_cache/<layout>), merge_jobs, comment.
"""

import argparse
import json
import signal
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

import checkpoint
import data
import evaluate
import gan
import networks
import ngi_paths

DEFAULTS = {
    "layout": "surround", "ngf": 32, "num_downs": 8, "dropout": True, "ndf": 32, "d_layers": 3,
    "lambda_l1": 100.0, "lr": 2e-4, "beta1": 0.5, "beta2": 0.999, "batch_size": 1,
    "steps": 20000, "decay_steps": 0, "seed": 1, "checkpoint_every": 500, "keep_every": 5000,
    "eval_every": 0, "eval_frames": 20, "threads": 0, "train_split": "train", "eval_split": "test",
    "max_frames": 0, "cache_dir": None, "merge_jobs": 1, "comment": "",
}
# Keys that may change when a run is resumed (they do not change what a step computes).
RESUMABLE_CHANGES = {"steps", "checkpoint_every", "keep_every", "eval_every", "eval_frames", "threads",
                     "merge_jobs", "comment", "cache_dir"}


def load_config(path, overrides):
    cfg = dict(DEFAULTS)
    if path:
        user = json.loads(Path(path).read_text())
        unknown = sorted(set(user) - set(DEFAULTS))
        if unknown:
            raise ValueError(f"{path}: unknown config keys {unknown}")
        cfg.update(user)
    cfg.update({k: v for k, v in overrides.items() if v is not None})
    data.check_layout(cfg["layout"])
    if cfg["batch_size"] != 1:
        raise ValueError("batch_size must be 1 (pix2pix's setting; per-image BatchNorm at inference relies on it)")
    if cfg["decay_steps"] < 0 or cfg["decay_steps"] > cfg["steps"]:
        raise ValueError("decay_steps must be in [0, steps]")
    return cfg


def check_sizes(cfg, n):
    h, w = data.input_hw(n, cfg["layout"])
    k = 2 ** cfg["num_downs"]
    if h % k or w % k:
        raise ValueError(f"a {h}x{w} input cannot be halved {cfg['num_downs']} times exactly (num_downs "
                         f"{cfg['num_downs']}); use num_downs <= log2 of {h if h % k else w}'s power-of-two factor")
    side = networks.min_discriminator_size(cfg["d_layers"])
    if n < side:
        raise ValueError(f"the discriminator sees {n}x{n} front views; d_layers {cfg['d_layers']} needs >= {side}")


def epoch_order(seed, epoch, count):
    """The frame order of one epoch: a function of (seed, epoch) only, so resuming needs no data RNG state."""
    return np.random.default_rng([seed, epoch]).permutation(count)


class StopSignal:
    """First SIGINT/SIGTERM: finish the step, save a checkpoint, exit. Second: stop at once."""

    def __init__(self):
        self.signum = None
        self.old = {s: signal.signal(s, self.handler) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(self, signum, frame):
        if self.signum is not None:
            self.restore()
            raise KeyboardInterrupt
        self.signum = signum
        print(f"\n{signal.Signals(signum).name}: saving a checkpoint after this step "
              "(again to stop at once)", file=sys.stderr, flush=True)

    def restore(self):
        for s, h in self.old.items():
            signal.signal(s, h)


def rewrite_log(path, max_step):
    """Keep the log lines of steps <= max_step (a resumed run repeats the steps after its checkpoint)."""
    if not path.is_file():
        return
    kept = []
    for line in path.read_text().splitlines():
        try:
            if json.loads(line).get("step", 0) <= max_step:
                kept.append(line)
        except ValueError:
            pass  # a line cut short by a hard kill
    data.write_text_atomic(path, "".join(line + "\n" for line in kept))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", help="training config JSON (training/configs/)")
    ap.add_argument("--dataset", required=True, help="dataset folder (ngi dataset --out)")
    ap.add_argument("--run", required=True, help="run folder (created; resumed when it has a checkpoint)")
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN or build*/ngi)")
    ap.add_argument("--device", help="ngi --device for the merges")
    ap.add_argument("--steps", type=int, help="override the config's steps")
    ap.add_argument("--seed", type=int, help="override the config's seed")
    ap.add_argument("--checkpoint-every", type=int, help="override the config's checkpoint_every")
    ap.add_argument("--threads", type=int, help="override the config's threads")
    args = ap.parse_args(argv)

    cfg = load_config(args.config, {"steps": args.steps, "seed": args.seed,
                                    "checkpoint_every": args.checkpoint_every, "threads": args.threads})
    run = Path(args.run)
    ckpt_dir = run / "checkpoints"
    latest = ckpt_dir / "latest.pt"
    resume = checkpoint.load(latest) if latest.is_file() else None
    if resume is not None:
        old = resume["config"]
        changed = sorted(k for k in set(old) | set(cfg) if old.get(k) != cfg.get(k) and k not in RESUMABLE_CHANGES)
        if changed:
            raise SystemExit(f"{run}: the checkpoint was trained with other settings: "
                             + ", ".join(f"{k} {old.get(k)!r} -> {cfg.get(k)!r}" for k in changed)
                             + " (use another --run folder)")

    if cfg["threads"]:
        torch.set_num_threads(cfg["threads"])
    torch.use_deterministic_algorithms(True)
    ngi = ngi_paths.find_ngi(args.ngi)
    dataset_dir = Path(args.dataset).resolve()
    cache_dir = Path(cfg["cache_dir"]) if cfg["cache_dir"] else data.default_cache_dir(dataset_dir, cfg["layout"])
    train_set, n, merge_stats = data.load_split(dataset_dir, cfg["train_split"], cfg["layout"], cache_dir,
                                                device=args.device, jobs=cfg["merge_jobs"],
                                                max_frames=cfg["max_frames"])
    eval_set = None
    if cfg["eval_every"]:
        eval_set, _, _ = data.load_split(dataset_dir, cfg["eval_split"], cfg["layout"], cache_dir,
                                         device=args.device, jobs=cfg["merge_jobs"], max_frames=cfg["eval_frames"])
    check_sizes(cfg, n)
    digest = data.frame_list_digest(train_set.frames)
    if resume is not None and resume["frames_digest"] != digest:
        raise SystemExit(f"{run}: the checkpoint was trained on another frame list ({resume['frames']} frames)")

    torch.manual_seed(cfg["seed"])
    model = gan.Pix2Pix(cfg, n)
    step, train_seconds = 0, 0.0
    if resume is not None:
        model.load_state_dict(resume["model"])
        torch.set_rng_state(resume["torch_rng"])
        step, train_seconds = resume["step"], resume["train_seconds"]

    run.mkdir(parents=True, exist_ok=True)
    run_info = {"config": cfg, "dataset": str(dataset_dir), "dataset_config": data.read_dataset_config(dataset_dir),
                "n": n, "frames": len(train_set), "frames_digest": digest, "ngi": ngi,
                "generator_parameters": networks.parameter_count(model.G),
                "discriminator_parameters": networks.parameter_count(model.D), "torch": torch.__version__}
    data.write_text_atomic(run / "run.json", json.dumps(run_info, indent=1) + "\n")
    log_path = run / "log.jsonl"
    rewrite_log(log_path, step)

    h, w = data.input_hw(n, cfg["layout"])
    print(f"train {cfg['layout']}: {len(train_set)} frames ({merge_stats['merged']} merged, "
          f"{merge_stats['reused']} cached), input [1, {data.input_nc(cfg['layout'])}, {h}, {w}], "
          f"G {run_info['generator_parameters'] / 1e6:.2f} M, D {run_info['discriminator_parameters'] / 1e6:.2f} M "
          f"parameters, {torch.get_num_threads()} threads; "
          + (f"resuming at step {step}" if resume is not None else "from scratch")
          + f", {cfg['steps']} steps", file=sys.stderr, flush=True)

    def save(path):
        checkpoint.save(path, {"model": model.state_dict(), "step": step, "torch_rng": torch.get_rng_state(),
                               "train_seconds": train_seconds, "config": cfg, "n": n, "frames": len(train_set),
                               "frames_digest": digest, "dataset": str(dataset_dir)})

    stop = StopSignal()
    progress = tqdm(total=cfg["steps"], initial=step, unit="step", **ngi_paths.progress_options())
    shown = {}  # the losses on the bar, smoothed
    exit_code = 0
    try:
        with open(log_path, "a") as log:
            while step < cfg["steps"]:
                t0 = time.monotonic()
                epoch, k = divmod(step, len(train_set))
                x, y, _ = train_set[int(epoch_order(cfg["seed"], epoch, len(train_set))[k])]
                losses = model.step(x[None], y[None], step)
                step += 1
                train_seconds += time.monotonic() - t0
                log.write(json.dumps({"step": step, **losses, "seconds": round(train_seconds, 3)}) + "\n")
                if cfg["eval_every"] and (step % cfg["eval_every"] == 0 or step == cfg["steps"]):
                    scores = evaluate.heldout_scores(model.G.state_dict(), cfg, eval_set, n, "per_image")
                    log.write(json.dumps({"step": step, "eval": scores}) + "\n")
                log.flush()
                for k in ("G_GAN", "G_L1", "D_real", "D_fake"):
                    if k in losses:
                        shown[k] = losses[k] if k not in shown else 0.9 * shown[k] + 0.1 * losses[k]
                progress.set_postfix({k: f"{v:.4g}" for k, v in shown.items()}, refresh=False)
                progress.update(step - progress.n)
                if step % cfg["checkpoint_every"] == 0 or step == cfg["steps"] or stop.signum is not None:
                    log.flush()
                    save(latest)
                    if cfg["keep_every"] and step % cfg["keep_every"] == 0:
                        save(ckpt_dir / f"step_{step:08d}.pt")
                if stop.signum is not None:
                    print(f"stopped at step {step}; checkpoint {latest} (run the same command to resume)",
                          file=sys.stderr)
                    exit_code = 128 + stop.signum
                    break
    finally:
        stop.restore()
        progress.close()
    if exit_code == 0:
        if step >= cfg["steps"] and not latest.is_file():
            save(latest)
        print(f"done: {step} steps, {train_seconds:.0f} s of training; checkpoint {latest}", file=sys.stderr)
    return exit_code


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Train a pix2pix generator for ngi on a rendered dataset (training/README.md has the whole recipe).

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.train \\
        --config training/configs/surround.json \\
        --dataset DATA --run runs/surround

The run folder holds run.json (the resolved config), checkpoints/latest.pt (every checkpoint_every steps, at
the end and on Ctrl-C / SIGTERM), checkpoints/step_<k>.pt (every keep_every steps) and log.jsonl (one line of
losses per step, eval lines every eval_every steps). Running the same command again resumes from latest.pt
bit for bit (same machine and thread count); --steps S extends or shortens a run. A progress bar with ETA
(tqdm, with the smoothed losses) goes to stderr.

Distributed (data parallel, PyTorch's DistributedDataParallel; training/README.md "Distributed training and
evaluation"):

    /usr/bin/python3 -m ngi_train.torchrun --standalone --nproc_per_node 2 --module ngi_train.generator.train ...

Each rank forwards its own images one at a time (per-image BatchNorm, batch_size stays 1) and DDP averages the
gradients over the ranks: one optimizer step sees an effective batch of world_size x accumulate images. Rank 0
prepares the merge cache, writes run.json, log.jsonl and the checkpoints and shows the progress bar; the other
ranks only read. Checkpoints hold the plain (non-DDP) state_dicts and every rank's RNG state: any world size
resumes them, and the same one bit for bit; a different effective batch is refused unless --allow-batch-change.

Config keys (JSON; training/configs/*.json): layout ("surround" | "single_view"), ngf, num_downs, dropout
(bool, pix2pix's nn.Dropout(0.5) in training), ndf, d_layers, lambda_l1, lr, beta1, beta2, steps (optimizer
steps), decay_steps (linear decay of lr to 0 over the last decay_steps), seed, checkpoint_every, keep_every,
eval_every, eval_frames, threads (per rank; 0 = PyTorch's default, which torchrun sets to 1 per rank),
accumulate (images per optimizer step per rank, each forwarded alone, gradients averaged; default 1),
batch_size (must be 1), train_split, eval_split, max_frames (0 = all), cache_dir
(null = DATA/merge_cache/<layout>), merge_jobs, comment; output_mode ("lightmap": the thesis, the output is the
whole lightmap | "indirect": the output is indirect light added to the frame's direct light), lambda_final (weight
of the L1 of tone-mapped final images, 0 = off), lambda_gan (weight of the GAN term, 0 = no discriminator);
gan.py says what each does; init_model (an exported ngi model file whose generator weights a new run starts
from, instead of random ones: fine-tuning, as ngi_train.adapt does; its architecture must be the config's).
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import torch
from tqdm import tqdm

from ngi_train import checkpoint, distributed, ngi_paths
from ngi_train.generator import data, evaluate, gan, lightmap_loss, networks

DEFAULTS = {
    "layout": "surround", "ngf": 32, "num_downs": 8, "dropout": True, "ndf": 32, "d_layers": 3,
    "lambda_l1": 100.0, "lr": 2e-4, "beta1": 0.5, "beta2": 0.999, "batch_size": 1, "accumulate": 1,
    "steps": 20000, "decay_steps": 0, "seed": 1, "checkpoint_every": 500, "keep_every": 5000,
    "eval_every": 0, "eval_frames": 20, "threads": 0, "train_split": "train", "eval_split": "test",
    "max_frames": 0, "cache_dir": None, "merge_jobs": 1, "comment": "",
    "output_mode": "lightmap", "lambda_final": 0.0, "lambda_gan": 1.0, "init_model": None,
}
# Keys that may change when a run is resumed (they do not change what a step computes).
# accumulate may change as long as the effective batch (world size x accumulate) stays (train() checks that).
RESUMABLE_CHANGES = {"accumulate", "steps", "checkpoint_every", "keep_every", "eval_every", "eval_frames", "threads",
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
    lightmap_loss.check_mode(cfg["output_mode"])
    for key in ("lambda_final", "lambda_gan"):
        if not (isinstance(cfg[key], (int, float)) and math.isfinite(cfg[key]) and cfg[key] >= 0):
            raise ValueError(f"{key} must be a finite number >= 0, got {cfg[key]!r}")
    if cfg["batch_size"] != 1:
        raise ValueError("batch_size must be 1 (pix2pix's setting; per-image BatchNorm at inference relies on it); "
                         "for more images per step use accumulate or more ranks (each image is normalized alone)")
    if not isinstance(cfg["accumulate"], int) or cfg["accumulate"] < 1:
        raise ValueError("accumulate must be an integer >= 1")
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


LOSS_KEYS = ("G_GAN", "G_L1", "D_real", "D_fake", "G_final")


class SampleOrder:
    """Global sample j (0, 1, 2, ... over the whole run) -> frame index: epoch j // L in checkpoint.epoch_order's
    order. Step s of an effective batch B covers samples [samples_before, samples_before + B); rank r takes the positions r,
    r + W, ..., r + (A - 1) W of it (W ranks, A = accumulate). The sequence does not depend on W or A, so a run
    resumed with another world size (same B) sees the same frames in the same steps."""

    def __init__(self, seed, count):
        self.seed, self.count = seed, count
        self.orders = {}

    def __call__(self, j):
        epoch, k = divmod(j, self.count)
        if epoch not in self.orders:
            if len(self.orders) > 2:
                self.orders.pop(min(self.orders))
            self.orders[epoch] = checkpoint.epoch_order(self.seed, epoch, self.count)
        return int(self.orders[epoch][k])


def init_generator(G, cfg):
    """Loads cfg["init_model"]'s generator weights into G (a new run's start); refuses another architecture."""
    import ngi.model_file as model_file
    path = cfg["init_model"]
    tensors, mc = model_file.read_model(str(path))
    mode = "ssgi_residual" if data.is_residual(cfg["layout"]) else cfg.get("output_mode", "lightmap")
    want = {"family": "pix2pix_unet", "input_nc": data.input_nc(cfg["layout"]), "output_nc": 3, "ngf": cfg["ngf"],
            "num_downs": cfg["num_downs"], "output_mode": mode}
    got = {k: mc.get(k) for k in want}
    if got != want:
        raise SystemExit(f"init_model {path}: {got} is not this config's generator {want}")
    state = G.state_dict()
    missing = sorted(k for k in state if k not in tensors and not k.endswith("num_batches_tracked"))
    extra = sorted(k for k in tensors if k not in state)
    if missing or extra:
        raise SystemExit(f"init_model {path}: tensor names differ from the generator's (missing {missing[:3]}, "
                         f"unexpected {extra[:3]})")
    for k, t in tensors.items():
        if tuple(t.shape) != tuple(state[k].shape):
            raise SystemExit(f"init_model {path}: tensor {k} is {tuple(t.shape)}, the generator's {tuple(state[k].shape)}")
        state[k] = torch.from_numpy(t.astype("float32"))
    G.load_state_dict(state)


def rng_state(device):
    return {"cpu": torch.get_rng_state(),
            "cuda": torch.cuda.get_rng_state(device) if device.type == "cuda" else None}


def set_rng_state(state, device):
    torch.set_rng_state(state["cpu"])
    if device.type == "cuda" and state.get("cuda") is not None:
        torch.cuda.set_rng_state(state["cuda"], device)


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
    ap.add_argument("--threads", type=int, help="override the config's threads (per rank)")
    ap.add_argument("--accumulate", type=int, help="override the config's accumulate (images per step per rank)")
    ap.add_argument("--allow-batch-change", action="store_true",
                    help="resume with another effective batch (world size x accumulate) than the checkpoint's")
    ap.add_argument("--merge-only", action="store_true", help="prepare the merge cache and exit")
    args = ap.parse_args(argv)
    cfg = load_config(args.config, {"steps": args.steps, "seed": args.seed, "accumulate": args.accumulate,
                                    "checkpoint_every": args.checkpoint_every, "threads": args.threads})
    d = distributed.init()
    try:
        return train(args, cfg, d)
    finally:
        d.close()


def train(args, cfg, d):
    """The training loop of one rank (d: distributed.Dist; a plain single process is rank 0 of 1)."""
    batch = d.world * cfg["accumulate"]
    run = Path(args.run)
    ckpt_dir = run / "checkpoints"
    latest = ckpt_dir / "latest.pt"
    found = d.all_gather(latest.is_file())
    if len(set(found)) > 1:
        raise SystemExit(f"{latest}: present on some ranks only ({found}); the run folder must be on a file system "
                         "every rank sees")
    resume = checkpoint.load(latest) if found[0] else None
    if resume is not None:
        checkpoint.check_resumable(resume["config"], cfg, RESUMABLE_CHANGES, run, defaults=DEFAULTS)
        old_batch = resume.get("effective_batch", 1)
        if old_batch != batch and not args.allow_batch_change:
            raise SystemExit(
                f"{run}: the checkpoint was trained with an effective batch of {old_batch} images per step "
                f"({resume.get('world_size', 1)} rank(s) x accumulate {resume.get('accumulate', 1)}); this run has "
                f"{batch} ({d.world} rank(s) x accumulate {cfg['accumulate']}). Resume with ranks x accumulate = "
                f"{old_batch} (e.g. --accumulate {max(1, old_batch // d.world)} with {d.world} rank(s)"
                + ("" if old_batch % d.world == 0 else f", which does not divide: use {old_batch} ranks or 1") + "), "
                "or pass --allow-batch-change to continue with the new batch (the schedule stays in steps)")

    if cfg["threads"]:
        torch.set_num_threads(cfg["threads"])
    torch.use_deterministic_algorithms(True)
    ngi = ngi_paths.find_ngi(args.ngi)
    dataset_dir = Path(args.dataset).resolve()
    cache_dir = Path(cfg["cache_dir"]) if cfg["cache_dir"] else data.default_cache_dir(dataset_dir, cfg["layout"])

    def load(split, max_frames, prepare):
        return data.load_split(dataset_dir, split, cfg["layout"], cache_dir, device=args.device,
                               jobs=cfg["merge_jobs"], max_frames=max_frames, prepare=prepare)

    # Rank 0 merges what the cache lacks; the other ranks wait, then only read it (nobody writes the same entry).
    if d.main:
        train_set, n, merge_stats = load(cfg["train_split"], cfg["max_frames"], True)
        eval_set = load(cfg["eval_split"], cfg["eval_frames"], True)[0] if cfg["eval_every"] else None
    d.barrier()
    if not d.main:
        train_set, n, merge_stats = load(cfg["train_split"], cfg["max_frames"], False)
        eval_set = load(cfg["eval_split"], cfg["eval_frames"], False)[0] if cfg["eval_every"] else None
    if args.merge_only:
        if d.main:
            print(f"merge cache {cache_dir}: {len(train_set)} train frames ({merge_stats['merged']} merged, "
                  f"{merge_stats['reused']} cached)" + (f", {len(eval_set)} eval frames" if eval_set else ""),
                  file=sys.stderr)
        return 0
    check_sizes(cfg, n)
    digest = data.frame_list_digest(train_set.frames)
    if resume is not None and resume["frames_digest"] != digest:
        raise SystemExit(f"{run}: the checkpoint was trained on another frame list ({resume['frames']} frames)")

    torch.manual_seed(cfg["seed"])
    model = gan.Pix2Pix(cfg, n, device=d.device)
    step, train_seconds, samples = 0, 0.0, 0
    if resume is not None:
        model.load_state_dict(resume["model"])
        step, train_seconds = resume["step"], resume["train_seconds"]
        samples = resume.get("samples", step)  # runs from before the effective batch: one image per step
        states = resume.get("rng_ranks") or [{"cpu": resume["torch_rng"]}]
        if len(states) == d.world or d.main:
            set_rng_state(states[d.rank], d.device)  # bit-exact resume at the same world size
        else:
            torch.manual_seed(distributed.rank_seed(cfg["seed"], d.rank, step))
    elif not d.main:
        # Rank r > 0 draws its own dropout masks; rank 0 keeps the run's stream (a single process is unchanged).
        torch.manual_seed(distributed.rank_seed(cfg["seed"], d.rank, 0))
    elif cfg["init_model"]:
        init_generator(model.G, cfg)
    model.distribute(d)

    log_path = run / "log.jsonl"
    run_info = {"config": cfg, "dataset": str(dataset_dir), "dataset_config": data.read_dataset_config(dataset_dir),
                "n": n, "frames": len(train_set), "frames_digest": digest, "ngi": ngi,
                "generator_parameters": networks.parameter_count(model.G),
                "discriminator_parameters": networks.parameter_count(model.D), "torch": torch.__version__,
                "world_size": d.world, "accumulate": cfg["accumulate"], "effective_batch": batch,
                "backend": d.backend, "threads_per_rank": torch.get_num_threads()}
    if d.main:  # the other ranks never write into the run folder
        run.mkdir(parents=True, exist_ok=True)
        checkpoint.write_text_atomic(run / "run.json", json.dumps(run_info, indent=1) + "\n")
        checkpoint.rewrite_log(log_path, step)
        h, w = data.input_hw(n, cfg["layout"])
        print(f"train {cfg['layout']}: {len(train_set)} frames ({merge_stats['merged']} merged, "
              f"{merge_stats['reused']} cached), input [1, {data.input_nc(cfg['layout'])}, {h}, {w}], "
              f"G {run_info['generator_parameters'] / 1e6:.2f} M, D {run_info['discriminator_parameters'] / 1e6:.2f} M "
              f"parameters, {torch.get_num_threads()} threads"
              + (f" per rank, {d.world} ranks ({d.backend})" if d.enabled else "")
              + f"; effective batch {batch} ({d.world} x accumulate {cfg['accumulate']}); "
              + (f"resuming at step {step} ({samples} samples)" if resume is not None else "from scratch")
              + f", {cfg['steps']} steps", file=sys.stderr, flush=True)

    def save_to(paths, step):
        """Collective: every rank hands over its RNG state, rank 0 writes the checkpoint files (after `step` steps)."""
        states = d.all_gather(rng_state(d.device))
        if not d.main:
            return
        state = {"model": model.state_dict(), "step": step, "samples": samples, "torch_rng": states[0]["cpu"],
                 "rng_ranks": states, "train_seconds": train_seconds, "config": cfg, "n": n,
                 "frames": len(train_set), "frames_digest": digest, "dataset": str(dataset_dir),
                 "world_size": d.world, "accumulate": cfg["accumulate"], "effective_batch": batch}
        for path in paths:
            checkpoint.save(path, state)

    order = SampleOrder(cfg["seed"], len(train_set))
    positions = [d.rank + d.world * a for a in range(cfg["accumulate"])]
    shown = {}  # the losses on the bar, smoothed
    ran = False

    def advance(step, stop):
        nonlocal samples, train_seconds, ran
        ran = True
        t0 = time.monotonic()
        indices = [order(samples + p) for p in positions]
        items = [train_set[i] for i in indices]
        fronts = [train_set.front(i)[None] for i in indices] if model.needs_front() else None
        sums = model.step([x[None] for x, _, _ in items], [y[None] for _, y, _ in items], step, fronts)
        # One small allreduce: the losses' sums over the effective batch, and whether any rank got a signal
        # (all ranks then stop after the same step).
        reduced = d.all_reduce_sum([sums[k] for k in LOSS_KEYS] + [float(stop.requested)])
        losses = {k: reduced[i].item() / batch for i, k in enumerate(LOSS_KEYS)}
        losses["lr"] = sums["lr"]
        bad = [k for k, v in losses.items() if not math.isfinite(v)]
        if bad:
            raise FloatingPointError(f"step {step}: non-finite losses {bad}: {losses}")
        step += 1
        samples += batch
        train_seconds += time.monotonic() - t0
        scores = None
        if cfg["eval_every"] and (step % cfg["eval_every"] == 0 or step == cfg["steps"]):
            scores = evaluate.heldout_scores(model.G.state_dict(), cfg, eval_set, n, "per_image", dist=d)
        if d.main:
            log.write(json.dumps({"step": step, **losses, "samples": samples, "batch": batch,
                                  "seconds": round(train_seconds, 3)}) + "\n")
            if scores is not None:
                log.write(json.dumps({"step": step, "eval": scores}) + "\n")
            log.flush()
            for k in LOSS_KEYS:
                shown[k] = losses[k] if k not in shown else 0.9 * shown[k] + 0.1 * losses[k]
            progress.set_postfix({k: f"{v:.4g}" for k, v in shown.items()}, refresh=False)
            progress.update(step - progress.n)
        return reduced[-1].item() > 0

    def save(step_done):
        paths = [latest]
        if cfg["keep_every"] and step_done % cfg["keep_every"] == 0:
            paths.append(ckpt_dir / f"step_{step_done:08d}.pt")
        save_to(paths, step_done)

    log = open(log_path, "a") if d.main else None
    try:
        with tqdm(total=cfg["steps"], initial=step, unit="step", disable=not d.main,
                  **ngi_paths.progress_options()) as progress:
            step, exit_code = checkpoint.run_steps(step, cfg["steps"], advance, save, cfg["checkpoint_every"], latest,
                                                   main=d.main)
    finally:
        if log is not None:
            log.close()
    if exit_code == 0:
        if not ran and resume is None:
            save_to([latest], step)
        if d.main:
            print(f"done: {step} steps ({samples} samples), {train_seconds:.0f} s of training; checkpoint {latest}",
                  file=sys.stderr)
    return exit_code


if __name__ == "__main__":
    sys.exit(main())

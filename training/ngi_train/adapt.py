#!/usr/bin/python3
"""ngi adapt: fit a GI network to one scene within a time budget (issue 46, docs/ADAPT.md).

    ngi adapt --scene F.vox --out M.safetensors [--budget-minutes 10] [--base adapt_base_ssgi_residual_n64] \\
        [--work DIR] [--times 8,12,16]
    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.adapt ...    (the same, from a checkout)

`ngi adapt` (samples/ngi/cmd_adapt.cpp) runs this module with its installation's Python package and itself as the
ngi binary; the work folder defaults to runs/adapt/<scene> in a checkout, ~/.cache/ngi/adapt/<scene> (under
$XDG_CACHE_HOME if set) for an installed package.

What it does, all inside the budget (wall clock, render + train + export; a run resumed after an interruption
counts the time spent before it):
1. Checks before any work: the scene loads, the base model is a pix2pix_unet of output mode ssgi_residual that runs
   at N = 64, and the budget holds the validation frames and one training frame within its render share plus a
   minute of training: the first validation frame is rendered as the measure, stopped (and removed) once it takes
   longer than its share; a budget too small leaves nothing behind.
2. Renders frames of the scene with the inputs an engine has (`ngi render`: direct light at FEATURE_SPP samples per
   pixel, i.e. without noise; references at REFERENCE_SPP): VAL_FRAMES validation views on one camera path, then
   training views on other paths (orbits around the model from other seeded starts and, where the scene has room,
   fly-throughs), FRAMES_PER_PATH frames each, until RENDER_SHARE of the budget is spent. None of these paths is
   the scene's dataset path (`ngi render` without --path-seed), on which the evaluation (adapt_eval) scores it.
   With --times, the views take those times of day in turn (`ngi render --time`): the network learns the scene
   under a moving sun (adapt_sun_eval scores it at other times).
3. Fine-tunes the base network (ngi_train.generator.train with init_model = the base, the base's own recipe at a
   constant FINE_TUNE_LR): a first chunk of CHUNK_STEPS steps measures the step rate, the second runs the steps
   the remaining budget holds (and is stopped with SIGTERM at the deadline if it overruns). The validation frames
   are scored every CHUNK_STEPS steps (evaluate.heldout_scores: L1 of the encoded front lightmap).
4. Early stopping: the kept checkpoint with the lowest validation L1 is exported (F16, ngi_train.generator.export);
   if no step beats the base on the validation frames the base's weights are written (and the card says so).
   The model file's config gets an "adapt" record (scene, frames, budget, time per phase, validation scores), and
   a card (M.md) is written beside it.

Interrupting it (Ctrl-C, SIGTERM) keeps what is finished: rendered frames, the training checkpoints; running the
same command again resumes. The model is written last, atomically: an interrupted run leaves no model.
"""

import argparse
import datetime
import importlib.util
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import torch

import ngi
import ngi.model_file as model_file
import ngi.zoo as zoo_mod

from ngi_train import checkpoint, ngi_paths
from ngi_train.generator import data, evaluate, export

N = 64
FEATURE_SPP, REFERENCE_SPP = 512, 256  # configs/dataset_engine_n64.json's: the base network's training inputs
PATH_FRAMES = 100                       # frames of every camera path (as engine_eval's)
VAL_PATH_SEED = 7001                    # the validation views' path; training paths start at TRAIN_PATH_SEED
TRAIN_PATH_SEED = 7101
VAL_FRAMES = (12, 37, 62, 87)
FRAMES_PER_PATH = 8
RENDER_SHARE = 0.4                      # of the budget, for the frames (the rest trains)
MAX_TRAIN_FRAMES = 160
CHUNK_STEPS = 250                       # steps between validation scores (and kept checkpoints)
FINE_TUNE_LR = 1e-4                     # chosen on procedural scenes (docs/ADAPT.md), never on the .vox files
MIN_TRAIN_SECONDS = 60.0
EXPORT_RESERVE_S = 30.0                 # kept for selection and export at the end
DEFAULT_BASE = "adapt_base_ssgi_residual_n64"
# PyTorch threads of the fine-tuning: this 1.8 M-parameter U-Net at 64 x 64 trains ~2x faster on one thread than on
# two here (45 vs 19 steps/s, measured side by side on room:seed=301; the second thread mostly synchronizes).
TRAIN_THREADS = 1


def log(msg):
    print(f"adapt: {msg}", file=sys.stderr, flush=True)


class AdaptError(Exception):
    """Bad input, found before any work."""


# --------------------------------------------------------------------------
# Budget bookkeeping (WORK/adapt.json: the seconds spent per phase, over interruptions)
# --------------------------------------------------------------------------

class Budget:
    def __init__(self, work, seconds, identity):
        self.path = work / "adapt.json"
        self.seconds = seconds
        state = json.loads(self.path.read_text()) if self.path.is_file() else {}
        if state and state.get("identity") != identity:
            raise AdaptError(f"{work}: holds an adaptation of {state.get('identity')}, not of {identity} "
                             "(use another --work folder)")
        self.state = state or {"identity": identity, "spent": {}}
        self.before = sum(self.state["spent"].values())  # seconds spent by earlier (interrupted) runs
        self.phase, self.phase_t0 = None, None

    def elapsed(self):
        return sum(self.state["spent"].values()) + (time.monotonic() - self.phase_t0 if self.phase else 0.0)

    def left(self):
        return self.seconds - self.elapsed()

    def enter(self, phase):
        self.close()
        self.phase, self.phase_t0 = phase, time.monotonic()

    def close(self):
        if self.phase is not None:
            self.record()
            self.phase = None

    def record(self):
        """Adds the current phase's time so far to the record and saves it: an interrupted run's time counts."""
        if self.phase is not None:
            now = time.monotonic()
            spent = self.state["spent"]
            spent[self.phase] = spent.get(self.phase, 0.0) + now - self.phase_t0
            self.phase_t0 = now
            self.save()

    def save(self):
        checkpoint.write_text_atomic(self.path, json.dumps(self.state, indent=1) + "\n")


# --------------------------------------------------------------------------
# Frames
# --------------------------------------------------------------------------

def render(ngi_bin, scene, out, frame, path_seed, kind, spp, feature_spp, n, device, timeout=None, hours=None):
    """`ngi render` of frame `frame` of the camera path (kind, path_seed) at time of day `hours` (None: the scene's)
    into the frame folder `out` (written beside it and renamed: an interrupted render is redone); returns its wall
    seconds (0 when it was there)."""
    if (out / "camera.json").is_file():
        return 0.0
    tmp = out.with_name(f".{out.name}.tmp-render")  # a name data.list_frames skips
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.parent.mkdir(parents=True, exist_ok=True)
    # The tracer's seed is the path's and the frame's, not the dataset's seed of frame K (which the scored views
    # of the same K use).
    cmd = [ngi_bin, "render", "--scene", scene, "--frame", frame, "--path-frames", PATH_FRAMES, "--path-seed",
           path_seed, "--camera-path", kind, "--face", n, "--spp", spp, "--feature-spp", feature_spp,
           "--seed", (path_seed * 7919 + frame * 104729 + 12345) % 2147483647, "--out", tmp]
    if device:
        cmd += ["--device", device]
    if hours is not None:
        cmd += ["--time", f"{hours:g}"]
    try:
        _, seconds = ngi_paths.run(cmd, timeout=timeout)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    tmp.rename(out)
    return seconds


def train_views(times=None):
    """(kind, path seed, frame, hours) of every training view, in rendering order: per camera path FRAMES_PER_PATH
    frames spread along it; every third path a fly-through (skipped on scenes without room for one); the time of day
    of view i is times[i % len(times)] (None: the scene's own)."""
    p, i = 0, 0
    while True:
        kind = "fly" if p % 3 == 2 else "auto"
        for j in range(FRAMES_PER_PATH):
            k = (5 + j * (PATH_FRAMES - 10) // (FRAMES_PER_PATH - 1) + 3 * p) % PATH_FRAMES
            yield kind, TRAIN_PATH_SEED + p, k, hour_of(times, i)
            i += 1
        p += 1


def val_views(times=None):
    """(frame, hours, folder name) of the validation views: VAL_FRAMES of the VAL_PATH_SEED path, the times of day
    taken in turn (None: the scene's own)."""
    views = []
    for i, k in enumerate(VAL_FRAMES):
        hours = hour_of(times, i)
        views.append((k, hours, f"p{VAL_PATH_SEED}_f{k:03d}" + time_suffix(hours)))
    return views


def hour_of(times, i):
    """The time of day of view i: the times taken in turn (None without times: the scene's own)."""
    return times[i % len(times)] if times else None


def time_suffix(hours):
    return "" if hours is None else f"_t{hours:05.2f}"


def recorded_frame_seconds(frame_dir):
    """A rendered frame's kernel seconds (render.json) plus the command's start-up (~0.5 s here)."""
    timing = json.loads((frame_dir / "render.json").read_text())["timing"]
    return (timing["features_ms"] + timing.get("reference_ms", 0.0)) * 1e-3 + 0.5


# --------------------------------------------------------------------------
# Training
# --------------------------------------------------------------------------

def train_config(base_path, base_config, work, lr):
    cfg = dict(base_config["training"]["config"])
    cfg.update({"init_model": str(base_path), "lr": lr, "decay_steps": 0, "eval_every": CHUNK_STEPS,
                "keep_every": CHUNK_STEPS, "checkpoint_every": CHUNK_STEPS, "eval_frames": 0, "train_split": "train",
                "eval_split": "val", "cache_dir": str(work / "merge_cache"), "max_frames": 0,
                "threads": TRAIN_THREADS, "steps": CHUNK_STEPS,
                "comment": f"ngi_train.adapt: fine-tuning {Path(base_path).name} on one scene"})
    return cfg


def child_pythonpath(path=None):
    """The training child's PYTHONPATH: this process's sys.path (`path`), so that it imports what this one does
    (a build tree's folders that `ngi adapt` put first included), in the same order; ngi_paths.PACKAGE_PARENT in
    front only when it is not on it already -- an installation's site folder (/usr/lib/python3/dist-packages) put
    first would hide the user's own packages (/usr/local, ~/.local) from the child."""
    path = [p for p in (sys.path if path is None else path) if p]
    parent = ngi_paths.PACKAGE_PARENT
    if not any(Path(p).resolve() == parent for p in path):
        path.insert(0, str(parent))
    return os.pathsep.join(path)


def run_training(cfg_path, work, steps, deadline, ngi_bin):
    """train.py up to `steps` steps (resuming the run folder); SIGTERM at the monotonic `deadline` (train.py then
    saves and exits). Returns the steps done."""
    cmd = [sys.executable, "-m", "ngi_train.generator.train", "--config", cfg_path, "--dataset", work / "data",
           "--run", work / "run", "--ngi", ngi_bin, "--steps", steps]
    env = dict(ngi_paths.ngi_env())
    env["PYTHONPATH"] = child_pythonpath()
    # Its own session: a Ctrl-C at the terminal reaches adapt only, which then sends the child exactly one SIGTERM
    # (train.py saves after the step it is in; a second signal would cut that short).
    proc = subprocess.Popen([str(c) for c in cmd], env=env, start_new_session=True)
    try:
        while proc.poll() is None:
            if time.monotonic() >= deadline:
                log("the budget's training time is up: stopping the training (it saves its checkpoint)")
                proc.send_signal(signal.SIGTERM)
                proc.wait()
                break
            time.sleep(0.5)
    except BaseException:
        proc.send_signal(signal.SIGTERM)
        proc.wait()
        raise
    # 128 + SIGTERM: stopped after a step, checkpoint saved; -SIGTERM: stopped before its first step (start-up),
    # nothing to save.
    if proc.returncode not in (0, 128 + signal.SIGTERM, -signal.SIGTERM):
        raise RuntimeError(f"training failed ({proc.returncode}): {' '.join(map(str, cmd))}")
    return steps_done(work)


def steps_done(work):
    latest = work / "run" / "checkpoints" / "latest.pt"
    return checkpoint.load(latest)["step"] if latest.is_file() else 0


def read_log(work):
    """(seconds of training steps so far, {step: validation scores}) from the run's log.jsonl (0, {} before it)."""
    path = work / "run" / "log.jsonl"
    seconds, evals = 0.0, {}
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                e = json.loads(line)
            except ValueError:  # a line cut short by a hard kill
                continue
            seconds = e.get("seconds", seconds)
            if "eval" in e:
                evals[e["step"]] = e["eval"]
    return seconds, evals


def train_seconds(work):
    return read_log(work)[0]


def base_scores(base_tensors, cfg, work):
    """The base network's validation scores (what step 0 of the fine-tuning would score)."""
    eval_set, n, _ = data.load_split(work / "data", "val", cfg["layout"], Path(cfg["cache_dir"]))
    state = {k: torch.from_numpy(v.astype(np.float32)) for k, v in base_tensors.items()}
    return evaluate.heldout_scores(state, cfg, eval_set, n, "per_image")


# --------------------------------------------------------------------------
# The command
# --------------------------------------------------------------------------

def check_inputs(args):
    """(scene object, base path, base tensors, base config); AdaptError for anything that cannot work."""
    try:
        scene = ngi.Scene(args.scene)
    except ngi.Error as e:
        raise AdaptError(f"--scene {args.scene}: cannot be loaded: {e}") from None
    try:
        base = Path(ngi.resolve_model(args.base))
    except ngi.Error as e:
        raise AdaptError(f"--base {args.base}: {e}") from None
    tensors, config = model_file.read_model(str(base))
    if config.get("family") != "pix2pix_unet" or config.get("output_mode") != "ssgi_residual":
        raise AdaptError(f"--base {args.base}: a {config.get('family')} model of output mode "
                         f"{config.get('output_mode')}; adapt fine-tunes a pix2pix_unet that corrects SSGI "
                         "(output mode ssgi_residual)")
    if N % (1 << int(config["num_downs"])):
        raise AdaptError(f"--base {args.base}: num_downs {config['num_downs']} cannot run at N = {N}")
    if "config" not in config.get("training", {}):
        raise AdaptError(f"--base {args.base}: its file holds no training config (not exported by "
                         "ngi_train.generator.export), so its recipe is unknown")
    if importlib.util.find_spec("tqdm") is None:  # the training child's progress bar (ngi_train.generator.train)
        raise AdaptError("the training needs the Python package tqdm (Debian: python3-tqdm; pip install tqdm)")
    out = Path(args.out)
    if out.suffix != ".safetensors":
        raise AdaptError(f"--out {out}: must end in .safetensors")
    if out.exists() and not out.is_file():
        raise AdaptError(f"--out {out}: exists and is not a file")
    return scene, base, tensors, config


def file_digest(path):
    """A file's sha256 (16 hex digits, as ngi.plan --adapted compares it: ngi.zoo.sha256); a procedural spec as is."""
    return zoo_mod.sha256(path)[:16] if Path(path).is_file() else str(path)


def default_work(scene):
    """The work folder of a scene without --work: runs/adapt/<stem> in a checkout, else the user's cache
    (AdaptError when there is none: no absolute $XDG_CACHE_HOME or $HOME)."""
    stem = Path(scene).stem if Path(scene).suffix else scene.replace(":", "_").replace("=", "")
    try:
        root = ngi_paths.REPO / "runs" if ngi_paths.REPO is not None else ngi_paths.user_cache_dir()
    except ngi_paths.CacheDirError as e:
        raise AdaptError(str(e)) from None
    return root / "adapt" / stem


def main(argv=None, prog=None):
    """The command (`prog`: its name in the usage line, `ngi adapt` when the CLI runs it); returns the exit code:
    0 written, 2 refused before any work (bad option, scene, base, budget), 130 interrupted (resumable)."""
    ap = argparse.ArgumentParser(prog=prog, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="a .vox or mesh file, or a procedural spec (room:seed=3)")
    ap.add_argument("--out", required=True, help="the adapted model (.safetensors; a card .md is written beside it)")
    ap.add_argument("--base", default=DEFAULT_BASE, help=f"the network to fine-tune (default {DEFAULT_BASE})")
    ap.add_argument("--budget-minutes", type=float, default=10.0, help="wall-clock budget, render + train (default 10)")
    ap.add_argument("--lr", type=float, default=FINE_TUNE_LR, help=f"fine-tuning learning rate (default {FINE_TUNE_LR:g})")
    ap.add_argument("--work", help="working folder (frames, checkpoints; default runs/adapt/<scene> in a checkout, "
                                   "else $XDG_CACHE_HOME/ngi/adapt/<scene> or ~/.cache/ngi/adapt/<scene>)")
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN, which `ngi adapt` sets to itself; else build*/ngi "
                                  "in a checkout, else the installation's bin/ngi, else PATH)")
    ap.add_argument("--device", help="OpenCL device of the renders (ngi --device)")
    ap.add_argument("--times", default="",
                    help="comma-separated times of day in hours (as ngi render --time, 0-48): the training and "
                         "validation views take them in turn, so that the network follows the sun (default: the "
                         "scene's own time only)")
    args = ap.parse_args(argv)
    try:
        args.times = [float(h) for h in args.times.split(",") if h.strip()]
    except ValueError:
        ap.error(f"--times {args.times!r}: comma-separated hours expected")
    if not all(math.isfinite(h) and 0 <= h <= 48 for h in args.times) or \
            len({time_suffix(h) for h in args.times}) != len(args.times):  # frame folders name them to 0.01 h
        ap.error(f"--times {args.times}: distinct hours in [0, 48] (to 0.01 h) expected")
    if not (math.isfinite(args.budget_minutes) and 0 < args.budget_minutes <= 24 * 60):
        ap.error("--budget-minutes must be in (0, 1440]")
    if not (math.isfinite(args.lr) and 0 < args.lr < 1):
        ap.error("--lr must be in (0, 1)")
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        return adapt(args)
    except AdaptError as e:
        print(f"adapt: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("adapt: interrupted; run the same command to resume", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def adapt(args):
    scene, base, base_tensors, base_config = check_inputs(args)
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    work = Path(args.work) if args.work else default_work(args.scene)
    work.mkdir(parents=True, exist_ok=True)
    identity = {"scene": scene.name, "scene_file": file_digest(args.scene), "base": file_digest(base),
                "budget_s": args.budget_minutes * 60.0, "lr": args.lr}
    if args.times:
        identity["times"] = args.times
    budget = Budget(work, args.budget_minutes * 60.0, identity)

    # --- 1. the cost of a frame, and whether the budget holds anything (on a fresh start; a resumed run goes on
    # with what is left, down to exporting what it has)
    data_dir = work / "data"
    fresh = not (data_dir / "val").is_dir()
    probe_t0 = time.monotonic()
    # The validation frames and one training frame within the render share, a minute of training, the export: the
    # first validation frame, rendered now, is the measure; it may take at most `allowed` seconds.
    views = len(VAL_FRAMES) + 1
    allowed = min(RENDER_SHARE * budget.seconds, budget.seconds - MIN_TRAIN_SECONDS - EXPORT_RESERVE_S) / views
    first_k, first_hours, first_name = val_views(args.times)[0]
    first = data_dir / "val" / first_name
    if fresh:
        too_small = (f"--budget-minutes {args.budget_minutes:g}: too small for {scene.name}: its {len(VAL_FRAMES)} "
                     f"validation frames and one training frame must fit in {100 * RENDER_SHARE:.0f} % of the budget "
                     f"with {MIN_TRAIN_SECONDS:.0f} s of training and {EXPORT_RESERVE_S:.0f} s to export, i.e. "
                     f"{max(allowed, 0):.1f} s per frame")
        if allowed <= 0:
            raise AdaptError(too_small)
        try:
            frame_s = render(ngi_bin, args.scene, first, first_k, VAL_PATH_SEED, "auto", REFERENCE_SPP,
                             FEATURE_SPP, N, args.device, timeout=allowed, hours=first_hours)
        except subprocess.TimeoutExpired:
            shutil.rmtree(data_dir, ignore_errors=True)
            raise AdaptError(f"{too_small}; one took longer") from None
        if frame_s > allowed:
            shutil.rmtree(data_dir, ignore_errors=True)
            raise AdaptError(f"{too_small}; one took {frame_s:.1f} s")
    else:
        frame_s = recorded_frame_seconds(first)
    log(f"{scene.name}: {frame_s:.1f} s per frame; budget {budget.seconds:.0f} s"
        + (f" ({budget.before:.0f} s spent before this run)" if budget.before else ""))
    budget.enter("render")
    budget.phase_t0 = probe_t0  # the cost probe is preparation too
    try:
        return run_phases(args, scene, base, base_tensors, base_config, ngi_bin, work, identity, budget, data_dir,
                          frame_s)
    finally:
        budget.close()  # an interrupted or failed run's time counts


def run_phases(args, scene, base, base_tensors, base_config, ngi_bin, work, identity, budget, data_dir, frame_s):
    out = Path(args.out)

    # --- 2. frames
    took = [frame_s]  # seconds of the renders: the loop below plans with their mean
    for k, hours, name in val_views(args.times):
        took.append(render(ngi_bin, args.scene, data_dir / "val" / name, k, VAL_PATH_SEED, "auto", REFERENCE_SPP,
                           FEATURE_SPP, N, args.device, hours=hours))
    took = [t for t in took if t > 0]
    budget.record()
    render_until = budget.seconds * RENDER_SHARE
    fly_ok, rendered = True, 0
    views = train_views(args.times)
    # A resumed run renders no more once rendering finished (training refuses another frame list) or training began.
    finished = budget.state.get("rendered") or steps_done(work) > 0
    while not finished and rendered < MAX_TRAIN_FRAMES and (
            rendered == 0 or budget.elapsed() + (np.mean(took) if took else frame_s) <= render_until):
        kind, seed, k, hours = next(views)
        if kind == "fly" and not fly_ok:
            continue
        # auto: the scene's own kind (orbit for a .vox file, fly for a family)
        name = f"{kind}_p{seed}_f{k:03d}" + time_suffix(hours)
        try:
            t = render(ngi_bin, args.scene, data_dir / "train" / name, k, seed, kind, REFERENCE_SPP, FEATURE_SPP, N,
                       args.device, hours=hours)
            if t > 0:
                took.append(t)
        except RuntimeError as e:
            if kind == "fly":  # a scene without room for a fly-through (make_camera_path refuses it)
                fly_ok = False
                log(f"no fly-through path in {scene.name} ({str(e).strip().splitlines()[-1][:160]}): training "
                    "views come from its own path kind only")
                continue
            raise
        rendered += 1
        budget.record()
        print(f"\radapt: {rendered} training frames, {budget.elapsed():.0f} / {render_until:.0f} s of rendering",
              end="", file=sys.stderr, flush=True)
    print("", file=sys.stderr)
    train_frames = data.list_frames(data_dir, "train")
    budget.state["rendered"] = True
    budget.close()

    # --- 3. fine-tuning
    budget.enter("train")
    cfg = train_config(base, base_config, work, args.lr)
    cfg_path = work / "train_config.json"
    checkpoint.write_text_atomic(cfg_path, json.dumps(cfg, indent=1) + "\n")
    train_deadline = time.monotonic() + budget.left() - EXPORT_RESERVE_S
    done = steps_done(work)
    startup = 10.0  # seconds a resumed train.py takes before its first step (measured below when it runs)
    rate = None     # steps per second of the steps themselves (the log's time; evaluations and saves count as start-up)
    while True:
        # Chunks until the deadline: the first measures the rate (its first steps are slow: warm-up), each later run
        # plans with the rate of the run before it, so the budget is filled within a chunk or so.
        t0, s0, before = time.monotonic(), done, train_seconds(work)
        if train_deadline - time.monotonic() <= 0:
            break
        if done < CHUNK_STEPS:
            target = CHUNK_STEPS
        else:
            room = train_deadline - time.monotonic() - startup
            target = done + (int(rate * room / CHUNK_STEPS) * CHUNK_STEPS if rate else CHUNK_STEPS)
            if target <= done or room <= 0:
                break
            log(f"training to step {target}" + (f" ({rate:.1f} steps/s)" if rate else ""))
        done = run_training(cfg_path, work, target, train_deadline, ngi_bin)
        budget.record()
        spent = train_seconds(work) - before
        if done <= s0 or time.monotonic() >= train_deadline:
            break
        rate = (done - s0) / max(1e-3, spent)
        startup = max(0.0, time.monotonic() - t0 - spent)
    budget.close()

    # --- 4. early stopping, export, card
    budget.enter("export")
    scores = read_log(work)[1]
    base_val = base_scores(base_tensors, cfg, work)
    ckpts = {s: work / "run" / "checkpoints" / f"step_{s:08d}.pt" for s in scores}
    candidates = {s: v for s, v in scores.items() if ckpts[s].is_file()}
    best = min(candidates, key=lambda s: candidates[s]["l1"]) if candidates else None
    use_base = best is None or candidates[best]["l1"] >= base_val["l1"]
    tmp = out.with_name(f".{out.name}.tmp")
    out.parent.mkdir(parents=True, exist_ok=True)
    if use_base:
        tensors, config = dict(base_tensors), json.loads(json.dumps(base_config))
    else:
        export.main(["--run", str(work / "run"), "--checkpoint", str(ckpts[best]), "--out", str(tmp), "--half",
                     "--eval-split", "val", "--eval-frames", "0"])
        tensors, config = model_file.read_model(str(tmp))
    budget.close()
    spent = dict(budget.state["spent"])
    config["adapt"] = {
        "scene": scene.name,
        "scene_file": Path(args.scene).name if Path(args.scene).suffix else None,
        "scene_digest": identity["scene_file"],
        "base": Path(base).stem,
        "base_digest": identity["base"],
        "budget_s": budget.seconds,
        "spent_s": {k: round(v, 1) for k, v in spent.items()},
        "frames": {"train": len(train_frames), "val": len(VAL_FRAMES), "n": N, "feature_spp": FEATURE_SPP,
                   "reference_spp": REFERENCE_SPP, "val_path_seed": VAL_PATH_SEED,
                   "train_path_seeds_from": TRAIN_PATH_SEED, "fly_paths": fly_ok,
                   "times_h": args.times or None},
        "steps": done,
        "lr": args.lr,
        "chosen_step": None if use_base else best,
        "validation": {"base": base_val, "chosen": base_val if use_base else candidates[best],
                       "curve": {str(s): scores[s]["l1"] for s in sorted(scores)}},
        "note": ("no fine-tuning step beat the base on the validation frames: the base's weights"
                 if use_base else f"the checkpoint of step {best}, the lowest validation L1"),
        "written": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }
    model_file.write_model(str(tmp), {k: np.asarray(v, np.float32) for k, v in tensors.items()}, config, half=True)
    tmp.replace(out)
    out.with_suffix(".md").write_text(card(config, out))
    log(f"wrote {out} ({config['adapt']['note']}); spent "
        + ", ".join(f"{k} {v:.0f} s" for k, v in spent.items()) + f" of {budget.seconds:.0f} s")
    return 0


def card(config, out):
    a = config["adapt"]
    v = a["validation"]
    times = ", ".join(f"{h:g} h" for h in a["frames"].get("times_h") or []) or "the scene's own"
    lines = [f"# {out.stem}: {a['base']} adapted to {a['scene']}", "",
             f"Written by `python3 -m ngi_train.adapt` on {a['written']}.", "",
             "| | |", "| --- | --- |",
             f"| scene | {a['scene']} ({a['scene_file'] or 'procedural'}, sha256 {a['scene_digest']}) |",
             f"| base | {a['base']} (sha256 {a['base_digest']}) |",
             f"| budget | {a['budget_s']:.0f} s; spent " + ", ".join(f"{k} {s:.0f} s" for k, s in a['spent_s'].items()) + " |",
             f"| frames | {a['frames']['train']} training, {a['frames']['val']} validation; N = {a['frames']['n']}, "
             f"direct light at {a['frames']['feature_spp']} spp, references at {a['frames']['reference_spp']} spp |",
             f"| times of day | {times} |",
             f"| steps | {a['steps']} (chosen: {a['chosen_step'] if a['chosen_step'] is not None else 'the base'}) |",
             f"| validation L1 (encoded front lightmap) | base {v['base']['l1']:.5f}, chosen {v['chosen']['l1']:.5f} |",
             "", a["note"] + ".", "",
             "Validation frames are views of another camera path than the training frames; the evaluation "
             "(ngi_train.adapt_eval, docs/ADAPT.md) scores on the scene's dataset path, which neither uses.", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())

"""Training checkpoints and the resumable step loop every trainer runs.

A checkpoint is one torch.save'd dict of what a bit-exact resume needs: the trainer's networks and optimizer
states, the number of steps done, torch's RNG state (dropout draws from it; the data order is a function of the
seed and the epoch, `epoch_order`), the accumulated training wall time and the run config. It is written to a
temporary file in the same folder, fsync'ed and renamed over the old one, so a crash or a second Ctrl-C during
the write leaves the previous checkpoint intact.

The loop (`run_steps`): a checkpoint every `checkpoint_every` steps, at the last step and after the step during
which SIGINT / SIGTERM arrived (then exit code 128 + the signal); a second signal stops at once. Running the same
command again resumes: `check_resumable` refuses a config that changes what a step computes, `rewrite_log` drops
the log lines of the steps after the checkpoint (they run again).
"""

import json
import os
import signal
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

FORMAT = 1


def save(path, state):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            torch.save(dict(state, format=FORMAT), f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        dir_fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def load(path):
    # Our own files (they hold Python ints, dicts and an RNG byte tensor); never load checkpoints you did
    # not write.
    state = torch.load(path, map_location="cpu")
    if state.get("format") != FORMAT:
        raise ValueError(f"{path}: checkpoint format {state.get('format')}, expected {FORMAT}")
    return state


class StopSignal:
    """First SIGINT/SIGTERM: finish the step, save a checkpoint, exit. Second: stop at once."""

    def __init__(self, quiet=False):
        self.signum = None
        self.quiet = quiet
        self.old = {s: signal.signal(s, self.handler) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(self, signum, frame):
        if self.signum is not None:
            self.restore()
            raise KeyboardInterrupt
        self.signum = signum
        if not self.quiet:
            print(f"\n{signal.Signals(signum).name}: saving a checkpoint after this step "
                  "(again to stop at once)", file=sys.stderr, flush=True)

    @property
    def requested(self):
        return self.signum is not None

    def restore(self):
        for s, h in self.old.items():
            signal.signal(s, h)


def epoch_order(seed, epoch, count):
    """The order in which one epoch visits `count` items: a function of (seed, epoch) only, so a resumed run needs
    no data RNG state."""
    return np.random.default_rng([seed, epoch]).permutation(count)


def check_resumable(old, new, resumable, folder, defaults=None):
    """Refuses (SystemExit) to resume a checkpoint trained with config `old` under config `new` when a key outside
    `resumable` (the keys that do not change what a step computes) differs; a key missing from `old` counts as its
    `defaults` value (a checkpoint from before the key existed)."""
    defaults = defaults or {}
    changed = sorted(k for k in set(old) | set(new)
                     if old.get(k, defaults.get(k)) != new.get(k) and k not in resumable)
    if changed:
        raise SystemExit(f"{folder}: the checkpoint was trained with other settings or data: "
                         + ", ".join(f"{k} {str(old.get(k))[:60]!r} -> {str(new.get(k))[:60]!r}" for k in changed)
                         + " (use another folder)")


def rewrite_log(path, max_step):
    """Keeps the lines of a JSON-lines log whose "step" is <= max_step: a resumed run repeats the steps after its
    checkpoint. A line cut short by a hard kill is dropped. Written atomically."""
    path = Path(path)
    if not path.is_file():
        return
    kept = []
    for line in path.read_text().splitlines():
        try:
            if line.strip() and json.loads(line).get("step", 0) <= max_step:
                kept.append(line)
        except ValueError:
            pass
    write_text_atomic(path, "".join(line + "\n" for line in kept))


def write_text_atomic(path, text):
    """`text` into `path` through a temporary file in the same folder, fsync'ed and renamed over it."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def run_steps(step, steps, advance, save, checkpoint_every, where, main=True):
    """The step loop of every trainer, from `step` (0, or a checkpoint's) to `steps`.

    advance(step, stop) runs step `step` + 1 (training and logging) and returns whether to stop after it:
    `stop.requested` in one process, the ranks' agreement in a distributed run (every rank must stop after the
    same step). save(step) writes the checkpoint: every `checkpoint_every` steps, after the last one and after a
    stop. Returns (steps done, exit code): 0, or 128 + the signal after a stop (the message names `where`, the
    checkpoint). `main`: this process reports (the other ranks of a distributed run are quiet)."""
    stop = StopSignal(quiet=not main)
    try:
        while step < steps:
            stopping = advance(step, stop)
            step += 1
            if step % checkpoint_every == 0 or step == steps or stopping:
                save(step)
            if stopping:
                if main:
                    print(f"stopped at step {step}; checkpoint {where} (run the same command to resume)",
                          file=sys.stderr)
                return step, 128 + (stop.signum or signal.SIGTERM)
    finally:
        stop.restore()
    return step, 0

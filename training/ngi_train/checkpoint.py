"""Training checkpoints: written atomically, holding everything a bit-exact resume needs.

A checkpoint is one torch.save'd dict: the generator, the discriminator and both Adam states, the number of
steps done, torch's CPU RNG state (dropout draws from it; the data order is a function of the seed and the
epoch, see train.py), the accumulated training wall time and the run config. It is written to a temporary
file in the same folder, fsync'ed and renamed over the old one, so a crash or a second Ctrl-C during the
write leaves the previous checkpoint intact.
"""

import os
import signal
import sys
import tempfile
from pathlib import Path

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
    """First SIGINT/SIGTERM: finish the step, save a checkpoint, exit. Second: stop at once.
    Shared by training/train.py and training/voxel_sh/train.py."""

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

    def restore(self):
        for s, h in self.old.items():
            signal.signal(s, h)

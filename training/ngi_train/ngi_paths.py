"""Where things are: the repository and the ngi command-line tool (and running it); how the training commands
report progress.

The training commands are modules of this package (`python3 -m ngi_train.generator.train ...`). What they share
with the converter and the parity tests (the model-file writer, the PyTorch reference networks) is the Python
package `ngi` (bindings/python/ngi), importable once a build has assembled it in <build>/python:
`PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.train ...`.
"""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]  # training/ngi_train/ngi_paths.py


def find_ngi(explicit=None):
    """The ngi binary: `explicit`, else $NGI_BIN, else the first of build*/ngi in the repository, else PATH."""
    candidates = [explicit, os.environ.get("NGI_BIN")]
    candidates += [str(p) for p in sorted(REPO.glob("build*/ngi"))]
    candidates.append(shutil.which("ngi"))
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return os.path.abspath(c)
    raise FileNotFoundError("cannot find the ngi binary: pass --ngi PATH or set NGI_BIN (build it with "
                            "cmake -S . -B build -G Ninja && ninja -C build ngi_cli)")


def ngi_env():
    """Environment for ngi subprocesses: kernel caches default to /tmp so repeated runs skip compilation."""
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", "/tmp/pocl-cache")
    env.setdefault("NGI_CACHE_DIR", "/tmp/ngi-cache")
    return env


def run(cmd, **kw):
    """Runs `cmd` (items str()-ed) with ngi_env(), output captured as text; returns (CompletedProcess, seconds).
    A non-zero exit raises RuntimeError with the command and its output."""
    t0 = time.monotonic()
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=ngi_env(), **kw)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
    return proc, time.monotonic() - t0


def progress_options():
    """tqdm keyword arguments of every training command's progress bar (ETA included) on stderr: redrawn in place
    four times a second on a terminal; in a log (stderr not a TTY) plain ASCII, at most every 30 s, so CI logs
    stay short."""
    tty = sys.stderr.isatty()
    interval = 0.25 if tty else 30.0
    # maxinterval >= mininterval: tqdm's monitor thread would otherwise force a redraw every 10 s.
    return {"file": sys.stderr, "mininterval": interval, "maxinterval": max(10.0, interval), "ascii": not tty,
            "dynamic_ncols": tty}

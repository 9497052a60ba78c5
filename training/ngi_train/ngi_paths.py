"""Where things are: the repository (when run from a checkout), this package, the user's cache and the ngi
command-line tool (and running it); how the training commands report progress.

The training commands are modules of this package (`python3 -m ngi_train.generator.train ...`). What they share
with the converter and the parity tests (the model-file writer, the PyTorch reference networks) is the Python
package `ngi` (bindings/python/ngi), importable once a build has assembled it in <build>/python:
`PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.train ...`.

Installed (`cmake --install`, the python3-ngi package, `pip install .`: the modules `ngi adapt` needs, listed in
installed.txt, beside the package `ngi`), there is no repository: REPO is None, and what adapt would put under it
goes to the user's cache (user_cache_dir()).
"""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

# The folder that holds this package: <checkout>/training, or an installation's Python folder
# (<prefix>/lib/python3/dist-packages, a virtual environment's site-packages). A child Python process that runs a
# module of this package gets it on its PYTHONPATH.
PACKAGE_PARENT = Path(__file__).resolve().parents[1]


def _checkout():
    """The repository this package is run from (training/ngi_train/ngi_paths.py of a tree with CMakeLists.txt), or
    None for an installed package."""
    root = PACKAGE_PARENT.parent
    return root if PACKAGE_PARENT.name == "training" and (root / "CMakeLists.txt").is_file() else None


REPO = _checkout()


class CacheDirError(RuntimeError):
    """The user's cache folder cannot be found (user_cache_dir()): no absolute $XDG_CACHE_HOME and no $HOME."""


def user_cache_dir():
    """$XDG_CACHE_HOME/ngi, else $HOME/.cache/ngi: the folder of ngi's own caches (the C++ program cache's default,
    ngi::program_cache_dir, without $NGI_CACHE_DIR). A relative $XDG_CACHE_HOME is ignored (the XDG Base Directory
    specification: such a value is invalid); CacheDirError when $HOME is not an absolute path either."""
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "ngi"
    home = os.environ.get("HOME", "")
    if not os.path.isabs(home):
        raise CacheDirError("cannot find the user's cache folder: neither $XDG_CACHE_HOME nor $HOME is an absolute "
                            f"path (XDG_CACHE_HOME={xdg!r}, HOME={home!r}); set one of them, or pass a folder "
                            "explicitly (ngi adapt --work DIR)")
    return Path(home) / ".cache" / "ngi"


def installed_ngi():
    """The ngi binary of the installation this package is part of, if there is one: ngi/ngi-cli beside this
    package (pip install .: the real binary, before <venv>/bin/ngi, the entry point that runs it), else
    <prefix>/bin/ngi beside <prefix>/lib/python3/dist-packages (cmake --install, the Debian packages). None in a
    checkout, and for a package too shallow to have a <prefix> (/app/ngi_train)."""
    if REPO is not None:
        return None
    candidates = [PACKAGE_PARENT / "ngi" / "ngi-cli"]
    if len(PACKAGE_PARENT.parents) > 2:
        candidates.append(PACKAGE_PARENT.parents[2] / "bin" / "ngi")
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return str(c)
    return None


def find_ngi(explicit=None):
    """The ngi binary: `explicit`, else $NGI_BIN (`ngi adapt` sets it to itself), else the first of build*/ngi in
    the repository, else the installation's own (installed_ngi()), else PATH."""
    candidates = [explicit, os.environ.get("NGI_BIN")]
    if REPO is not None:
        candidates += [str(p) for p in sorted(REPO.glob("build*/ngi"))]
    candidates += [installed_ngi(), shutil.which("ngi")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return os.path.abspath(c)
    raise FileNotFoundError("cannot find the ngi binary: pass --ngi PATH or set NGI_BIN (build it with "
                            "cmake -S . -B build -G Ninja && ninja -C build ngi_cli; an installation has it as "
                            "<prefix>/bin/ngi)")


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

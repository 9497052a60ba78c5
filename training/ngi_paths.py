"""Where things are: the repository, the modules the training code borrows, the ngi command-line tool.

The training scripts are plain files run with /usr/bin/python3 (`python3 training/train.py ...`); importing
this module puts tools/ (ngi_convert: the model file writer) and tests/parity/ (reference_models: the
PyTorch generator the C++ library is tested against) on sys.path.
"""

import os
import shutil
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
for _sub in ("tools", "tests/parity"):
    _path = str(REPO / _sub)
    if _path not in sys.path:
        sys.path.insert(0, _path)


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

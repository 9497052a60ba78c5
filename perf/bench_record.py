"""What every perf/ side-by-side script records with its numbers, in one place: the load average, the commit, paths
without the machine's prefix, and the JSON result printed to stdout (and written to --out)."""

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def log(text):
    """Progress and summaries go to stderr: stdout carries the JSON result only."""
    print(text, file=sys.stderr, flush=True)


def load():
    """The 1-, 5- and 15-minute load averages (a busy machine makes timings noise: recorded beside them)."""
    return [round(v, 2) for v in os.getloadavg()]


def git_head():
    try:
        return subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def relative(path):
    """A path as the JSON records it: relative to the repository when inside it, else its file name only (no
    machine paths in recorded results)."""
    p = Path(path).resolve()
    return str(p.relative_to(REPO)) if p.is_relative_to(REPO) else p.name


def emit(result, out=None):
    """Print the result as JSON on stdout and, with `out`, write the same text there."""
    text = json.dumps(result, indent=2)
    print(text)
    if out:
        with open(out, "w") as f:
            f.write(text + "\n")

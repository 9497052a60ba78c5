#!/usr/bin/python3
"""The training code is one package, imported as a package (ctest training_package, a few seconds).

    PYTHONPATH=training:build/python /usr/bin/python3 training/tests/test_package_layout.py

1. No Python file of the repository's training, tests, Python bindings or perf scripts edits sys.path (sys.path.insert / append /
   extend / assignment, site.addsitedir): modules are found through PYTHONPATH, never through the order of path
   edits (issue 30: five files did, and which `data` module won depended on it).
2. Every module of ngi_train imports from the package (no module relies on a script's own folder on the path).
3. Each family's commands are modules under ngi_train, and no loose training script is left beside the package.
4. What an installation ships of ngi_train (installed.txt: cmake --install, python3-ngi, pip install .) is exactly
   what `ngi adapt` imports (ngi_train.adapt and its training child ngi_train.generator.train, in a fresh
   interpreter), and run from the checkout the package knows its repository (ngi_paths.REPO).
"""

import importlib
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CHECKED = ("training", "tests", "bindings/python", "perf")
SYS_PATH_EDIT = re.compile(r"\bsys\.path\s*(\.\s*(insert|append|extend)\s*\(|\+?=[^=])|\bsite\.addsitedir\s*\(")
COMMANDS = ["ngi_train.generator.train", "ngi_train.generator.export", "ngi_train.generator.evaluate",
            "ngi_train.ao.train", "ngi_train.ao.evaluate", "ngi_train.neural_gi.train", "ngi_train.neural_gi.evaluate",
            "ngi_train.neural_gi.sequences", "ngi_train.voxel_sh.train", "ngi_train.voxel_sh.export",
            "ngi_train.voxel_sh.evaluate", "ngi_train.torchrun"]


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print(f"ok  {what}")


def python_files():
    for top in CHECKED:
        for path in sorted((REPO / top).rglob("*.py")):
            if "__pycache__" not in path.parts:
                yield path


def main():
    this = Path(__file__).resolve()
    edits = [f"{p.relative_to(REPO)}:{n}: {line.strip()}"
             for p in python_files() if p != this
             for n, line in enumerate(p.read_text().splitlines(), 1) if SYS_PATH_EDIT.search(line)]
    check(not edits, "no Python file in " + ", ".join(CHECKED) + " edits sys.path" + "".join(f"\n  {e}" for e in edits))

    import ngi_train
    package_dir = Path(ngi_train.__file__).parent
    check(package_dir == REPO / "training" / "ngi_train", f"ngi_train comes from the repository ({package_dir})")
    names = [m.name for m in pkgutil.walk_packages(ngi_train.__path__, "ngi_train.")]
    for name in names:
        importlib.import_module(name)
    check(len(names) >= 30, f"every module of ngi_train imports as a package ({len(names)} modules)")
    check(all(name in names for name in COMMANDS), "every training command is a module: " + ", ".join(COMMANDS))
    loose = sorted(str(p.relative_to(REPO)) for p in (REPO / "training").glob("*.py"))
    check(not loose, f"no loose scripts in training/ beside the package {loose}")

    from ngi_train import ngi_paths
    check(ngi_paths.REPO == REPO, f"ngi_paths.REPO is the checkout ({ngi_paths.REPO})")
    listed = {line.strip() for line in (package_dir / "installed.txt").read_text().splitlines()
              if line.strip() and not line.startswith("#")}
    files = subprocess.run([sys.executable, "-c", "import sys, ngi_train.adapt, ngi_train.generator.train\n"
                            "for n, m in sorted(sys.modules.items()):\n"
                            "    if n.split('.')[0] == 'ngi_train': print(m.__file__)"],
                           capture_output=True, text=True, check=True).stdout.split()
    imported = {Path(f).resolve().relative_to(package_dir).as_posix() for f in files}
    check(listed == imported, "installed.txt lists what ngi adapt imports (missing: "
          f"{sorted(imported - listed)}, not imported: {sorted(listed - imported)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

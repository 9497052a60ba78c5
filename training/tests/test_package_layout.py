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
5. pip's list of packages (setup.py, run with setuptools.setup captured) is installed.txt's: the folders of its
   modules, also for a list with a subpackage more (a copy of setup.py beside another installed.txt); a subpackage
   listed without its __init__.py is refused.
"""

import importlib
import json
import os
import pkgutil
import re
import shutil
import subprocess
import sys
import tempfile
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


# Runs setup.py (argv[1]) with setuptools.setup replaced by a recorder; prints the packages it was given.
SETUP_PACKAGES = ("import json, runpy, sys, setuptools\n"
                  "given = {}\n"
                  "setuptools.setup = lambda **kw: given.update(kw)\n"
                  "runpy.run_path(sys.argv[1], run_name='__main__')\n"
                  "print(json.dumps(given['packages']))\n")


def setup_packages(root, scratch):
    """(exit code, packages or the error) of `root`/setup.py; setuptools' staging folder under `scratch`."""
    env = dict(os.environ, NGI_PIP_BUILD_DIR=str(scratch))
    proc = subprocess.run([sys.executable, "-c", SETUP_PACKAGES, str(root / "setup.py")], capture_output=True,
                          text=True, env=env, cwd=scratch)
    return proc.returncode, json.loads(proc.stdout) if proc.returncode == 0 else proc.stderr


def packages_of(modules):
    """ngi and the ngi_train packages that hold `modules` (paths relative to training/ngi_train)."""
    return sorted({"ngi", "ngi_train"} | {".".join(("ngi_train",) + Path(m).parent.parts) for m in modules})


def check_pip_packages(listed):
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        got = setup_packages(REPO, tmp)
        check(got == (0, packages_of(listed)), f"setup.py's packages are installed.txt's folders ({got})")
        copy = tmp / "copy"
        (copy / "training" / "ngi_train").mkdir(parents=True)
        shutil.copy(REPO / "setup.py", copy)
        shutil.copy(REPO / "CMakeLists.txt", copy)  # its version
        more = sorted(listed) + ["ao/__init__.py", "ao/train.py"]
        (copy / "training" / "ngi_train" / "installed.txt").write_text("# one subpackage more\n" + "\n".join(more))
        got = setup_packages(copy, tmp)
        check(got == (0, packages_of(more)) and "ngi_train.ao" in got[1],
              f"setup.py follows installed.txt: a subpackage listed there is a package for pip ({got})")
        (copy / "training" / "ngi_train" / "installed.txt").write_text("\n".join(sorted(listed) + ["vox/x.py"]))
        code, err = setup_packages(copy, tmp)
        check(code != 0 and "vox/__init__.py" in err, f"a subpackage without its __init__.py is refused ({err!r})")


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
    check_pip_packages(listed)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""setuptools build step of `pip install .` (pyproject.toml): builds ngi with CMake and puts into the package
ngi (from bindings/python/ngi) its native module _ngi, the native command-line tool (ngi/ngi-cli, run by the `ngi`
entry point) and the shipped models (ngi/models, where model names find them: ngi.Model(dev, "surround")); beside
it, the modules of the training package ngi_train that `ngi adapt` runs (training/ngi_train/installed.txt; PyTorch
is the extra `adapt`: pip install .[adapt]).

Environment:
  NGI_PIP_BUILD_DIR=DIR   use this existing, built CMake tree (its python/ngi/_ngi*.so and ngi) as it is: no
                          configure, no build (a test need not build ngi again). Its module must match this Python.
  NGI_PIP_CMAKE_ARGS      extra arguments for the CMake configure of a fresh build (build-pip/cmake).
Without NGI_PIP_BUILD_DIR the build tree is build-pip/cmake (Release; no tests, benchmarks or GL viewer), kept for
the next install. setuptools' own staging goes to build-pip/ too (<NGI_PIP_BUILD_DIR>/pip when that is given),
never to setuptools' default ./build (the developers' CMake tree). A source tree that is not writable (a read-only
checkout, a mounted source) builds in the user's cache instead: ${XDG_CACHE_HOME:-~/.cache}/ngi/build-pip-<hash of
the source path>.
"""

import hashlib
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

ROOT = Path(__file__).resolve().parent
TRAIN = ROOT / "training" / "ngi_train"
# setuptools' staging (and, without NGI_PIP_BUILD_DIR, the CMake tree): build-pip/, or <NGI_PIP_BUILD_DIR>/pip.
PIP_DIR = ROOT / "build-pip"
if not os.access(ROOT, os.W_OK) and not os.access(PIP_DIR, os.W_OK):  # a read-only source tree
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    PIP_DIR = cache / "ngi" / ("build-pip-" + hashlib.sha256(str(ROOT).encode()).hexdigest()[:12])
if os.environ.get("NGI_PIP_BUILD_DIR"):
    PIP_DIR = Path(os.environ["NGI_PIP_BUILD_DIR"]).resolve() / "pip"
PIP_DIR.mkdir(parents=True, exist_ok=True)  # egg_info's egg_base must exist


def version():
    m = re.search(r"project\(ngi VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not m:
        sys.exit("setup.py: no 'project(ngi VERSION x.y.z' in CMakeLists.txt")
    return m.group(1)


def run(cmd):
    print("setup.py: " + " ".join(shlex.quote(str(c)) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True)


def cmake_tree():
    """The built CMake tree: NGI_PIP_BUILD_DIR as it is, else build-pip/cmake configured and built here."""
    given = os.environ.get("NGI_PIP_BUILD_DIR")
    if given:
        tree = Path(given).resolve()
        if not (tree / "CMakeCache.txt").is_file():
            sys.exit(f"setup.py: NGI_PIP_BUILD_DIR={given}: not a CMake build tree (no CMakeCache.txt)")
        return tree
    tree = PIP_DIR / "cmake"
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
    run(["cmake", "-S", ROOT, "-B", tree, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release", "-DNGI_BUILD_TESTS=OFF",
         "-DNGI_BUILD_PERF=OFF", "-DNGI_BUILD_GL_VIEWER=OFF", "-DNGI_SOURCE_MODELS_FALLBACK=OFF",
         f"-DPython_EXECUTABLE={sys.executable}", *shlex.split(os.environ.get("NGI_PIP_CMAKE_ARGS", ""))])
    run(["cmake", "--build", tree, "-j", jobs, "--target", "ngi_python", "ngi_cli"])
    return tree


def train_modules():
    """The ngi_train modules an installation ships (training/ngi_train/installed.txt), relative to the package."""
    lines = (TRAIN / "installed.txt").read_text().splitlines()
    return {line.strip() for line in lines if line.strip() and not line.startswith("#")}


def train_packages():
    """The packages of ngi_train an installation ships: those that hold installed.txt's modules (ngi_train,
    ngi_train.generator, ...), each with its __init__.py listed too."""
    modules = train_modules()
    packages = set()
    for m in modules:
        folders = Path(m).parent.parts
        packages.update(("ngi_train",) + folders[:i] for i in range(len(folders) + 1))
    for package in sorted(packages):
        init = Path(*package[1:], "__init__.py").as_posix()
        if init not in modules:
            sys.exit(f"setup.py: training/ngi_train/installed.txt lists modules of {'.'.join(package)}, not its {init}")
    return sorted(".".join(package) for package in packages)


class BuildWithCMake(build_py):
    """build_py, then the native module, the CLI and the models from the CMake tree into the staged package."""

    def find_package_modules(self, package, package_dir):
        """Of ngi_train, only the modules installed.txt lists (as cmake --install)."""
        modules = super().find_package_modules(package, package_dir)
        if package.split(".")[0] != "ngi_train":
            return modules
        keep = train_modules()
        return [m for m in modules if Path(m[2]).resolve().relative_to(TRAIN).as_posix() in keep]

    def run(self):
        super().run()
        tree = cmake_tree()
        pkg = Path(self.build_lib) / "ngi"
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        module = tree / "python" / "ngi" / f"_ngi{suffix}"
        if not module.is_file():
            found = sorted(p.name for p in (tree / "python" / "ngi").glob("_ngi*.so"))
            sys.exit(f"setup.py: {module} does not exist (found: {found or 'no native module'}): the tree was not "
                     f"built, or built for another Python than {sys.executable} ({suffix})")
        cli = tree / "ngi"
        if not cli.is_file():
            sys.exit(f"setup.py: {cli} does not exist: the CMake tree has no ngi command-line tool (target ngi_cli)")
        self.copy_file(str(module), str(pkg / module.name))
        # Modules the CMake build generates (not in bindings/python/ngi), e.g. constants printed from the C++ side.
        for gen in sorted((tree / "python" / "ngi").glob("*.py")):
            if not (pkg / gen.name).exists():
                self.copy_file(str(gen), str(pkg / gen.name))
        self.copy_file(str(cli), str(pkg / "ngi-cli"))
        models = pkg / "models"
        if models.exists():
            shutil.rmtree(models)
        for src in sorted((ROOT / "models").rglob("*")):
            if src.is_file() and (src.suffix in (".safetensors", ".md") or src.name == "zoo.json"):
                dst = models / src.relative_to(ROOT / "models")
                dst.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, dst)
        print(f"setup.py: staged {module.name}, ngi-cli and {sum(1 for _ in models.rglob('*.safetensors'))} models "
              f"from {tree}", flush=True)


class NativeDistribution(Distribution):
    """The wheel holds a native module: platform-specific (cp311-linux_x86_64), installed to platlib."""

    def has_ext_modules(self):
        return True


setup(
    version=version(),
    packages=["ngi", *train_packages()],
    package_dir={"ngi": "bindings/python/ngi", "ngi_train": "training/ngi_train"},
    package_data={"ngi": ["py.typed", "*.pyi"]},
    cmdclass={"build_py": BuildWithCMake},
    distclass=NativeDistribution,
    options={"build": {"build_base": str(PIP_DIR / "setuptools")}, "egg_info": {"egg_base": str(PIP_DIR)}},
    zip_safe=False,
)

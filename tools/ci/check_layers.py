#!/usr/bin/env python3
"""Fails on an #include that crosses ngi's layers the wrong way (ctest layer_check; docs/ARCHITECTURE.md "Map").

The rules, with CMakeLists.txt as the source of truth for which library compiles what and links what:
  1. Libraries: a file of library L includes private headers (host/src/...) only of L and of the libraries L links
     (target_link_libraries). A file belongs to the library of its directory: base, runtime, ops, graph, models
     -> ngi_core; io -> ngi_io; pipeline -> ngi_pipeline; render -> ngi_render. CMakeLists.txt must build each
     library from its directories' globs alone (a source list that adds or removes single files is a violation:
     the directories are the libraries).
  2. Inside ngi_core, directories are ordered base < runtime < ops < graph < models (an op knows kernels, not
     graphs; a graph knows ops, not model files; base holds conventions, file access, .npy and the host-memory
     limit).
  3. Public headers (host/include/ngi) include only public headers; the applications and bindings (samples/,
     bindings/) include only public headers (ngi/*.hpp, ngi.h) and their own.
  4. docs/ARCHITECTURE.md's map names every directory `git ls-files` has (top level; host/src, bindings, samples
     and training one level down), and every directory it names exists.
Usage: check_layers.py [REPO_ROOT]   (prints every violation; exit 1 if any)
"""
import re
import sys
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
CORE_DIR_RANK = {"base": 0, "runtime": 1, "ops": 2, "graph": 3, "models": 4}
DIR_LIBRARY = {"base": "ngi_core", "runtime": "ngi_core", "ops": "ngi_core", "graph": "ngi_core", "models": "ngi_core",
               "io": "ngi_io", "pipeline": "ngi_pipeline", "render": "ngi_render"}
CLIENT_DIRS = ["samples", "bindings"]
# Build-time tools inside a client directory that read the library's internals by design: the generator of the
# Python package's constants module (ngi/_constants.py) exists to copy the values the kernels are built with.
CLIENT_EXEMPT = {"bindings/python/constants/gen_constants.cpp"}


def cmake_facts(root):
    """({library: libraries it may include from}, [problems]): the link lists, and any source list of CMakeLists.txt
    that names single files of host/src instead of globbing directories."""
    text = (root / "CMakeLists.txt").read_text()
    problems = []
    for m in re.finditer(r"(?:list\((APPEND|REMOVE_ITEM) NGI_\w+_SOURCES|(target_sources)\(ngi_(?:core|io|pipeline|render)\b)(.*?)\)",
                         text, re.S):
        for f in re.findall(r"(?:\$\{NGI_SRC\}|host/src)/([\w/]+\.cpp)", m.group(3)):
            how = f"list({m.group(1)} ...)" if m.group(1) else "target_sources(...)"
            problems.append(f"CMakeLists.txt: {how} moves host/src/{f} between libraries: "
                            "a library is its directories (move the file instead)")
    links = {lib: {lib} for lib in set(DIR_LIBRARY.values())}
    for lib, args in re.findall(r"target_link_libraries\((ngi_core|ngi_io|ngi_pipeline|ngi_render)\b(.*?)\)", text, re.S):
        links[lib] |= set(re.findall(r"\bngi_(?:core|io|pipeline|render)\b", args))
    return links, problems


def library_of(rel):
    """rel: a path under host/src ("io/exr.cpp", "base/npy.hpp")."""
    return DIR_LIBRARY.get(rel.split("/")[0])


def core_rank(rel):
    return CORE_DIR_RANK.get(rel.split("/")[0], 0)


def check_map(root):
    """docs/ARCHITECTURE.md's map names every directory of the repository, and every path it names exists."""
    text = (root / "docs" / "ARCHITECTURE.md").read_text()
    m = re.search(r"## Map\n.*?```\n(.*?)```", text, re.S)
    if not m:
        return ["docs/ARCHITECTURE.md: no '## Map' section with a code block"]
    block = m.group(1)
    problems = []
    for line in block.splitlines()[1:]:  # the first line is the column header
        for name in re.split(r",\s*", line[:20].strip()):
            if name.endswith("/") and not (root / name).is_dir():
                problems.append(f"docs/ARCHITECTURE.md map: {name} does not exist")
    import subprocess
    files = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True).stdout.split()
    dirs = set()
    for f in files:
        parts = f.split("/")
        if len(parts) > 1:
            dirs.add(parts[0] + "/")
        if len(parts) > 2 and parts[0] in ("bindings", "samples", "training"):
            dirs.add("/".join(parts[:2]) + "/")
        if len(parts) > 3 and parts[:2] == ["host", "src"]:
            dirs.add("/".join(parts[:3]) + "/")
    for d in sorted(dirs):
        if d not in block:
            problems.append(f"docs/ARCHITECTURE.md map: the directory {d} (git ls-files) is not on the map")
    return problems


def includes(path):
    text = path.read_text(errors="replace")
    for m in INCLUDE.finditer(text):
        yield text.count("\n", 0, m.start()) + 1, m.group(1)


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2]).resolve()
    src = root / "host" / "src"
    links, problems = cmake_facts(root)
    for f in sorted(src.rglob("*")):
        if f.suffix not in (".cpp", ".hpp"):
            continue
        rel = f.relative_to(src).as_posix()
        lib = library_of(rel)
        if lib is None:
            problems.append(f"host/src/{rel}: in no library's directory ({', '.join(sorted(DIR_LIBRARY))})")
            continue
        for line, inc in includes(f):
            if inc.startswith("ngi/") or inc == "ngi.h":
                continue
            if not (src / inc).exists():
                continue  # generated or a sibling's relative include: not a layer question
            target = library_of(inc)
            where = f"host/src/{rel}:{line}: #include \"{inc}\""
            if target not in links[lib]:
                problems.append(f"{where}: {lib} does not link {target} (CMakeLists.txt target_link_libraries)")
            elif lib == target == "ngi_core" and core_rank(inc) > core_rank(rel):
                problems.append(f"{where}: {rel.split('/')[0]} is below {inc.split('/')[0]} inside ngi_core "
                                "(runtime < ops < graph < models)")
    for f in sorted((root / "host" / "include" / "ngi").glob("*.hpp")):
        for line, inc in includes(f):
            if not inc.startswith("ngi/"):
                problems.append(f"host/include/ngi/{f.name}:{line}: #include \"{inc}\": a public header includes "
                                "only public headers")
    for d in CLIENT_DIRS:
        for f in sorted((root / d).rglob("*")):
            if f.suffix not in (".c", ".cpp", ".hpp", ".h") or f.relative_to(root).as_posix() in CLIENT_EXEMPT:
                continue
            for line, inc in includes(f):
                if inc.startswith("ngi/") or inc == "ngi.h" or (f.parent / inc).exists():
                    continue
                problems.append(f"{f.relative_to(root).as_posix()}:{line}: #include \"{inc}\": {d}/ uses the "
                                "public API only (ngi/*.hpp, ngi.h) and its own headers")
    problems += check_map(root)
    for p in problems:
        print(p)
    files = sum(1 for f in src.rglob("*") if f.suffix in (".cpp", ".hpp"))
    print(f"check_layers: {len(problems)} violation(s) in {files} library files, the public headers, "
          f"{' and '.join(CLIENT_DIRS)}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

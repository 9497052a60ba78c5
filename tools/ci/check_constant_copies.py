#!/usr/bin/env python3
"""Fails when a Python module or a kernel file carries its own copy of a value the library defines once
(ctest constant_copies).

The table of shared values is the generated module ngi/_constants.py (bindings/python/constants/gen_constants.cpp
prints it from the C++ definitions the kernels are built with). A copy is found by value, not by a phrase:
  - Python (bindings/python, training, perf, tests, fuzz, tools): a module- or class-level assignment of a literal
    whose name is one of the table's names, or whose float value (or tuple of floats) is one of the table's
    non-integer values -- LIGHT_MAX = 65504.0 in a training module is a copy whether or not a comment says so;
  - kernels (kernels/*.cl): `#define NAME literal` or `constant float NAME = literal` with a float value of the
    table (kernels get shared values as -D build options; runtime/kernel_defines.hpp).
Integer values are compared by name only: small integers (64, 1024) mean many unrelated things.
Usage: check_constant_copies.py REPO_ROOT CONSTANTS_PY   (prints every copy; exit 1 if any)
"""
import ast
import re
import sys
from pathlib import Path

PY_DIRS = ["bindings/python", "training", "perf", "tests", "fuzz", "tools"]
CL_DEFINE = re.compile(r"^\s*#\s*define\s+(\w+)\s+\(?\s*(-?[0-9][0-9.eE+-]*)f?\s*\)?\s*$", re.M)
CL_CONST = re.compile(r"\bconstant\s+float\s+(\w+)\s*=\s*(-?[0-9][0-9.eE+-]*)f?\s*;")
# Another concept that happens to have a table value, with the reason.
NOT_COPIES = {
    ("kernels/scene.cl", "T_INF"): "a ray's no-hit distance, not neural GI's radiance bound (both 1e30)",
}


def table(constants_py):
    """({name: value}, [float values]) of the generated module."""
    values = {}
    for node in ast.parse(Path(constants_py).read_text()).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            try:
                values[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                pass
    floats = []
    for v in values.values():
        items = v if isinstance(v, tuple) else (v,)
        if all(isinstance(x, float) for x in items) and any(x != int(x) or abs(x) >= 1e3 for x in items):
            floats.append(v)
    return values, floats


def same(a, b):
    if isinstance(a, tuple) or isinstance(b, tuple):
        return isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return isinstance(a, (int, float)) and isinstance(b, (int, float)) and float(a) == float(b)


def literal(node):
    try:
        v = ast.literal_eval(node)
    except (ValueError, SyntaxError, TypeError):
        return None
    if isinstance(v, bool):
        return None
    if isinstance(v, (int, float)) or (isinstance(v, tuple) and v and all(isinstance(x, (int, float)) for x in v)):
        return v
    return None


def python_copies(path, names, floats):
    try:
        tree = ast.parse(path.read_text(errors="replace"))
    except SyntaxError:
        return []
    found = []
    bodies = [tree.body] + [n.body for n in ast.walk(tree) if isinstance(n, ast.ClassDef)]
    for body in bodies:
        for node in body:
            if not (isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None):
                continue
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            value = literal(node.value)
            if value is None:
                continue
            for t in targets:
                if not isinstance(t, ast.Name):
                    continue
                by_name = t.id in names and same(value, names[t.id])
                by_value = isinstance(value, float) or isinstance(value, tuple)
                by_value = by_value and any(same(value, f) for f in floats)
                if by_name or by_value:
                    what = next((k for k, v in names.items() if same(value, v)), t.id)
                    found.append(f"{node.lineno}: {t.id} = {value!r} copies ngi._constants.{what}")
    return found


def kernel_copies(path, rel, floats):
    text = path.read_text(errors="replace")
    found = []
    for rx in (CL_DEFINE, CL_CONST):
        for m in rx.finditer(text):
            try:
                v = float(m.group(2))
            except ValueError:
                continue
            if (rel, m.group(1)) in NOT_COPIES:
                continue
            if any(same(v, f) for f in floats if not isinstance(f, tuple)):
                found.append(f"{text.count(chr(10), 0, m.start()) + 1}: {m.group(1)} = {m.group(2)} (a host value: pass "
                             "it as a build option)")
    return found


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    root, constants_py = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    names, floats = table(constants_py)
    if not names:
        sys.exit(f"check_constant_copies: no values in {constants_py}")
    problems, scanned = [], 0
    for d in PY_DIRS:
        for f in sorted((root / d).rglob("*.py")):
            if f.resolve() == constants_py or f.name == "_constants.py":
                continue
            scanned += 1
            problems += [f"{f.relative_to(root)}:{p}" for p in python_copies(f, names, floats)]
    for f in sorted((root / "kernels").glob("*.cl")):
        scanned += 1
        rel = f.relative_to(root).as_posix()
        problems += [f"{rel}:{p}" for p in kernel_copies(f, rel, floats)]
    for p in problems:
        print(p)
    print(f"check_constant_copies: {len(names)} shared values, {scanned} files, {len(problems)} copies", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Fails on a Catch2 test name ctest cannot register whole (ctest test_names).

The build registers every TEST_CASE as its own ctest test (catch_discover_tests); CMake lists are ';'-separated, so a
name with ';' becomes two tests that each run nothing of the case and fail ("No test cases matched"). Names with
'[' or ',' are fine; names may not start or end with blanks either (Catch2 trims them, ctest does not).
Usage: check_test_names.py REPO_ROOT   (prints every bad name; exit 1 if any)
"""
import re
import sys
from pathlib import Path

NAME = re.compile(r'\bTEST_CASE(?:_METHOD)?\s*\(\s*(?:\w+\s*,\s*)?((?:"(?:[^"\\]|\\.)*"\s*)+)', re.S)


def names(text):
    for m in NAME.finditer(text):
        parts = re.findall(r'"((?:[^"\\]|\\.)*)"', m.group(1))
        yield text.count("\n", 0, m.start()) + 1, "".join(parts)


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2])
    bad, seen = [], 0
    for f in sorted((root / "tests").rglob("*.cpp")):
        for line, name in names(f.read_text(errors="replace")):
            seen += 1
            if ";" in name or name != name.strip():
                bad.append(f"{f.relative_to(root)}:{line}: TEST_CASE name {name!r}: no ';' (ctest splits the name "
                           "there) and no leading or trailing blanks")
    for b in bad:
        print(b)
    print(f"check_test_names: {seen} test cases, {len(bad)} bad names", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

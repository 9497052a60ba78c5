#!/usr/bin/env python3
"""Fails when two .cpp files of one library define the same name with internal linkage (ctest unity_names).

Why: the sanitize stage builds the libraries as unity batches (NGI_UNITY_BUILD), where several .cpp files become one
translation unit; two `namespace { struct Builder ... }` in files that land in one batch are then a redefinition.
Which files share a batch depends on the file list, so a clash can sleep until an unrelated file is added (it did,
twice). This check does not depend on batches: each library's anonymous-namespace names must be unique.

What counts as a name: at the top level of an anonymous namespace, a struct / class / enum / union, a function
definition (a name followed by "(" whose declaration ends in "{" rather than ";") and a variable (with or without an
initializer); in any namespace (the file scope too), a `static` function or variable. Type aliases do not (`using Clock = ...` twice for one type is legal). Overloads that differ in
parameters are legal in one translation unit too, but they are reported: one name per concept per library also
reads more clearly.
Libraries (CMakeLists.txt): host/src/<dir> by directory (base, runtime, ops, graph, models -> ngi_core; io, pipeline,
render -> their own), bindings/c -> ngi_c.
Usage: check_unity_names.py [REPO_ROOT]   (prints every clash; exit 1 if any)
"""
import re
import sys
from collections import defaultdict
from pathlib import Path

DIR_LIBRARY = {"base": "ngi_core", "runtime": "ngi_core", "ops": "ngi_core", "graph": "ngi_core", "models": "ngi_core",
               "io": "ngi_io", "pipeline": "ngi_pipeline", "render": "ngi_render"}
TYPE = re.compile(r"^(?:template\s*<[^;{]*>\s*)?(?:struct|class|union|enum(?:\s+class)?)\s+(\w+)\s*[:{]")
FUNC = re.compile(r"^(?:template\s*<[^;{]*>\s*)?[\w:<>,\s\*&\[\]]*?\b(\w+)\s*\([^;]*?\)[^;()]*?\{", re.S)
VAR_DECL = re.compile(r"^(?:static\s+|inline\s+|thread_local\s+|const\s+|constexpr\s+)*[\w:<>,\s\*&]+?\b(\w+)\s*(?:\[[^\]]*\]\s*)*;$")
VAR = re.compile(r"^(?:static\s+|inline\s+|thread_local\s+)*(?:constexpr\s+|const\s+)*[\w:<>,\s\*&]+?\b(\w+)\s*(?:\[[^\]]*\]\s*)*(?:=|\{)")
KEYWORDS = {"if", "for", "while", "switch", "return", "operator", "sizeof", "static_assert"}


def strip(text):
    """The text with comments, string and character literals blanked (lengths kept, so braces count true)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c); i = j + 1
        else:
            out.append(c); i += 1
    return "".join(out)


def internal_names(path):
    """(name, line) of every definition with internal linkage at namespace scope in one file: anything at the top
    level of an anonymous namespace, and `static` functions and variables of any namespace (the file scope
    included)."""
    text = strip(path.read_text(errors="replace"))
    text = re.sub(r"^[ \t]*#.*$", lambda m: " " * len(m.group(0)), text, flags=re.M)  # preprocessor lines
    names = []
    scopes = []        # per open brace: "anon", "ns" (a named namespace) or "other" (class, function, extern, ...)
    stmt_start = 0     # where the current statement of the innermost namespace scope began
    for m in re.finditer(r"\bnamespace\s*(?:[\w:]+\s*)?\{|[{};]", text):
        tok, pos = m.group(0), m.start()
        at_ns_scope = not scopes or scopes[-1] != "other"
        if tok.startswith("namespace"):
            scopes.append("ns" if re.match(r"namespace\s*[\w:]", tok) else "anon")
            stmt_start = m.end()
            continue
        if at_ns_scope and tok in "{;":
            raw = text[stmt_start:pos + 1]
            stmt = raw.strip()
            line = text.count("\n", 0, stmt_start + len(raw) - len(raw.lstrip())) + 1
            internal = "anon" in scopes or stmt.startswith("static ")
            name = None
            rules = (TYPE, FUNC, VAR, VAR_DECL) if "anon" in scopes else (FUNC, VAR, VAR_DECL)
            for rx in rules if internal and not stmt.startswith(("using ", "typedef ")) else ():
                mm = rx.match(stmt)
                if mm and mm.group(1) not in KEYWORDS:
                    name = mm.group(1)
                    break
            if tok == ";" and (FUNC.match(stmt + "{") and "=" not in stmt.split("(")[0]):
                name = None      # a declaration, defined later in the file
            if name:
                names.append((name, line))
        if tok == "{":
            scopes.append("other")
        elif tok == "}":
            if scopes:
                scopes.pop()
            if not scopes or scopes[-1] != "other":
                stmt_start = pos + 1
        elif tok == ";" and at_ns_scope:
            stmt_start = pos + 1
    return names


def library_files(root):
    libs = defaultdict(list)
    src = root / "host" / "src"
    for f in sorted(src.rglob("*.cpp")):
        rel = f.relative_to(src).as_posix()
        lib = DIR_LIBRARY.get(rel.split("/")[0])
        if lib:
            libs[lib].append(f)
    libs["ngi_c"] = sorted((root / "bindings" / "c").glob("*.cpp"))
    return libs


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2]).resolve()
    problems, files = [], 0
    for lib, paths in sorted(library_files(root).items()):
        seen = defaultdict(list)
        for p in paths:
            files += 1
            for name, line in internal_names(p):
                seen[name].append(f"{p.relative_to(root).as_posix()}:{line}")
        for name, where in sorted(seen.items()):
            if len({w.split(':')[0] for w in where}) > 1:
                problems.append(f"{lib}: '{name}' is defined in the anonymous namespaces of {', '.join(where)} "
                                "(a unity batch joining them fails to compile: give one a distinct name or share it)")
    for p in problems:
        print(p)
    print(f"check_unity_names: {files} files, {len(problems)} clashes", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Which failed tests of the sanitize stage failed for reasons that are not ngi's (tools/test.sh).

Reads BUILD/Testing/Temporary/LastTest.log (ctest's log of the last run) and sorts every failed test into one of:

  tool crash    LeakSanitizer's ptrace-based tracer died at exit ("Tracer caught signal 11" ... "LeakSanitizer has
                encountered a fatal error") while PoCL's worker threads were exiting, after the test passed: no finding.
                Such a test must pass when run again.
  foreign leak  the only finding is leak reports none of whose allocation stacks has a frame of ngi's code (its
                sources under the repository root, or an ngi:: symbol). Seen on one machine of this project's kind:
                every process that used the device leaked 128 bytes "allocated from realloc <- (<unknown module>)"
                -- a library the OpenCL stack loaded and unloaded again, so no module name is left to suppress by
                (tools/ci/lsan.supp suppresses the driver's leaks by module name). Accepted, and listed.
  real          anything else: a leak with an ngi frame, an AddressSanitizer or UBSan error, a failed assertion, a
                timeout, or a failure with no sanitizer output at all.

Prints one line per failed test on stderr. Exit status: 0 when no failure is real and none needs a rerun; 3 when no
failure is real but tool crashes need one (tools/test.sh then runs ctest --rerun-failed and calls this again on that
run's log); 1 when a failure is real or the log shows no failed test.
Usage: sanitizer_triage.py BUILD_DIR [REPOSITORY_ROOT]   (root: default the parent of tools/)
"""
import re
import sys
from pathlib import Path

TOOL_CRASH = "LeakSanitizer has encountered a fatal error"
LEAK_HEADER = "ERROR: LeakSanitizer: detected memory leaks"
OTHER_FINDINGS = ("ERROR: AddressSanitizer", "runtime error:", "FAILED:", "***Timeout", "Test timeout")
CATCH2_FAILED = re.compile(r"\| \d+ failed")  # Catch2's summary: "test cases: 2 | 1 passed | 1 failed"
LEAK_BLOCK = re.compile(r"^(?:Direct|Indirect) leak of .*?(?=^\s*$)", re.M | re.S)
FRAME = re.compile(r"^\s*#\d+ 0x[0-9a-f]+ (.*)$", re.M)


def blocks(log: str):
    """(name, output, passed) of every test in ctest's LastTest.log."""
    parts = re.split(r"^\d+/\d+ Testing: (.*)$", log, flags=re.M)
    for name, body in zip(parts[1::2], parts[2::2]):
        yield name.strip(), body, "Test Passed." in body


MODULE = re.compile(r"\s*\((?:[^()]*\+0x[0-9a-f]+|BuildId: [0-9a-f]+)\)")  # "(module+0xoffset)", "(BuildId: ..)"


def is_ngi_frame(frame: str, root: str) -> bool:
    """A frame in ngi's code: its function or source file says so ("ngi::", a path under root). The module a frame
    is in does not: clang links the sanitizer runtime into the executable, so the allocator's own frame ("in
    __interceptor_realloc (<root>/build-sanitize/tests/ngi_tests+0x..)") sits in ngi's binary. A frame nothing
    could symbolize ("#1 0x..  (<root>/.../ngi_tests+0x..)") may be ngi's code: it counts as ngi's."""
    if not frame.lstrip().startswith("in "):  # FRAME's group: what follows the address
        return root in frame
    location = MODULE.sub("", frame)
    return root in location or "ngi::" in location


def classify(body: str, root: str) -> str:
    """'tool crash', 'foreign leak' or 'real' for one failed test's output."""
    if any(f in body for f in OTHER_FINDINGS) or CATCH2_FAILED.search(body):
        return "real"
    if LEAK_HEADER in body:
        leaks = LEAK_BLOCK.findall(body + "\n\n")
        if not leaks:
            return "real"
        for leak in leaks:
            if any(is_ngi_frame(f, root) for f in FRAME.findall(leak)):
                return "real"
        return "foreign leak"
    if TOOL_CRASH in body:
        return "tool crash"
    return "real"


def main() -> int:
    build = Path(sys.argv[1])
    root = str(Path(sys.argv[2]).resolve()) if len(sys.argv) > 2 else str(Path(__file__).resolve().parents[2])
    log = (build / "Testing" / "Temporary" / "LastTest.log").read_text(errors="replace")
    failed = [(n, b) for n, b, ok in blocks(log) if not ok]
    if not failed:
        return 1
    kinds = {}
    for name, body in failed:
        kind = classify(body, root)
        kinds.setdefault(kind, []).append(name)
        print(f"{kind}: {name}", file=sys.stderr)
    if "real" in kinds:
        return 1
    if "foreign leak" in kinds:
        print(f"sanitize: {len(kinds['foreign leak'])} test(s) passed but leaked only in code that is not ngi's "
              "(no frame of ngi's sources in any allocation stack): accepted", file=sys.stderr)
    return 3 if "tool crash" in kinds else 0


if __name__ == "__main__":
    sys.exit(main())

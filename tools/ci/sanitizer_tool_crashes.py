#!/usr/bin/python3
"""Which failed ctest tests failed only because LeakSanitizer itself crashed (tools/test.sh, sanitize stage).

LeakSanitizer stops every thread of the process with a ptrace-based tracer at exit. That tracer now and then
dies (signal 11) while PoCL's worker threads exit at the same moment: "Tracer caught signal 11" followed by
"LeakSanitizer has encountered a fatal error" -- after the test passed every assertion. That is a tool failure,
not a leak: no leak is reported. This script reads BUILD/Testing/Temporary/LastTest.log and prints the names of
the failed tests, then exits 0 only when every one of them shows the tool crash and none shows a real finding
(a leak report, an AddressSanitizer or UndefinedBehaviorSanitizer error, a failed Catch2 assertion, a timeout).
"""
import re
import sys
from pathlib import Path

TOOL_CRASH = "LeakSanitizer has encountered a fatal error"
FINDINGS = ("ERROR: LeakSanitizer: detected memory leaks", "ERROR: AddressSanitizer", "runtime error:",
            "FAILED:", "***Timeout", "Test timeout")
CATCH2_FAILED = re.compile(r"\| \d+ failed")  # Catch2's summary: "test cases: 2 | 1 passed | 1 failed"


def blocks(log: str):
    """(name, output, passed) of every test in ctest's LastTest.log."""
    parts = re.split(r"^\d+/\d+ Testing: (.*)$", log, flags=re.M)
    for name, body in zip(parts[1::2], parts[2::2]):
        yield name.strip(), body, "Test Passed." in body


def main() -> int:
    log = (Path(sys.argv[1]) / "Testing" / "Temporary" / "LastTest.log").read_text(errors="replace")
    failed = [(n, b) for n, b, ok in blocks(log) if not ok]
    if not failed:
        return 1
    only_tool = True
    for name, body in failed:
        crash = TOOL_CRASH in body and not any(f in body for f in FINDINGS) and not CATCH2_FAILED.search(body)
        print(f"{'LeakSanitizer crashed' if crash else 'real failure'}: {name}", file=sys.stderr)
        only_tool &= crash
    return 0 if only_tool else 1


if __name__ == "__main__":
    sys.exit(main())

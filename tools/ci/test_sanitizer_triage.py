"""tools/ci/sanitizer_triage.py on synthetic ctest logs: each kind of failure, and mixes of them."""
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).with_name("sanitizer_triage.py")
ROOT = "/tmp/clone"

PASSED = """1/3 Testing: host only
Test command: /tmp/clone/build-sanitize/tests/ngi_tests "host only"
All tests passed (3 assertions in 1 test case)
Test Passed.
"""

# As CI printed it on a machine whose OpenCL stack unloaded the library that had allocated (stop 22).
FOREIGN_LEAK = """2/3 Testing: conv2d matches the naive reference on random shapes
All tests passed (96 assertions in 1 test case)

=================================================================
==7076==ERROR: LeakSanitizer: detected memory leaks

Direct leak of 128 byte(s) in 1 object(s) allocated from:
    #0 0x7f2b318b78d5 in __interceptor_realloc ../../../../src/libsanitizer/asan/asan_malloc_linux.cpp:85
    #1 0x7f2b19af3f45  (<unknown module>)

SUMMARY: AddressSanitizer: 128 byte(s) leaked in 1 allocation(s).
Test Failed.
"""

# The same leak with clang's runtime (linked into the test program, so the allocator's frame names it), stop 35.
CLANG_FOREIGN_LEAK = """2/3 Testing: conv2d matches the naive reference on random shapes
All tests passed (96 assertions in 1 test case)

==29501==ERROR: LeakSanitizer: detected memory leaks

Direct leak of 128 byte(s) in 1 object(s) allocated from:
    #0 0x55a788c220d6 in __interceptor_realloc (/tmp/clone/build-sanitize/tests/ngi_tests+0x61c0d6) (BuildId: a2c185f669e728fe15e650252217eccd6928df48)
    #1 0x7fcefc8f3f45  (<unknown module>)

SUMMARY: AddressSanitizer: 128 byte(s) leaked in 1 allocation(s).
Test Failed.
"""

# Nothing symbolized (no llvm-symbolizer): a frame in ngi's program may be ngi's code.
UNSYMBOLIZED_LEAK = """2/3 Testing: conv2d matches the naive reference on random shapes
==28443==ERROR: LeakSanitizer: detected memory leaks

Direct leak of 128 byte(s) in 1 object(s) allocated from:
    #0 0x55d7be0780d6  (/tmp/clone/build-sanitize/tests/ngi_tests+0x61c0d6) (BuildId: a2c185f669e728fe15e650252217eccd6928df48)
    #1 0x7ff6340f3f45  (<unknown module>)

SUMMARY: AddressSanitizer: 128 byte(s) leaked in 1 allocation(s).
Test Failed.
"""

NGI_LEAK = """3/3 Testing: model loads
All tests passed (5 assertions in 1 test case)

==7080==ERROR: LeakSanitizer: detected memory leaks

Direct leak of 128 byte(s) in 1 object(s) allocated from:
    #0 0x7f2b318b78d5 in __interceptor_realloc ../../../../src/libsanitizer/asan/asan_malloc_linux.cpp:85
    #1 0x7f2b19af3f45  (<unknown module>)

Direct leak of 64 byte(s) in 1 object(s) allocated from:
    #0 0x7f2b318b7000 in operator new(unsigned long) ../../../../src/libsanitizer/asan/asan_new_delete.cpp:95
    #1 0x55d0c0de0001 in ngi::Model::load(ngi::Device const&, std::string const&) /tmp/clone/host/src/models/model.cpp:42

SUMMARY: AddressSanitizer: 192 byte(s) leaked in 2 allocation(s).
Test Failed.
"""

TOOL_CRASH = """3/3 Testing: broken mlp model files
All tests passed (15 assertions in 1 test case)
Tracer caught signal 11: addr=0x0 pc=0x7f00 sp=0x7f00
==7090==LeakSanitizer has encountered a fatal error.
Test Failed.
"""

ASSERTION = """3/3 Testing: metrics
tests/test_metrics.cpp:10: FAILED:
test cases: 1 | 1 failed
Test Failed.
"""

UBSAN = """3/3 Testing: tone map
tone_map.cpp:12:5: runtime error: signed integer overflow
Test Failed.
"""

SILENT = """3/3 Testing: c_api
Test Failed.
"""


def triage(tmp_path, *tests):
    log = tmp_path / "build" / "Testing" / "Temporary" / "LastTest.log"
    log.parent.mkdir(parents=True)
    log.write_text("Start testing\n" + "".join(tests) + "End testing\n")
    return subprocess.run([sys.executable, str(SCRIPT), str(tmp_path / "build"), ROOT], capture_output=True,
                          text=True)


@pytest.mark.parametrize("tests, status", [
    ((PASSED, FOREIGN_LEAK), 0),             # accepted, no rerun
    ((PASSED, CLANG_FOREIGN_LEAK), 0),       # the allocator's frame in ngi's program is not ngi's code
    ((PASSED, UNSYMBOLIZED_LEAK), 1),        # a frame in ngi's program that nothing symbolized may be
    ((PASSED, TOOL_CRASH), 3),               # rerun
    ((FOREIGN_LEAK, TOOL_CRASH), 3),
    ((PASSED, NGI_LEAK), 1),                 # an ngi frame in one of the leaks: real
    ((FOREIGN_LEAK, ASSERTION), 1),
    ((PASSED, UBSAN), 1),
    ((PASSED, SILENT), 1),                   # a failure without sanitizer output is real
    ((PASSED,), 1),                          # nothing failed: nothing to triage
])
def test_status(tmp_path, tests, status):
    assert triage(tmp_path, *tests).returncode == status


def test_each_failure_is_named_with_its_kind(tmp_path):
    err = triage(tmp_path, PASSED, FOREIGN_LEAK, NGI_LEAK).stderr
    assert "foreign leak: conv2d matches the naive reference on random shapes" in err
    assert "real: model loads" in err
    assert "host only" not in err

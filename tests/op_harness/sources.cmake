# The op harness's sources (tests/op_harness/op_cases.hpp), compiled into ngi_tests (tests/CMakeLists.txt) and into
# perf/op_bench (perf/CMakeLists.txt), which builds without the test suite; both add host/src and tests/ to their
# include paths (the harness uses the ops' internal headers and the tests' references).
set(NGI_OP_HARNESS_SOURCES ${CMAKE_CURRENT_LIST_DIR}/guarded_buffer.cpp ${CMAKE_CURRENT_LIST_DIR}/op_cases.cpp)

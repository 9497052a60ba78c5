#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "test_support.hpp"

int main(int argc, char** argv) {
    const int rc = Catch::Session().run(argc, argv);
    // Release the OpenCL objects while the process is still whole: oclgrind 21.10 keeps per-thread API state in
    // thread_local objects, which exit() destroys before static destructors, so clRelease* from a static Device
    // wrote into freed memory and aborted the run ("corrupted double-linked list", found with valgrind).
    ngi::test::device_slot().reset();
    return rc;
}

// Catch2 runner. The device is released before main returns, while the OpenCL runtime is still intact.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "test_support.hpp"

int main(int argc, char** argv) {
    const int rc = Catch::Session().run(argc, argv);
    ngi::test::release_device();
    return rc;
}

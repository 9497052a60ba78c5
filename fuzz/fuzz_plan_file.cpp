// Plan JSON (samples/ngi/plan_file.cpp, read by `ngi lightmap --plan`): format, version, rung, model path, n,
// bn_mode, the per-frame switch. Relative model paths resolve under /fuzz (absent): the reader must refuse them
// with an ngi error, never crash.
#include "fuzz_common.hpp"
#include "plan_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        ngi_cli::Plan::parse(ngi::fuzz::bytes(data, size), "/fuzz/plan.json");
    });
}

// Dataset config JSON (host/src/render/dataset.cpp): keys, ranges, splits, seeds, scene spec strings.
#include "fuzz_common.hpp"
#include "ngi/dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        ngi::DatasetConfig::parse(ngi::fuzz::bytes(data, size), "/fuzz/dataset.json");
    });
}

// NumPy .npy reader (host/src/base/npy.cpp): header dict parsing, shapes, dtypes, size checks.
#include "fuzz_common.hpp"
#include "io/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        const ngi::Tensor t = ngi::detail::decode_npy(ngi::fuzz::bytes(data, size), "fuzz.npy");
        if (t.data.size() != ngi::Tensor::element_count(t.shape)) __builtin_trap();  // shape and data must agree
    });
}

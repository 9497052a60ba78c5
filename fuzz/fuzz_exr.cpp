// OpenEXR reader (host/src/io/exr.cpp): the header prescan, OpenEXR's decoder on an in-memory stream, windows.
#include "fuzz_common.hpp"
#include "io/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        std::vector<std::string> names;
        const ngi::Image img = ngi::detail::decode_exr(ngi::fuzz::bytes(data, size), "fuzz.exr", &names);
        if (img.data.size() != img.plane() * std::size_t(img.channels) || names.size() != std::size_t(img.channels))
            __builtin_trap();
    });
}

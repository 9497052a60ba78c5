// PNG reader (host/src/io/png.cpp): libpng through the in-memory reader, both encodings.
#include "fuzz_common.hpp"
#include "io/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        // The last byte of the input picks the encoding (a PNG ignores bytes after IEND), so both paths are run.
        const auto enc = size && (data[size - 1] & 1) ? ngi::PngEncoding::Srgb : ngi::PngEncoding::Linear;
        const ngi::Image img = ngi::detail::decode_png(ngi::fuzz::bytes(data, size), "fuzz.png", enc);
        if (img.channels < 1 || img.channels > 4 || img.data.size() != img.plane() * std::size_t(img.channels))
            __builtin_trap();
    });
}

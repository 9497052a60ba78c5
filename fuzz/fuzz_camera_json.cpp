// camera.json of a frame folder (host/src/io/frame_io.cpp): JSON, vec3 fields, the camera cluster check, the optional
// position and area light.
#include "fuzz_common.hpp"
#include "io/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        ngi::Frame frame;
        ngi::detail::decode_camera_json(ngi::fuzz::bytes(data, size), "camera.json", frame);
    });
}

// Files without a handle: a frame folder read straight into frame planes, and an image written as EXR, PNG or .npy.
#include "c_handles.hpp"
#include "ngi/image_io.hpp"

using namespace c_abi;

extern "C" {

ngi_status ngi_read_frame_planes(const char* folder, int faces, float* planes, size_t bytes, int* n, size_t* needed,
                                 unsigned* flags, float look[3], float up[3]) {
    return guarded(__func__, [&] {
        require(folder, "folder is NULL");
        require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces));
        const ngi::Frame frame = ngi::read_frame(folder);
        const std::size_t need = ngi::frame_planes_bytes(frame.n, faces);
        if (n) *n = frame.n;
        if (needed) *needed = need;
        const ngi::FrameDesc d = ngi::FrameDesc::of(frame, faces);
        if (flags) *flags = (d.has_emission ? unsigned(NGI_FRAME_EMISSION) : 0u) | (d.has_env ? unsigned(NGI_FRAME_ENV) : 0u);
        for (int i = 0; i < 3; ++i) {
            if (look) look[i] = d.look[i];
            if (up) up[i] = d.up[i];
        }
        if (!planes) return;
        require(bytes >= need, "bytes is " + std::to_string(bytes) + ", the frame's planes need " + std::to_string(need));
        const std::vector<float> packed = ngi::pack_frame_planes(frame, faces);
        std::memcpy(planes, packed.data(), need);
    });
}

ngi_status ngi_write_image(const char* path, const float* data, size_t bytes, int width, int height, int channels) {
    return guarded(__func__, [&] {
        require(path, "path is NULL");
        require(data, "data is NULL");
        require(channels > 0 && channels <= 4, "channels must be 1..4, got " + std::to_string(channels));
        const std::size_t need = image_bytes(channels, height, width);
        require(bytes >= need, "bytes is " + std::to_string(bytes) + ", the image needs " + std::to_string(need));
        ngi::Image im(width, height, channels);
        std::memcpy(im.data.data(), data, need);
        ngi::write_image(path, im);
    });
}

}  // extern "C"

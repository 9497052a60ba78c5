// Seed 001's ambient-occlusion networks (ngi::AoNetwork): normals in, AO out, on the host or on device buffers.
#include "c_handles.hpp"

using namespace c_abi;

namespace {
float ao_radius(float radius_px) {
    require(!std::isnan(radius_px) && radius_px < 1.0e6f, "radius_px " + std::to_string(radius_px) +
                                                              " is not a radius (negative = the trained one)");
    return radius_px < 0 ? -1.0f : radius_px;
}
}  // namespace

extern "C" {

ngi_status ngi_ao_load(ngi_device* device, const char* path, ngi_ao** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(path, "path is NULL");
        *out = track(std::make_unique<ngi_ao>(ngi::AoNetwork::load(d.device, path)));
    });
}

ngi_status ngi_ao_info(const ngi_ao* ao, float* trained_radius_px, int* trained_size, int* face_normals) {
    return guarded(__func__, [&] {
        const ngi::AoNetwork& a = live(ao, "ao").ao;
        if (trained_radius_px) *trained_radius_px = a.trained_radius_px();
        if (trained_size) *trained_size = a.trained_size();
        if (face_normals) *face_normals = a.normals() == "face";
    });
}

ngi_status ngi_ao_run(ngi_ao* ao, const float* normals, size_t normals_bytes, int height, int width, float radius_px,
                      float* result, size_t result_bytes) {
    return guarded(__func__, [&] {
        ngi_ao& a = live(ao, "ao");
        require(normals, "normals is NULL");
        require(result, "result is NULL");
        const float r = ao_radius(radius_px);
        const std::size_t in_need = image_bytes(3, height, width), out_need = image_bytes(1, height, width);
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_bytes(normals_bytes, in_need, "normals_bytes", "3x" + shape + " floats");
        require_bytes(result_bytes, out_need, "result_bytes", "1x" + shape + " floats");
        ngi::Image n(width, height, 3);
        std::memcpy(n.data.data(), normals, in_need);
        const ngi::Image y = a.ao.run(n, r);
        std::memcpy(result, y.data.data(), out_need);
    });
}

ngi_status ngi_ao_enqueue(ngi_ao* ao, ngi_buffer* normals, ngi_buffer* result, int height, int width, float radius_px) {
    return guarded(__func__, [&] {
        ngi_ao& a = live(ao, "ao");
        const ngi_buffer& in = live(normals, "normals");
        const ngi_buffer& out = live(result, "result");
        const float r = ao_radius(radius_px);
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_buffer(in, image_bytes(3, height, width), "normals", "3x" + shape + " floats");
        require_buffer(out, image_bytes(1, height, width), "result", "1x" + shape + " floats");
        a.ao.enqueue(in.buffer, out.buffer, height, width, r);
    });
}

ngi_status ngi_ao_retain(ngi_ao* ao) { return guarded(__func__, [&] { retain_handle(ao, "ao"); }); }
ngi_status ngi_ao_release(ngi_ao* ao) { return guarded(__func__, [&] { release_handle(ao, "ao"); }); }

}  // extern "C"

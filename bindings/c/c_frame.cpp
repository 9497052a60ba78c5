// Frames on the host (ngi::Frame): read from a frame folder or made from frame planes, given a camera position and an
// area light (what the Neural GI renderer and probe shading need), and queried or packed back into planes.
#include "c_handles.hpp"
#include "ngi/image_io.hpp"

using namespace c_abi;

namespace {

bool has_face(const ngi::Frame& f, int face) {
    const ngi::Image& d = f.get(ngi::Feature::Depth, ngi::Face(face));
    return d.width == f.n && d.height == f.n && f.n > 0;
}

int frame_faces(const ngi::Frame& f) {
    for (int face = 0; face < ngi::kFaceCount; ++face)
        if (!has_face(f, face)) return 1;
    return ngi::kFaceCount;
}

bool has_feature(const ngi::Frame& f, ngi::Feature k) { return !f.get(k, ngi::Face::Front).data.empty(); }

void require_faces(int faces) { require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces)); }

}  // namespace

extern "C" {

ngi_status ngi_frame_read(const char* folder, ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require(folder, "folder is NULL");
        *out = track(std::make_unique<ngi_frame>(ngi::read_frame(folder)));
    });
}

ngi_status ngi_frame_from_planes(int n, const float* planes, size_t planes_bytes, int faces, unsigned flags,
                                 const float look[3], const float up[3], ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require_face_size(n);
        require_faces(faces);
        require((flags & ~unsigned(NGI_FRAME_EMISSION | NGI_FRAME_ENV)) == 0,
                "flags " + std::to_string(flags) + " holds bits that are not ngi_frame_flags");
        require(planes, "planes is NULL");
        require_bytes(planes_bytes, ngi::frame_planes_bytes(n, faces), "planes_bytes", face_string(n, faces));
        ngi::FrameDesc desc;
        desc.faces = faces;
        desc.has_emission = (flags & NGI_FRAME_EMISSION) != 0;
        desc.has_env = (flags & NGI_FRAME_ENV) != 0;
        desc.look = vec3_arg(look, "look");
        desc.up = vec3_arg(up, "up");
        require_camera(desc.look, desc.up);
        *out = track(std::make_unique<ngi_frame>(ngi::unpack_frame_planes(planes, n, desc)));
    });
}

ngi_status ngi_frame_set_position(ngi_frame* frame, const float position[3]) {
    return guarded(__func__, [&] {
        ngi_frame& f = live(frame, "frame");
        f.frame.position = vec3_arg(position, "position");
    });
}

ngi_status ngi_frame_set_area_light(ngi_frame* frame, const float centre[3], const float half_u[3],
                                    const float half_v[3], const float radiance[3]) {
    return guarded(__func__, [&] {
        ngi_frame& f = live(frame, "frame");
        ngi::AreaLight light;
        light.centre = vec3_arg(centre, "centre");
        light.half_u = vec3_arg(half_u, "half_u");
        light.half_v = vec3_arg(half_v, "half_v");
        light.radiance = vec3_arg(radiance, "radiance");
        try {
            ngi::check_area_light(light, "-");
        } catch (const ngi::InputError& e) {  // the numbers are this call's arguments: "-: area light half_u ..."
            const std::string m = e.what();
            fail(NGI_ERROR_INVALID_ARGUMENT, m.rfind("-: ", 0) == 0 ? m.substr(3) : m);
        }
        if (light.enabled())
            f.frame.area_light = light;
        else
            f.frame.area_light.reset();
    });
}

ngi_status ngi_frame_info(const ngi_frame* frame, int* n, int* faces, unsigned* flags, int* has_position,
                          int* has_area_light) {
    return guarded(__func__, [&] {
        const ngi::Frame& f = live(frame, "frame").frame;
        if (n) *n = f.n;
        if (faces) *faces = frame_faces(f);
        if (flags)
            *flags = (has_feature(f, ngi::Feature::Emission) ? unsigned(NGI_FRAME_EMISSION) : 0u) |
                     (has_feature(f, ngi::Feature::Env) ? unsigned(NGI_FRAME_ENV) : 0u);
        if (has_position) *has_position = f.position.has_value();
        if (has_area_light) *has_area_light = f.area_light.has_value() && f.area_light->enabled();
    });
}

ngi_status ngi_frame_planes(const ngi_frame* frame, int faces, float* planes, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi::Frame& f = live(frame, "frame").frame;
        require_faces(faces);
        require(planes, "planes is NULL");
        require_bytes(bytes, ngi::frame_planes_bytes(f.n, faces), "bytes", face_string(f.n, faces));
        if (faces > frame_faces(f)) fail(NGI_ERROR_INPUT, "the frame holds the front face only, 6 faces were asked for");
        const std::vector<float> packed = ngi::pack_frame_planes(f, faces);
        std::memcpy(planes, packed.data(), packed.size() * sizeof(float));
    });
}

ngi_status ngi_frame_retain(ngi_frame* frame) { return guarded(__func__, [&] { retain_handle(frame, "frame"); }); }
ngi_status ngi_frame_release(ngi_frame* frame) { return guarded(__func__, [&] { release_handle(frame, "frame"); }); }

}  // extern "C"

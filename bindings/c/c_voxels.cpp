// Seed 004 on one voxel scene at one time of day (ngi::SceneVoxels): its surface voxels and their attributes, the
// path-traced field, a voxel_sh network's prediction, the LTF, frames rendered from the scene and probe shading.
#include "c_handles.hpp"

using namespace c_abi;

namespace {
std::size_t voxel_bytes(const ngi_voxels& v, int per_voxel) {
    return v.voxels.surface().size() * std::size_t(per_voxel) * sizeof(float);
}
std::string voxel_what(const ngi_voxels& v, int per_voxel) {
    return std::to_string(v.voxels.surface().size()) + " voxels x " + std::to_string(per_voxel) + " floats";
}
void copy_voxels(float* dst, const std::vector<float>& src) {
    if (dst) std::memcpy(dst, src.data(), src.size() * sizeof(float));
}
}  // namespace

extern "C" {

ngi_status ngi_voxels_new(ngi_device* device, const char* scene, float hours, ngi_voxels** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(scene, "scene is NULL");
        require(!std::isnan(hours) && hours <= 24.0f, "hours " + std::to_string(hours) +
                                                          " is not a time of day (0..24, negative = the scene's)");
        *out = track(std::make_unique<ngi_voxels>(ngi::SceneVoxels(d.device, ngi::make_scene(scene), hours)));
    });
}

ngi_status ngi_voxels_info(const ngi_voxels* voxels, int* count, int grid[3], float* hours) {
    return guarded(__func__, [&] {
        const ngi_voxels& v = live(voxels, "voxels");
        if (count) *count = int(v.voxels.surface().size());
        if (grid)
            for (int i = 0; i < 3; ++i) grid[i] = v.voxels.surface().grid[i];
        if (hours) *hours = v.voxels.hours();
    });
}

ngi_status ngi_voxels_attributes(const ngi_voxels* voxels, float* attributes, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi_voxels& v = live(voxels, "voxels");
        require(attributes, "attributes is NULL");
        require_bytes(bytes, voxel_bytes(v, ngi::kVoxelAttributes), "bytes", voxel_what(v, ngi::kVoxelAttributes));
        copy_voxels(attributes, v.voxels.surface().attributes);
    });
}

ngi_status ngi_voxels_field(ngi_voxels* voxels, const ngi_voxel_field_settings* settings, float* sh, size_t sh_bytes,
                            float* direct, size_t direct_bytes, float* lighting, size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        require(sh || direct || lighting, "sh, direct and lighting are all NULL: nothing to make");
        if (sh) require_bytes(sh_bytes, voxel_bytes(v, 27), "sh_bytes", voxel_what(v, 27));
        if (direct) require_bytes(direct_bytes, voxel_bytes(v, 3), "direct_bytes", voxel_what(v, 3));
        if (lighting) require_bytes(lighting_bytes, voxel_bytes(v, 3), "lighting_bytes", voxel_what(v, 3));
        const ngi_voxel_field_settings defaults = NGI_VOXEL_FIELD_DEFAULTS;
        const ngi_voxel_field_settings& c = settings ? *settings : defaults;
        constexpr int kMax = 1 << 20;
        const int root = int(std::lround(std::sqrt(double(std::max(c.directions, 0)))));
        require(c.directions >= 1 && c.directions <= kMax && root * root == c.directions,
                "settings->directions " + std::to_string(c.directions) + " is not a perfect square in 1..2^20");
        require(c.sun_rays >= 1 && c.sun_rays <= kMax,
                "settings->sun_rays " + std::to_string(c.sun_rays) + " is not in 1..2^20");
        require(c.point_samples >= 1 && c.point_samples <= kMax,
                "settings->point_samples " + std::to_string(c.point_samples) + " is not in 1..2^20");
        require(c.max_bounces >= 0 && c.max_bounces <= 64,
                "settings->max_bounces " + std::to_string(c.max_bounces) + " is not in 0..64");
        require(c.rr_start >= 0, "settings->rr_start " + std::to_string(c.rr_start) + " is negative");
        ngi::VoxelFieldSettings s;
        s.directions = c.directions;
        s.sun_rays = c.sun_rays;
        s.point_samples = c.point_samples;
        s.max_bounces = c.max_bounces;
        s.rr_start = c.rr_start;
        s.seed = c.seed;
        const ngi::VoxelField f = v.voxels.field(s);
        copy_voxels(sh, f.sh);
        copy_voxels(direct, f.direct);
        copy_voxels(lighting, f.lighting);
    });
}

ngi_status ngi_voxels_predict_sh(ngi_voxels* voxels, ngi_model* model, float* sh, size_t sh_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        ngi_model& m = live(model, "model");
        require(sh, "sh is NULL");
        v.voxels.check_sh_model(m.model);  // InputError: another family, another grid
        require_bytes(sh_bytes, voxel_bytes(v, 27), "sh_bytes", voxel_what(v, 27));
        ngi::RunInfo info;
        copy_voxels(sh, v.voxels.predict_sh(m.model, &info));
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_voxels_ltf(ngi_voxels* voxels, const float* direct, size_t direct_bytes, int bounces,
                          ngi_ltf_variant variant, int visibility, float* lighting, size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        require(direct, "direct is NULL");
        require(lighting, "lighting is NULL");
        require_bytes(direct_bytes, voxel_bytes(v, 3), "direct_bytes", voxel_what(v, 3));
        require_bytes(lighting_bytes, voxel_bytes(v, 3), "lighting_bytes", voxel_what(v, 3));
        require(bounces >= 0 && bounces <= 64, "bounces " + std::to_string(bounces) + " is not in 0..64");
        require(variant == NGI_LTF_PHYSICAL || variant == NGI_LTF_AS_WRITTEN,
                "variant " + std::to_string(int(variant)) + " is not an ngi_ltf_variant");
        require(visibility == 0 || visibility == 1, "visibility must be 0 or 1, got " + std::to_string(visibility));
        require(!visibility || variant == NGI_LTF_PHYSICAL,
                "visibility 1 needs NGI_LTF_PHYSICAL (the as-written LTF has no shadow term)");
        const std::vector<float> d(direct, direct + v.voxels.surface().size() * 3);
        copy_voxels(lighting, v.voxels.ltf(d, bounces,
                                           variant == NGI_LTF_PHYSICAL ? ngi::LtfVariant::Physical
                                                                       : ngi::LtfVariant::AsWritten,
                                           visibility != 0));
    });
}

ngi_status ngi_voxels_render_frame(ngi_voxels* voxels, const float position[3], const float look[3],
                                   const float up[3], int n, int feature_spp, unsigned seed, ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        ngi_voxels& v = live(voxels, "voxels");
        ngi::CameraPose pose;
        pose.position = vec3_arg(position, "position");
        pose.look = vec3_arg(look, "look");
        pose.up = vec3_arg(up, "up");
        require_camera(pose.look, pose.up);
        require_face_size(n);
        require(feature_spp >= 1 && feature_spp <= 65536, "feature_spp " + std::to_string(feature_spp) +
                                                               " is not in 1..65536");
        ngi::RenderSettings rs;
        rs.n = n;
        rs.feature_spp = feature_spp;
        rs.reference = false;
        rs.seed = seed;
        *out = track(std::make_unique<ngi_frame>(v.voxels.render(pose, rs)));
    });
}

ngi_status ngi_voxels_shade(ngi_voxels* voxels, const ngi_frame* frame, const float camera_position[3], ngi_face face,
                            const float* field, size_t field_bytes, ngi_voxel_field_kind kind, float* lighting,
                            size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        const ngi::Frame& f = live(frame, "frame").frame;
        require(int(face) >= 0 && int(face) < ngi::kFaceCount, "face " + std::to_string(int(face)) + " is not an ngi_face");
        require(kind == NGI_FIELD_SH || kind == NGI_FIELD_LIGHTING,
                "kind " + std::to_string(int(kind)) + " is not an ngi_voxel_field_kind");
        require(field, "field is NULL");
        require(lighting, "lighting is NULL");
        const int per_voxel = kind == NGI_FIELD_SH ? 27 : 3;
        require_bytes(field_bytes, voxel_bytes(v, per_voxel), "field_bytes", voxel_what(v, per_voxel));
        require_bytes(lighting_bytes, image_bytes(3, f.n, f.n), "lighting_bytes",
                      "a 3 x " + std::to_string(f.n) + " x " + std::to_string(f.n) + " image");
        glm::vec3 position;
        if (camera_position)
            position = vec3_arg(camera_position, "camera_position");
        else if (f.position)
            position = *f.position;
        else
            fail(NGI_ERROR_INPUT, "camera_position is NULL and the frame records no position");
        const std::vector<float> values(field, field + v.voxels.surface().size() * std::size_t(per_voxel));
        const ngi::Image im = v.voxels.shade(f, position, ngi::Face(int(face)), values,  // InputError: no such face
                                             kind == NGI_FIELD_SH ? ngi::VoxelFieldKind::Sh
                                                                  : ngi::VoxelFieldKind::Lighting);
        std::memcpy(lighting, im.data.data(), im.data.size() * sizeof(float));
    });
}

ngi_status ngi_voxels_retain(ngi_voxels* voxels) { return guarded(__func__, [&] { retain_handle(voxels, "voxels"); }); }
ngi_status ngi_voxels_release(ngi_voxels* voxels) { return guarded(__func__, [&] { release_handle(voxels, "voxels"); }); }

}  // extern "C"

// ngi/scene_voxels.hpp: seed 004 on one scene at one time of day, composed of the public objects that do the work
// (surface_voxels, Renderer, VoxelGi, Model); no computation of its own.
#include "ngi/scene_voxels.hpp"

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "ngi/error.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

struct SceneVoxels::Impl {
    Impl(const Device& d, VoxelScene s, float h)
        : device(d), scene(std::move(s)), hours(h < 0 ? scene.default_time : h),
          lighting(lighting_at(hours, scene.sun_azimuth)), voxels(surface_voxels(device, scene, lighting)),
          gi(device, voxels) {}

    Renderer& renderer() {  // uploads the scene at the first call that traces rays
        if (!renderer_) renderer_.emplace(device, scene);
        return *renderer_;
    }

    Device device;
    VoxelScene scene;
    float hours;
    Lighting lighting;
    SurfaceVoxels voxels;
    VoxelGi gi;
    std::optional<Renderer> renderer_;
};

namespace {
float checked_hours(float hours) {
    if (std::isnan(hours) || hours > 24.0f)
        throw InputError("scene voxels: hours " + std::to_string(hours) +
                         " is not a time of day (0..24, negative = the scene's)");
    return hours;
}
}  // namespace

SceneVoxels::SceneVoxels(const Device& device, VoxelScene scene, float hours)
    : impl_(std::make_unique<Impl>(device, std::move(scene), checked_hours(hours))) {}
SceneVoxels::~SceneVoxels() = default;
SceneVoxels::SceneVoxels(SceneVoxels&&) noexcept = default;
SceneVoxels& SceneVoxels::operator=(SceneVoxels&&) noexcept = default;

const VoxelScene& SceneVoxels::scene() const { return impl_->scene; }
float SceneVoxels::hours() const { return impl_->hours; }
const Lighting& SceneVoxels::lighting() const { return impl_->lighting; }
const SurfaceVoxels& SceneVoxels::surface() const { return impl_->voxels; }

VoxelField SceneVoxels::field(const VoxelFieldSettings& settings) {
    return impl_->renderer().render_voxel_field(impl_->voxels, impl_->lighting, settings);
}

void SceneVoxels::check_sh_model(const Model& model) const {
    const ModelConfig& c = model.config();
    if (c.family != "voxel_sh") throw InputError("the model's family is " + c.family + ", not voxel_sh");
    const glm::ivec3 g = impl_->voxels.grid;
    c.voxel_sh.check_grid(g.x, g.y, g.z);  // InputError naming both grids
}

std::vector<float> SceneVoxels::predict_sh(Model& model, RunInfo* info) {
    check_sh_model(model);
    Tensor in({int(impl_->voxels.size()), kVoxelAttributes});
    in.data = impl_->voxels.attributes;
    return model.run(in, info).data;
}

std::vector<float> SceneVoxels::ltf(const std::vector<float>& direct, int bounces, LtfVariant variant,
                                    bool visibility) {
    std::vector<std::uint32_t> mask;
    if (visibility) mask = impl_->renderer().voxel_visibility(impl_->voxels);
    return impl_->gi.ltf(direct, bounces, variant, visibility ? &mask : nullptr);
}

Frame SceneVoxels::render(const CameraPose& pose, const RenderSettings& settings) {
    Frame f = impl_->renderer().render(pose, impl_->lighting, settings);
    f.position = pose.position;
    return f;
}

Image SceneVoxels::shade(const Frame& frame, glm::vec3 camera_position, Face face, const std::vector<float>& field,
                         VoxelFieldKind kind) {
    const Image& depth = frame.get(Feature::Depth, face);
    if (!(depth.width == frame.n && depth.height == frame.n && frame.n > 0))
        throw InputError(std::string("the frame has no ") + face_name(face) + " face");
    return impl_->gi.shade(frame, camera_position, face, field, kind);
}

}  // namespace ngi

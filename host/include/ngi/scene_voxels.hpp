// Seed 004 on one voxel scene at one time of day, as one object: the scene, its lighting at that hour
// (lighting_at), its surface voxels (surface_voxels) and what works on them -- the path tracer for the ground-truth
// field, the visibility mask and frames (the scene is uploaded at the first call that traces rays), the LTF and probe
// shading (VoxelGi), and a voxel_sh network's prediction from the voxels' attributes. Each method is the step-by-step
// calls it names on these objects, so its results are theirs bit for bit. The C ABI's ngi_voxels is this object.
// The maths: ngi/voxel_field.hpp, ngi/voxel_gi.hpp, docs/VOXEL_FIELD.md, docs/VOXEL_LTF.md.
#pragma once
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/camera.hpp"
#include "ngi/device.hpp"
#include "ngi/image.hpp"
#include "ngi/model.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/voxel_field.hpp"
#include "ngi/voxel_gi.hpp"

namespace ngi {

// Used by one thread at a time, like every ngi object made from a Device.
class SceneVoxels {
public:
    // `hours`: the time of day (0..24), or negative for the scene's default_time. Throws InputError for a NaN or a
    // later hour, and as surface_voxels() does (a scene without surface voxels, beyond the limits of voxel_field.hpp).
    SceneVoxels(const Device& device, VoxelScene scene, float hours);
    ~SceneVoxels();
    SceneVoxels(SceneVoxels&&) noexcept;
    SceneVoxels& operator=(SceneVoxels&&) noexcept;

    const VoxelScene& scene() const;
    float hours() const;                   // the time of day in use (the scene's default for a negative one)
    const Lighting& lighting() const;      // lighting_at(hours(), scene().sun_azimuth)
    const SurfaceVoxels& surface() const;  // V voxels in increasing dense id; per-voxel arrays are [V][k]

    // Renderer::render_voxel_field: the path-traced ground truth of the surface voxels under lighting().
    VoxelField field(const VoxelFieldSettings& settings);

    // Throws InputError unless `model` is a voxel_sh model trained on this scene's grid (naming both grids).
    void check_sh_model(const Model& model) const;
    // The SH-27 field [V][27] a voxel_sh model predicts from the voxels' attributes [V][kVoxelAttributes]
    // (check_sh_model first).
    std::vector<float> predict_sh(Model& model, RunInfo* info = nullptr);

    // VoxelGi::ltf from the direct lighting [V][3]; `visibility` adds the renderer's voxel_visibility mask (the
    // Physical variant only).
    std::vector<float> ltf(const std::vector<float>& direct, int bounces, LtfVariant variant, bool visibility);

    // Renderer::render under lighting(); the frame records pose.position, the cluster centre shade() needs.
    Frame render(const CameraPose& pose, const RenderSettings& settings);

    // VoxelGi::shade of face `face` of `frame` taken from `camera_position`. Throws InputError "the frame has no
    // <face> face" when the frame lacks that face's n x n depth.
    Image shade(const Frame& frame, glm::vec3 camera_position, Face face, const std::vector<float>& field,
                VoxelFieldKind kind);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi

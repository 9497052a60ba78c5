// Keyframed camera fly-throughs for the dataset (the thesis: a keyframe every 25 frames, Blender's smooth
// interpolation). Positions follow a uniform Catmull-Rom spline through the keyframes; orientations are slerped
// between consecutive keyframes.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "ngi/render.hpp"
#include "ngi/scene.hpp"

namespace ngi {

struct CameraKey {
    glm::vec3 position{0.0f};
    glm::quat orientation{1, 0, 0, 0};  // camera space (look -z, up +y, right +x) to world
};

struct CameraPath {
    int interval = 25;  // frames from one keyframe to the next
    std::vector<CameraKey> keys;

    int frame_count() const { return keys.empty() ? 0 : int(keys.size() - 1) * interval + 1; }
    // Pose at a (possibly fractional) frame, clamped to [0, frame_count() - 1]; keyframe k is frame k * interval.
    CameraPose at(float frame) const;
};

// Whether the axis-aligned box of half-size `radius` around p is inside the grid and free of blocks.
bool clear_of_blocks(const VoxelScene& scene, glm::vec3 p, float radius);

// A fly-through of at least `frames` frames inside scene.camera's region: keyframes at least 0.5 m from every
// block, mutually visible, at most ~7 m apart, looking mostly horizontally (toward scene.camera.look if given,
// else along the direction of travel, with seeded variation); every interpolated position stays >= 0.3 m from
// blocks. Deterministic in (scene, frames, seed). Throws InputError if the scene has no room for a camera.
CameraPath make_camera_path(const VoxelScene& scene, int frames, std::uint32_t seed, int interval = 25);

}  // namespace ngi

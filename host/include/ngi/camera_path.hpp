// Keyframed camera fly-throughs for the dataset (the thesis: a keyframe every 25 frames, Blender's smooth
// interpolation). Positions follow a uniform Catmull-Rom spline through the keyframes; orientations are slerped
// between consecutive keyframes. Two kinds: a fly-through of the scene's free space (worlds: the procedural
// families) and an orbit around the occupied blocks (models: .vox files, mesh scenes). A scene's triangle mesh counts
// as the blocks it passes through or encloses (block resolution, conservative): every function below sees it so.
#pragma once
#include <cstdint>
#include <string>
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
// The same with the outside of the grid counted as air (an orbit camera may stand outside the grid).
bool clear_of_blocks_in_open_air(const VoxelScene& scene, glm::vec3 p, float radius);

// Share of the front face's n x n pixels (camera.hpp's 90-degree face of `pose`) whose primary ray hits a block:
// a host-side DDA over the grid (outside the grid is air, as in the tracer). 0 = the front view sees only sky.
float front_geometry_share(const VoxelScene& scene, const CameraPose& pose, int n);

// The most frames a camera path may have. The path search costs ~0.1-0.2 ms per frame at 25 frames per keyframe (each
// keyframe tries 80 hops, each checked for clearance every 0.1 m; a dead end anywhere restarts the whole walk),
// and it is built whole even to render one frame: `ngi render --path-frames 1000000` spent 69-205 s before frame 0.
// 10,000 frames take ~1.5 s; dataset entries and the CLI's --path-frames are bounded by the same number, so that
// every dataset frame can still be rendered alone. make_camera_path / make_orbit_path refuse more (InputError).
inline constexpr int kMaxPathFrames = 10000;

// Which automatic path: `Fly` = make_camera_path below, `Orbit` = make_orbit_path, `Auto` = Orbit when
// scene.camera.orbit (.vox files) and Fly otherwise (procedural scenes: their paths are what they always were).
enum class CameraPathKind { Auto, Fly, Orbit };
// "auto" | "fly" | "orbit"; throws InputError naming `what` (an option or a config key) for anything else.
CameraPathKind parse_camera_path_kind(const std::string& text, const std::string& what);
const char* camera_path_kind_name(CameraPathKind kind);

// A fly-through of at least `frames` frames inside scene.camera's region: keyframes at least 0.5 m from every
// block, mutually visible, at most ~7 m apart, looking mostly horizontally (toward scene.camera.look if given,
// else along the direction of travel, with seeded variation); every interpolated position stays >= 0.3 m from
// blocks. Deterministic in (scene, frames, seed). Throws InputError if the scene has no room for a camera.
CameraPath make_camera_path(const VoxelScene& scene, int frames, std::uint32_t seed, int interval = 25);

// An orbit of at least `frames` frames around the bounding box of the scene's solid blocks: a keyframe every
// ~48 degrees of azimuth (seeded start and direction), each looking at a point near the model's centre from a
// distance and elevation chosen among candidates (0.55-1.7 x the box's bounding-sphere radius, 5-50 degrees up)
// for the share of front-face pixels that see the model (front_geometry_share), with a preference for the
// farther ones and for staying near the previous keyframe's distance; keyframes stay inside scene.camera's region
// with 0.5 m of air around them, every interpolated position (half-frame steps) with 0.3 m, and no frame's front
// view is pure sky (else up to 8 other starts are tried). Deterministic in (scene, frames, seed).
// Throws InputError naming the scene if it has no solid block, or no room for the camera around the model.
CameraPath make_orbit_path(const VoxelScene& scene, int frames, std::uint32_t seed, int interval = 25);
// make_camera_path or make_orbit_path, by `kind` (Auto: by scene.camera.orbit).
CameraPath make_camera_path(const VoxelScene& scene, CameraPathKind kind, int frames, std::uint32_t seed,
                            int interval = 25);

}  // namespace ngi

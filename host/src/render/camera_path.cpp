// Automatic keyframed camera paths through the free space of a voxel scene.
#include "ngi/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>

#include "ngi/error.hpp"
#include "render/rand.hpp"

namespace ngi {
namespace {

constexpr float kKeyClearance = 0.5f;   // keyframes: half-size of the block-free box around the camera
constexpr float kPathClearance = 0.3f;  // every interpolated position
constexpr int kAttempts = 48;

glm::vec3 catmull_rom(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, float s) {
    const float s2 = s * s, s3 = s2 * s;
    return 0.5f * (2.0f * p1 + (p2 - p0) * s + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * s2 +
                   (3.0f * p1 - p0 - 3.0f * p2 + p3) * s3);
}

bool in_region(const VoxelScene& s, glm::vec3 p) {
    return glm::all(glm::greaterThanEqual(p, s.camera.region_lo)) && glm::all(glm::lessThanEqual(p, s.camera.region_hi));
}

bool segment_clear(const VoxelScene& s, glm::vec3 a, glm::vec3 b) {
    const int steps = int(std::ceil(glm::length(b - a) / 0.1f));
    for (int i = 1; i <= steps; ++i)
        if (!clear_of_blocks(s, glm::mix(a, b, float(i) / float(steps)), kPathClearance + 0.05f)) return false;
    return true;
}

glm::quat orientation(float yaw, float pitch) {
    const glm::vec3 look(std::cos(pitch) * std::cos(yaw), std::sin(pitch), std::cos(pitch) * std::sin(yaw));
    return glm::quatLookAtRH(look, glm::vec3(0, 1, 0));  // columns right, up, -look: camera space -> world
}

float yaw_of(glm::vec3 d) { return std::atan2(d.z, d.x); }

}  // namespace

CameraPose CameraPath::at(float frame) const {
    if (keys.empty()) throw Error("CameraPath::at: the path has no keyframes");
    CameraPose pose;
    glm::quat q = keys[0].orientation;
    pose.position = keys[0].position;
    if (keys.size() > 1) {
        const float f = std::clamp(frame, 0.0f, float(frame_count() - 1));
        const int i = std::min(int(f / float(interval)), int(keys.size()) - 2);
        const float s = (f - float(i * interval)) / float(interval);
        const glm::vec3 p1 = keys[i].position, p2 = keys[i + 1].position;
        const glm::vec3 p0 = i > 0 ? keys[i - 1].position : 2.0f * p1 - p2;  // mirrored end points
        const glm::vec3 p3 = i + 2 < int(keys.size()) ? keys[i + 2].position : 2.0f * p2 - p1;
        pose.position = catmull_rom(p0, p1, p2, p3, s);
        q = glm::slerp(keys[i].orientation, keys[i + 1].orientation, s);  // shortest arc
    }
    pose.look = glm::normalize(q * glm::vec3(0, 0, -1));
    pose.up = glm::normalize(q * glm::vec3(0, 1, 0));
    return pose;
}

bool clear_of_blocks(const VoxelScene& scene, glm::vec3 p, float radius) {
    const glm::ivec3 lo(glm::floor(p - radius)), hi(glm::floor(p + radius));
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x)
                if (!scene.inside({x, y, z}) || scene.solid({x, y, z})) return false;
    return true;
}

CameraPath make_camera_path(const VoxelScene& scene, int frames, std::uint32_t seed, int interval) {
    if (frames < 1 || interval < 1) throw InputError("camera path: frames and interval must be positive");
    const int nkeys = std::max(2, (frames - 1 + interval - 1) / interval + 1);
    detail::Rand r(seed, 0x70617468u);

    // Start candidates: block centres inside the region with room around them.
    std::vector<glm::vec3> starts;
    const glm::ivec3 lo = glm::max(glm::ivec3(glm::floor(scene.camera.region_lo)), glm::ivec3(0));
    const glm::ivec3 hi = glm::min(glm::ivec3(glm::ceil(scene.camera.region_hi)), scene.size);
    for (int z = lo.z; z < hi.z; ++z)
        for (int y = lo.y; y < hi.y; ++y)
            for (int x = lo.x; x < hi.x; ++x) {
                const glm::vec3 p = glm::vec3(x, y, z) + 0.5f;
                if (in_region(scene, p) && clear_of_blocks(scene, p, kKeyClearance)) starts.push_back(p);
            }
    if (starts.empty())
        throw InputError("camera path: scene " + scene.name + " has no free space for the camera in its region");

    CameraPath path;
    path.interval = interval;
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const float max_step = attempt < kAttempts / 2 ? 7.0f : 3.5f;  // shorter hops bend less
        std::vector<glm::vec3> pos{r.pick(starts)};
        float heading = scene.camera.look ? yaw_of(*scene.camera.look) : r.range(0.0f, glm::two_pi<float>());
        while (int(pos.size()) < nkeys) {
            glm::vec3 best;
            float best_score = -1e9f;
            for (int k = 0; k < 80; ++k) {
                const float yaw = r.range(0.0f, glm::two_pi<float>()), dist = r.range(1.5f, max_step);
                const glm::vec3 dir(std::cos(yaw), r.range(-0.25f, 0.25f), std::sin(yaw));
                const glm::vec3 q = pos.back() + glm::normalize(dir) * dist;
                if (!in_region(scene, q) || !clear_of_blocks(scene, q, kKeyClearance) || !segment_clear(scene, pos.back(), q))
                    continue;
                // Keep going roughly the same way (a walk, not a jitter), prefer longer hops, add variety.
                const float score = std::cos(yaw - heading) + 0.15f * dist + r.range(0.0f, 0.8f);
                if (score > best_score) { best_score = score; best = q; }
            }
            if (best_score <= -1e9f) break;  // dead end: start over
            heading = yaw_of(best - pos.back());
            pos.push_back(best);
        }
        if (int(pos.size()) < nkeys) continue;
        path.keys.clear();
        for (int k = 0; k < nkeys; ++k) {
            const glm::vec3 travel = pos[std::min(k + 1, nkeys - 1)] - pos[std::max(k - 1, 0)];
            const float base = scene.camera.look ? yaw_of(*scene.camera.look) : yaw_of(travel);
            const float spread = scene.camera.look ? 0.5f : 0.8f;
            path.keys.push_back({pos[k], orientation(base + r.range(-spread, spread), r.range(-0.2f, 0.2f))});
        }
        bool ok = true;  // the spline may swing wider than the straight hops: check it
        for (int f = 0; f < path.frame_count() * 2 && ok; ++f)
            ok = clear_of_blocks(scene, path.at(0.5f * float(f)).position, kPathClearance);
        if (ok) return path;
    }
    // No moving path fits (a tiny or cluttered space): stand still at one spot and look around.
    const glm::vec3 p = r.pick(starts);
    path.keys.clear();
    const float yaw0 = r.range(0.0f, glm::two_pi<float>());
    for (int k = 0; k < nkeys; ++k) path.keys.push_back({p, orientation(yaw0 + 1.2f * float(k), 0.0f)});
    return path;
}

}  // namespace ngi

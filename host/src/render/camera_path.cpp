// Automatic keyframed camera paths through the free space of a voxel scene.
#include "ngi/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <string>
#include <glm/gtc/constants.hpp>

#include "ngi/camera.hpp"
#include "ngi/error.hpp"
#include "render/mesh_scene.hpp"
#include "render/rand.hpp"

namespace ngi {
namespace {

constexpr float kKeyClearance = 0.5f;   // keyframes: half-size of the block-free box around the camera
constexpr float kPathClearance = 0.3f;  // every interpolated position
constexpr int kAttempts = 48;

std::string scene_label(const VoxelScene& s) { return s.name.empty() ? std::string("(unnamed)") : s.name; }

// The geometry every test below sees: the scene's blocks plus the blocks its triangle mesh occupies (its bounds,
// its inside), so that paths orbit a mesh and keep clear of it as of blocks. `scene` itself when it has no mesh;
// else with_mesh_blocks' copy, kept in `storage`.
// (An optional: these functions run in the path search's inner loops, where a default VoxelScene's palette
// allocation per call would be the main cost for block scenes.)
const VoxelScene& camera_geometry(const VoxelScene& scene, std::optional<VoxelScene>& storage) {
    if (scene.mesh.empty()) return scene;
    storage = detail::with_mesh_blocks(scene);  // without the mesh: its blocks stand for it
    return *storage;
}

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

float safe_inv(float x) { return x != 0.0f ? 1.0f / x : 1.0e30f; }

// Distance along o + t d (d unit) to the first solid block, or -1 if the ray leaves the grid without one. Like the
// tracer's DDA (kernels/scene.cl, trace_grid), a ray that starts outside the grid enters it through its box.
float first_hit(const VoxelScene& s, glm::vec3 o, glm::vec3 d) {
    const glm::vec3 inv(safe_inv(d.x), safe_inv(d.y), safe_inv(d.z));
    const glm::vec3 ta = -o * inv, tb = (glm::vec3(s.size) - o) * inv;
    const glm::vec3 lo = glm::min(ta, tb), hi = glm::max(ta, tb);
    const float t_enter = std::max({lo.x, lo.y, lo.z}), t_exit = std::min({hi.x, hi.y, hi.z});
    float t = std::max(t_enter, 0.0f);
    if (t_exit < t) return -1.0f;
    glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor(o + d * t)), glm::ivec3(0), s.size - 1);
    const glm::ivec3 step(d.x >= 0.0f ? 1 : -1, d.y >= 0.0f ? 1 : -1, d.z >= 0.0f ? 1 : -1);
    const glm::vec3 delta = glm::abs(inv);
    glm::vec3 next = (glm::vec3(c + glm::ivec3(glm::greaterThan(step, glm::ivec3(0)))) - o) * inv;
    for (;;) {  // each step enters a neighbour cell: at most X + Y + Z steps
        if (s.voxels[s.index(c)] != 0) return t;
        const int a = next.x < next.y && next.x < next.z ? 0 : (next.y < next.z ? 1 : 2);
        t = next[a];
        c[a] += step[a];
        next[a] += delta[a];
        if (c[a] < 0 || c[a] >= s.size[a]) return -1.0f;
    }
}

// Bounding box (block corners) and centroid (block centres) of the solid blocks.
struct Occupied {
    glm::vec3 lo{0.0f}, hi{0.0f}, centroid{0.0f};
};

Occupied occupied_blocks(const VoxelScene& s) {
    glm::ivec3 lo(s.size), hi(-1);
    glm::dvec3 sum(0.0);
    std::size_t count = 0;
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x)
                if (s.voxels[s.index({x, y, z})] != 0) {
                    lo = glm::min(lo, glm::ivec3(x, y, z));
                    hi = glm::max(hi, glm::ivec3(x, y, z));
                    sum += glm::dvec3(x, y, z) + 0.5;
                    ++count;
                }
    if (count == 0) throw InputError("camera orbit: scene " + scene_label(s) + " has no solid block to orbit");
    return {glm::vec3(lo), glm::vec3(hi + 1), glm::vec3(sum / double(count))};
}

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

bool clear_of_blocks_in_open_air(const VoxelScene& scene_in, glm::vec3 p, float radius) {
    std::optional<VoxelScene> storage;
    const VoxelScene& scene = camera_geometry(scene_in, storage);
    const glm::ivec3 lo = glm::max(glm::ivec3(glm::floor(p - radius)), glm::ivec3(0));
    const glm::ivec3 hi = glm::min(glm::ivec3(glm::floor(p + radius)), scene.size - 1);
    for (int z = lo.z; z <= hi.z; ++z)  // empty loops when the box misses the grid
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x)
                if (scene.voxels[scene.index({x, y, z})] != 0) return false;
    return true;
}

float front_geometry_share(const VoxelScene& scene_in, const CameraPose& pose, int n) {
    std::optional<VoxelScene> storage;
    const VoxelScene& scene = camera_geometry(scene_in, storage);
    if (n < 1) throw InputError("front_geometry_share: the face size must be positive");
    const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
    int hits = 0;
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col)
            hits += first_hit(scene, pose.position, glm::normalize(face_pixel_direction(b, col, row, n))) >= 0.0f;
    return float(hits) / float(n * n);
}

CameraPathKind parse_camera_path_kind(const std::string& text, const std::string& what) {
    if (text == "auto") return CameraPathKind::Auto;
    if (text == "fly") return CameraPathKind::Fly;
    if (text == "orbit") return CameraPathKind::Orbit;
    throw InputError(what + ": camera path '" + text + "' is not auto, fly or orbit");
}

const char* camera_path_kind_name(CameraPathKind kind) {
    switch (kind) {
        case CameraPathKind::Fly: return "fly";
        case CameraPathKind::Orbit: return "orbit";
        case CameraPathKind::Auto: break;
    }
    return "auto";
}

bool clear_of_blocks(const VoxelScene& scene_in, glm::vec3 p, float radius) {
    std::optional<VoxelScene> storage;
    const VoxelScene& scene = camera_geometry(scene_in, storage);
    const glm::ivec3 lo(glm::floor(p - radius)), hi(glm::floor(p + radius));
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x)
                if (!scene.inside({x, y, z}) || scene.solid({x, y, z})) return false;
    return true;
}

CameraPath make_camera_path(const VoxelScene& scene_in, int frames, std::uint32_t seed, int interval) {
    std::optional<VoxelScene> storage;
    const VoxelScene& scene = camera_geometry(scene_in, storage);
    if (frames < 1 || interval < 1) throw InputError("camera path: frames and interval must be positive");
    if (frames > kMaxPathFrames)
        throw InputError("camera path: " + std::to_string(frames) + " frames, more than the limit of " +
                         std::to_string(kMaxPathFrames) + " (ngi/camera_path.hpp)");
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

CameraPath make_orbit_path(const VoxelScene& scene_in, int frames, std::uint32_t seed, int interval) {
    std::optional<VoxelScene> storage;
    const VoxelScene& scene = camera_geometry(scene_in, storage);
    if (frames < 1 || interval < 1) throw InputError("camera orbit: frames and interval must be positive");
    if (frames > kMaxPathFrames)
        throw InputError("camera orbit: " + std::to_string(frames) + " frames, more than the limit of " +
                         std::to_string(kMaxPathFrames) + " (ngi/camera_path.hpp)");
    const int nkeys = std::max(2, (frames - 1 + interval - 1) / interval + 1);
    const Occupied m = occupied_blocks(scene);
    // Look at the box's centre pulled halfway to the centroid: models with much empty box (a character's arms,
    // a tree's crown) are framed by their mass, not by the air between.
    const glm::vec3 box_centre = 0.5f * (m.lo + m.hi);
    const glm::vec3 target = 0.5f * (box_centre + m.centroid);
    // The distance at which the box's bounding sphere just fits the 90-degree face; candidates reach from well
    // inside it (flat or wide models fill the view only from close by or from above) to beyond it.
    const float d0 = 0.5f * glm::length(m.hi - m.lo) / std::sin(glm::quarter_pi<float>());
    constexpr float kFactors[] = {0.4f, 0.5f, 0.6f, 0.75f, 0.9f, 1.05f, 1.2f};
    constexpr float kElevations[] = {5.0f, 20.0f, 35.0f, 50.0f};  // degrees above the target
    constexpr int nf = int(std::size(kFactors)), ne = int(std::size(kElevations));
    constexpr int kOrbitAttempts = 8;
    // 7.5 keyframes per turn: a second turn does not retrace the first one's keyframes.
    const float step = glm::two_pi<float>() / 7.5f;
    const glm::vec3 up(0, 1, 0);
    detail::Rand r(seed, 0x6f726274u);  // "orbt"

    CameraPath best;
    float best_worst = -1.0f;
    // Open air along the straight hop from the previous keyframe (the spline stays near it): in a scene with
    // blocks all over its box (a forest), a close keyframe may stand in a clearing the next one cannot reach.
    auto hop_clear = [&](glm::vec3 a, glm::vec3 b) {
        const int steps = int(std::ceil(glm::length(b - a) / 0.1f));
        for (int i = 1; i < steps; ++i)
            if (!clear_of_blocks_in_open_air(scene, glm::mix(a, b, float(i) / float(steps)), kPathClearance + 0.05f))
                return false;
        return true;
    };
    for (int attempt = 0; attempt < kOrbitAttempts; ++attempt) {
        // Each failed attempt gives up the closest distance left: the last ones orbit from outside the clutter.
        const int first_f = std::min(attempt, nf - 1);
        const float theta0 = r.range(0.0f, glm::two_pi<float>());
        const float dir = r.chance(0.5f) ? 1.0f : -1.0f;
        CameraPath path;
        path.interval = interval;
        int prev_f = -1, prev_e = -1;
        for (int k = 0; k < nkeys; ++k) {
            const float theta = theta0 + dir * step * float(k);
            float best_score = -1e9f;
            CameraKey key;
            int key_f = -1, key_e = -1;
            for (int fi = first_f; fi < nf; ++fi)
                for (int ei = 0; ei < ne; ++ei) {
                    const float dist = d0 * kFactors[fi], el = glm::radians(kElevations[ei]);
                    const glm::vec3 p = target + dist * glm::vec3(std::cos(el) * std::cos(theta), std::sin(el),
                                                                  std::cos(el) * std::sin(theta));
                    if (!in_region(scene, p) || !clear_of_blocks_in_open_air(scene, p, kKeyClearance)) continue;
                    if (!path.keys.empty() && !hop_clear(path.keys.back().position, p)) continue;
                    const glm::vec3 look = glm::normalize(target - p);
                    // Not from behind a nearby wall or inside a tree: the view toward the target must carry
                    // at least a quarter of the way there.
                    const float t_centre = first_hit(scene, p, look);
                    if (t_centre >= 0.0f && t_centre < 0.25f * dist) continue;
                    const float share = front_geometry_share(scene, {p, look, up}, 16);
                    if (share <= 0.0f) continue;
                    // Filled views first (beyond 80 % more fill is no better), then farther views (more of the
                    // model), then staying near the previous keyframe's distance and height (a calm orbit),
                    // plus a little seeded variety.
                    float score = std::min(share, 0.8f) + 0.08f * float(fi) / float(nf - 1) + r.range(0.0f, 0.04f);
                    if (prev_f >= 0)
                        score -= 0.1f * float(std::abs(fi - prev_f)) / float(nf - 1) +
                                 0.1f * float(std::abs(ei - prev_e)) / float(ne - 1);
                    if (score > best_score) {
                        best_score = score;
                        key = {p, glm::quatLookAtRH(look, up)};
                        key_f = fi;
                        key_e = ei;
                    }
                }
            if (key_f < 0) break;  // no room at this azimuth: try another start
            path.keys.push_back(key);
            prev_f = key_f;
            prev_e = key_e;
        }
        if (int(path.keys.size()) < nkeys) continue;
        bool clear = true;  // the spline swings wider or narrower than the keyframes: check it
        for (int f = 0; f < path.frame_count() * 2 && clear; ++f) {
            const glm::vec3 p = path.at(0.5f * float(f)).position;
            clear = in_region(scene, p) && clear_of_blocks_in_open_air(scene, p, kPathClearance);
        }
        if (!clear) continue;
        float worst = 1.0f;  // the emptiest front view of the path's frames
        for (int f = 0; f < path.frame_count() && worst > 0.0f; ++f)
            worst = std::min(worst, front_geometry_share(scene, path.at(float(f)), 8));
        if (worst > 0.0f) return path;
        if (worst > best_worst) {
            best_worst = worst;
            best = path;
        }
    }
    if (best_worst < 0.0f)
        throw InputError("camera orbit: scene " + scene_label(scene) +
                         " has no room for the camera around its model (0.5 m of air at each keyframe, inside the "
                         "scene's camera region)");
    return best;  // every start leaves some frame looking past the model: the best one found
}

CameraPath make_camera_path(const VoxelScene& scene, CameraPathKind kind, int frames, std::uint32_t seed,
                            int interval) {
    if (kind == CameraPathKind::Auto) kind = scene.camera.orbit ? CameraPathKind::Orbit : CameraPathKind::Fly;
    return kind == CameraPathKind::Orbit ? make_orbit_path(scene, frames, seed, interval)
                                         : make_camera_path(scene, frames, seed, interval);
}

}  // namespace ngi

// A host voxel DDA (Amanatides & Woo) with the path tracer's conventions (kernels/pathtrace.cl, trace()): block
// (x, y, z) is the unit cube at that corner, outside the grid is air, faces are numbered 2 * axis + (normal points
// -axis ? 1 : 0). The light bake traces its rays with it, so "visible" means what the tracer means by it.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include <ngi/scene.hpp>

namespace ngi_gl {

struct DdaHit {
    bool hit = false;
    glm::ivec3 cell{0};
    int face = 0;          // the face the ray entered the block through
    std::uint8_t mat = 0;  // palette index of the block hit
    float t = 0.0f;
};

// The unit normal of face f (pathtrace.cl face_normal).
inline glm::vec3 face_normal(int f) {
    const float s = (f & 1) ? -1.0f : 1.0f;
    glm::vec3 n(0.0f);
    n[f >> 1] = s;
    return n;
}

// First solid block along o + t d (d unit), t in [0, tmax]; rays starting outside the grid enter it through its box.
inline DdaHit dda_trace(const ngi::VoxelScene& s, glm::vec3 o, glm::vec3 d, float tmax = 1e30f) {
    DdaHit h;
    const glm::vec3 dims(s.size);
    glm::vec3 inv;
    for (int a = 0; a < 3; ++a) inv[a] = d[a] != 0.0f ? 1.0f / d[a] : 1e30f;
    const glm::vec3 ta = -o * inv, tb = (dims - o) * inv;
    const glm::vec3 lo = glm::min(ta, tb), hi = glm::max(ta, tb);
    const float t_enter = std::max({lo.x, lo.y, lo.z}), t_exit = std::min({hi.x, hi.y, hi.z});
    float t = std::max(t_enter, 0.0f);
    if (t_exit < t || t > tmax) return h;
    int axis = t_enter > 0.0f ? (lo.x >= lo.y && lo.x >= lo.z ? 0 : (lo.y >= lo.z ? 1 : 2)) : -1;
    const glm::vec3 p = o + d * t;
    glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor(p)), glm::ivec3(0), s.size - 1);
    const glm::ivec3 step(d.x >= 0 ? 1 : -1, d.y >= 0 ? 1 : -1, d.z >= 0 ? 1 : -1);
    const glm::vec3 delta = glm::abs(inv);
    glm::vec3 next = (glm::vec3(c + glm::ivec3(step.x > 0, step.y > 0, step.z > 0)) - o) * inv;
    const int max_steps = s.size.x + s.size.y + s.size.z + 3;
    for (int i = 0; i < max_steps; ++i) {
        const std::uint8_t m = s.voxels[s.index(c)];
        if (m != 0) {
            if (axis < 0) {
                const glm::vec3 ad = glm::abs(d);
                axis = ad.x >= ad.y && ad.x >= ad.z ? 0 : (ad.y >= ad.z ? 1 : 2);
            }
            h.hit = true; h.cell = c; h.mat = m; h.t = t;
            h.face = 2 * axis + (step[axis] > 0 ? 1 : 0);
            return h;
        }
        if (next.x < next.y && next.x < next.z) { axis = 0; t = next.x; c.x += step.x; next.x += delta.x; }
        else if (next.y < next.z) { axis = 1; t = next.y; c.y += step.y; next.y += delta.y; }
        else { axis = 2; t = next.z; c.z += step.z; next.z += delta.z; }
        if (c[axis] < 0 || c[axis] >= s.size[axis] || t > tmax) break;
    }
    return h;
}

}  // namespace ngi_gl

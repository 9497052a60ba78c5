// The blocks a scene's triangle mesh occupies (mesh_scene.hpp: with_mesh_blocks). The camera-path code places
// cameras with a DDA over blocks and block-clearance tests (camera_path.cpp); giving it the mesh as blocks keeps one
// geometry model there. Block resolution is enough for that use: keyframes keep 0.5 m of air, and a block that a
// triangle only touches counts as solid, so cameras stay at least as far from the surface as they would from blocks.
#include <algorithm>
#include <cmath>

#include "render/mesh_scene.hpp"

namespace ngi::detail {
namespace {

// Whether the triangle (a, b, c) overlaps the box of centre `centre` and half size `h`: the separating-axis test
// of Akenine-Moller (2001) over the box's 3 axes, the triangle's normal and the 9 edge x axis cross products.
bool triangle_overlaps_box(glm::vec3 centre, glm::vec3 h, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 v[3] = {a - centre, b - centre, c - centre};
    const glm::vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    auto separated = [&](glm::vec3 axis) {
        const float p0 = glm::dot(v[0], axis), p1 = glm::dot(v[1], axis), p2 = glm::dot(v[2], axis);
        const float r = glm::dot(h, glm::abs(axis));
        return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
    };
    for (int i = 0; i < 3; ++i) {
        glm::vec3 unit(0.0f);
        unit[i] = 1.0f;
        if (separated(unit)) return false;
        for (const glm::vec3& edge : e)
            if (separated(glm::cross(unit, edge))) return false;
    }
    return !separated(glm::cross(e[0], e[1]));
}

}  // namespace

VoxelScene with_mesh_blocks(const VoxelScene& scene) {
    VoxelScene s = scene;
    s.mesh = TriangleMesh{};
    if (scene.mesh.empty()) return s;
    const std::size_t blocks = s.voxels.size();
    std::vector<std::uint8_t> shell(blocks, 0);  // blocks a triangle passes through
    const glm::vec3 h(0.5f + 1e-4f);             // a hair wider: a triangle on a block face marks both sides
    for (const glm::uvec3& t : scene.mesh.triangles) {
        const glm::vec3 a = scene.mesh.positions[t.x], b = scene.mesh.positions[t.y], c = scene.mesh.positions[t.z];
        const glm::vec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
        if (!(glm::all(glm::lessThan(lo, glm::vec3(s.size))) && glm::all(glm::greaterThan(hi, glm::vec3(0.0f)))))
            continue;  // outside the grid (or not finite): nothing to mark
        const glm::ivec3 c0 = glm::max(glm::ivec3(glm::floor(lo - h + 0.5f)), glm::ivec3(0));
        const glm::ivec3 c1 = glm::min(glm::ivec3(glm::floor(hi + h - 0.5f)), s.size - 1);
        for (int z = c0.z; z <= c1.z; ++z)
            for (int y = c0.y; y <= c1.y; ++y)
                for (int x = c0.x; x <= c1.x; ++x)
                    if (triangle_overlaps_box(glm::vec3(x, y, z) + 0.5f, h, a, b, c)) shell[s.index({x, y, z})] = 1;
    }
    // The outside: air reachable from the grid's boundary without crossing the shell or a block. Whatever the
    // mesh encloses is not reached and becomes solid too (a camera must not stand inside the object).
    std::vector<std::uint8_t> outside(blocks, 0);
    std::vector<glm::ivec3> queue;
    auto visit = [&](glm::ivec3 c) {
        if (!s.inside(c)) return;
        const std::size_t i = s.index(c);
        if (outside[i] || shell[i] || s.voxels[i] != 0) return;
        outside[i] = 1;
        queue.push_back(c);
    };
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x)
                if (x == 0 || y == 0 || z == 0 || x == s.size.x - 1 || y == s.size.y - 1 || z == s.size.z - 1)
                    visit({x, y, z});
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const glm::ivec3 c = queue[q];
        for (int a = 0; a < 3; ++a)
            for (int d : {-1, 1}) {
                glm::ivec3 n = c;
                n[a] += d;
                visit(n);
            }
    }
    const std::uint8_t m = s.palette.size() > 1 ? std::uint8_t(1) : s.add_material(Material{});
    for (std::size_t i = 0; i < blocks; ++i)
        if (s.voxels[i] == 0 && !outside[i]) s.voxels[i] = m;
    return s;
}

}  // namespace ngi::detail

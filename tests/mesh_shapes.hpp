// Small closed meshes built in the tests (no asset files): an icosphere and an axis-aligned box, and the exact
// form factor of a polygon seen from a point (the analytic side of the mesh rendering tests).
#pragma once
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/mesh.hpp"

namespace ngi::test {

// An icosahedron subdivided `levels` times and pushed onto the sphere (20 * 4^levels triangles, outward winding,
// shared vertices, normals = the radial direction), material `mat`.
inline TriangleMesh icosphere(glm::vec3 centre, float radius, int levels, std::uint8_t mat) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (auto& p : v) p = glm::normalize(p);
    std::vector<glm::uvec3> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<unsigned, unsigned>, unsigned> mid;
        auto midpoint = [&](unsigned a, unsigned b) {
            const auto key = std::minmax(a, b);
            if (auto it = mid.find(key); it != mid.end()) return it->second;
            v.push_back(glm::normalize(v[a] + v[b]));
            return mid[key] = unsigned(v.size() - 1);
        };
        std::vector<glm::uvec3> g;
        for (const auto& tri : f) {
            const unsigned a = midpoint(tri.x, tri.y), b = midpoint(tri.y, tri.z), c = midpoint(tri.z, tri.x);
            g.insert(g.end(), {{tri.x, a, c}, {tri.y, b, a}, {tri.z, c, b}, {a, b, c}});
        }
        f = std::move(g);
    }
    TriangleMesh m;
    for (const auto& p : v) {
        m.positions.push_back(centre + radius * p);
        m.normals.push_back(p);
    }
    m.triangles = f;
    m.materials.assign(f.size(), mat);
    return m;
}

// The closed box [lo, hi] as 12 triangles (outward winding, per-vertex normals of its faces: 24 vertices).
inline TriangleMesh box_mesh(glm::vec3 lo, glm::vec3 hi, std::uint8_t mat) {
    TriangleMesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            glm::vec3 n(0.0f);
            n[axis] = side ? 1.0f : -1.0f;
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            const auto base = unsigned(m.positions.size());
            for (int k = 0; k < 4; ++k) {
                glm::vec3 p;
                p[axis] = side ? hi[axis] : lo[axis];
                p[u] = (k == 1 || k == 2) ? hi[u] : lo[u];
                p[w] = (k >= 2) ? hi[w] : lo[w];
                m.positions.push_back(p);
                m.normals.push_back(n);
            }
            // (u, w) then the axis is right-handed: counter-clockwise seen from +axis is 0 1 2, 0 2 3.
            if (side) m.triangles.insert(m.triangles.end(), {{base, base + 1, base + 2}, {base, base + 2, base + 3}});
            else m.triangles.insert(m.triangles.end(), {{base, base + 2, base + 1}, {base, base + 3, base + 2}});
        }
    m.materials.assign(m.triangles.size(), mat);
    return m;
}

// Form factor from a differential area at p (unit normal n) to the planar polygon `poly` (Lambert's formula):
// (1 / 2 pi) * |sum over edges of angle(a_i, b_i) * n . unit(a_i x b_i)|, a_i = unit(v_i - p). A uniform emitter of
// radiance L gives irradiance pi L F there, i.e. lighting (irradiance / pi) L F; unoccluded AO loses F to it.
inline double polygon_form_factor(glm::dvec3 p, glm::dvec3 n, const std::vector<glm::dvec3>& poly) {
    double sum = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const glm::dvec3 a = glm::normalize(poly[i] - p), b = glm::normalize(poly[(i + 1) % poly.size()] - p);
        const glm::dvec3 c = glm::cross(a, b);
        const double len = glm::length(c);
        if (len < 1e-15) continue;
        sum += std::atan2(len, glm::dot(a, b)) * glm::dot(n, c / len);
    }
    return std::abs(sum) / (2.0 * M_PI);
}

}  // namespace ngi::test

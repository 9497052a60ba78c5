// TriangleMesh basics: bounds, smooth vertex normals, the checks every mesh passes before the renderer sees it, and
// which paths name mesh files.
#include <algorithm>
#include <cmath>
#include <string>

#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/mesh.hpp"
#include "render/finite.hpp"

namespace ngi {
namespace {

using detail::finite;

std::string vec_text(glm::vec3 v) {
    return "(" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ")";
}

}  // namespace

std::pair<glm::vec3, glm::vec3> mesh_bounds(const TriangleMesh& mesh) {
    if (mesh.triangles.empty()) return {glm::vec3(0.0f), glm::vec3(0.0f)};
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    // Only vertices a triangle uses: a loader may keep unreferenced ones, and they are not geometry.
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 p = mesh.positions.at(t[k]);
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
    return {lo, hi};
}

void compute_vertex_normals(TriangleMesh& mesh) {
    // Sums in double: a vertex shared by thousands of small triangles (a fan, a pole) keeps its precision.
    std::vector<glm::dvec3> sum(mesh.positions.size(), glm::dvec3(0.0));
    for (const glm::uvec3& t : mesh.triangles) {
        const glm::dvec3 a(mesh.positions.at(t.x)), b(mesh.positions.at(t.y)), c(mesh.positions.at(t.z));
        const glm::dvec3 n = glm::cross(b - a, c - a);  // |n| = twice the area: the sum is area-weighted
        sum[t.x] += n;
        sum[t.y] += n;
        sum[t.z] += n;
    }
    mesh.normals.resize(mesh.positions.size());
    for (std::size_t i = 0; i < sum.size(); ++i) {
        const double len = glm::length(sum[i]);
        mesh.normals[i] = len > 0.0 && std::isfinite(len) ? glm::vec3(sum[i] / len) : glm::vec3(0.0f, 1.0f, 0.0f);
    }
}

void validate_mesh(const TriangleMesh& mesh, std::size_t palette_size, const std::string& name) {
    const std::string what = "mesh " + name + ": ";
    if (mesh.triangles.empty()) throw InputError(what + "has no triangles");
    if (mesh.triangles.size() > kMaxMeshTriangles)
        throw InputError(what + std::to_string(mesh.triangles.size()) + " triangles, more than the limit of " +
                         std::to_string(kMaxMeshTriangles));
    if (mesh.positions.size() > kMaxMeshVertices)
        throw InputError(what + std::to_string(mesh.positions.size()) + " vertices, more than the limit of " +
                         std::to_string(kMaxMeshVertices));
    if (mesh.normals.size() != mesh.positions.size())
        throw InputError(what + std::to_string(mesh.normals.size()) + " normals for " +
                         std::to_string(mesh.positions.size()) + " vertices");
    if (mesh.materials.size() != mesh.triangles.size())
        throw InputError(what + std::to_string(mesh.materials.size()) + " material indices for " +
                         std::to_string(mesh.triangles.size()) + " triangles");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        if (!finite(mesh.positions[i])) throw InputError(what + "vertex " + std::to_string(i) + " position " +
                                                         vec_text(mesh.positions[i]) + " is not finite");
    for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
        const glm::vec3 n = mesh.normals[i];
        // Unit within float rounding: the renderer shades with them as they are.
        if (!finite(n) || std::abs(glm::length(n) - 1.0f) > 1e-3f)
            throw InputError(what + "vertex " + std::to_string(i) + " normal " + vec_text(n) +
                             " is not a finite unit vector");
    }
    const std::size_t nv = mesh.positions.size();
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const glm::uvec3 t = mesh.triangles[i];
        for (int k = 0; k < 3; ++k)
            if (t[k] >= nv)
                throw InputError(what + "triangle " + std::to_string(i) + " vertex index " + std::to_string(t[k]) +
                                 " is out of range (" + std::to_string(nv) + " vertices)");
        const std::uint8_t m = mesh.materials[i];
        if (m == 0 || m >= palette_size)
            throw InputError(what + "triangle " + std::to_string(i) + " material " + std::to_string(m) +
                             (m == 0 ? " is air (0)" : " is outside the palette of " + std::to_string(palette_size)));
    }
}

bool is_mesh_path(const std::string& path) {
    const std::string e = detail::lower_extension(path);
    return e == ".obj" || e == ".ply" || e == ".gltf" || e == ".glb";
}

}  // namespace ngi

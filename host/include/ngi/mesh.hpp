// Triangle meshes for the path tracer: the smooth geometry seed 001's AO network was designed for, and what
// applications light. A scene (ngi/scene.hpp) holds one TriangleMesh beside its voxel grid; the renderer builds a
// BVH over it (render/bvh.hpp) and traces both. Units and axes as for voxels (docs/RENDERER.md): metres, +y up.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/material.hpp"

namespace ngi {

// An indexed triangle mesh. Surfaces are two-sided (a ray may hit either side); `normals` are per vertex, unit,
// and only shade (features, the AO network's inputs): light transport uses each triangle's geometric normal, so
// that a convex object never occludes itself.
struct TriangleMesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;        // per vertex (same count as positions), unit
    std::vector<glm::uvec3> triangles;     // vertex indices, counter-clockwise seen from the front
    std::vector<std::uint8_t> materials;   // per triangle: palette index into the scene's palette, 1..255

    std::size_t triangle_count() const { return triangles.size(); }
    bool empty() const { return triangles.empty(); }
};

// Limits that keep a hostile file (or a header that claims 10^9 indices) from costing more than the largest mesh
// the renderer takes. 16 Mi triangles = 0.8 GiB of device memory in the BVH layout.
constexpr std::size_t kMaxMeshTriangles = std::size_t(1) << 24;
constexpr std::size_t kMaxMeshVertices = std::size_t(1) << 24;

// The axis-aligned bounds of the vertices the triangles use: {lo, hi}. Both zero for an empty mesh.
std::pair<glm::vec3, glm::vec3> mesh_bounds(const TriangleMesh& mesh);

// Area-weighted vertex normals from the triangles (each triangle's cross product added to its three vertices),
// normalized; a vertex no triangle uses (or whose sum vanishes) gets +y.
void compute_vertex_normals(TriangleMesh& mesh);

// Checks that `mesh` is one the renderer takes: finite positions and normals, indices in range, material indices in
// 1..palette_size-1, counts within the limits, at least one triangle. Throws InputError naming `name` and the first
// offending element.
void validate_mesh(const TriangleMesh& mesh, std::size_t palette_size, const std::string& name);

// A mesh file and the materials its triangles refer to (materials[i] becomes palette index first + i when added to
// a scene; TriangleMesh::materials then holds 1-based indices into `materials`). At most 255 materials (the scene
// palette's usable entries): more distinct colours are merged (mesh_io.cpp says how).
struct LoadedMesh {
    TriangleMesh mesh;
    std::vector<Material> materials;
    std::size_t dropped_degenerate = 0;  // zero-area triangles left out (no ray can hit them)
    std::size_t dropped_primitives = 0;  // points and lines left out (no area either)
};

// Largest mesh file load_mesh reads: 1 GiB, counted over the file and the files it names (an OBJ's .mtl, a glTF's
// external buffers). A 16 Mi-triangle binary PLY is ~0.3 GiB, as text OBJ ~0.7 GiB.
constexpr std::uint64_t kMaxMeshFileBytes = std::uint64_t(1) << 30;

// OBJ (+ .mtl), PLY (ASCII and binary) and glTF 2.0 (.gltf with embedded or external buffers, .glb), one reader per
// format (OBJ and PLY: ngi's own; glTF: tinygltf): polygons triangulated, identical vertices joined, node transforms
// applied (normals by the inverse transpose, winding flipped under a mirroring transform), per-vertex normals (the
// file's, else area-weighted ones from compute_vertex_normals). Albedo per triangle: the material's diffuse colour
// (OBJ Kd: sRGB -> linear; glTF baseColorFactor: linear, as its specification says); where the file gives no
// material colour (an OBJ without .mtl, any PLY) the mean of the triangle's vertex colours (sRGB -> linear), else
// ngi's default (Material{}); glTF's COLOR_0 multiplies its base colour (the specification's rule). Albedo is capped
// at 0.95 like every scene's. Emissive colours (OBJ Ke, glTF emissiveFactor x KHR_materials_emissive_strength) become
// Material::emission, as linear radiance; negative colour components, emission past kMaxEmission, an OBJ whose
// mtllib names a missing library and a usemtl its libraries do not define are refused. Zero-area triangles, points
// and lines are dropped and counted: they can never be hit, and real scans contain them; a mesh left with no
// triangle is an error.
// Throws InputError naming the file (and the line, element or accessor, where known) for unreadable, malformed or
// truncated files, NaN/Inf vertices or normals, indices out of range, empty meshes and anything over the limits
// above. Sizes the format states up front (a PLY header's element counts, glTF accessors, buffers and its node tree)
// are checked against the limits and against the bytes present before anything is allocated for them, so a 1 KB
// file claiming 10^9 faces never allocates for them. Nothing is returned half-built.
// The path is opened like every ngi input (directories, FIFOs and devices are refused).
LoadedMesh load_mesh(const std::string& path);
// The same from a file's bytes; the extension of `name` picks the format and `name` stands for the path in errors.
// Files it names (.mtl, external buffers) are not read: an OBJ loads without its materials, a glTF with external
// buffers is refused. For tests and the fuzz target.
LoadedMesh parse_mesh(const std::string& bytes, const std::string& name);

// True if the path names a mesh file by its extension (.obj, .ply, .gltf, .glb; any case).
bool is_mesh_path(const std::string& path);

}  // namespace ngi

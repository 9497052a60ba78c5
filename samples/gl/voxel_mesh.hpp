// The rasterizer's geometry: one quad per block face that borders air (outside the grid counts as air, as in the
// tracer), so the mesh is closed and every surface the tracer can hit has exactly one quad.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <ngi/scene.hpp>

namespace ngi_gl {

struct ExposedFace {
    glm::ivec3 cell;
    int face;           // pathtrace.cl numbering: 2 * axis + (normal points -axis ? 1 : 0)
    std::uint8_t mat;
};

// Every exposed face, in block order (x fastest), faces 0..5 per block.
std::vector<ExposedFace> exposed_faces(const ngi::VoxelScene& scene);

// The face's four corners, counter-clockwise seen from the side its normal points to (GL front faces), and the
// face-local coordinates (u, v) in [0, 1]^2 of each: u along axis (a + 1) % 3, v along (a + 2) % 3, the same
// parametrisation the light bake's texels use.
struct QuadCorners {
    glm::vec3 p[4];
    glm::vec2 uv[4];
};
QuadCorners quad_corners(const ExposedFace& f);

// Interleaved vertex layout uploaded to GL (kVertexFloats floats per vertex, 4 vertices and 6 indices per face).
struct Vertex {
    glm::vec3 position;
    glm::vec3 normal;
    glm::vec3 albedo;
    glm::vec3 emission;  // the material's emission at lamp level 1
    float lamp;          // 1 for lamp materials (emission x lamp_level), else 0
    glm::vec2 tile;      // the face's tile origin in the bake atlas (texels)
    glm::vec2 uv;        // face-local coordinates in [0, 1]
};
struct Mesh {
    std::vector<Vertex> vertices;
    std::vector<std::uint32_t> indices;
    std::size_t faces = 0;
};
// tile_origin(i) gives face i's atlas tile origin (LightBake::tile_origin).
template <class TileOrigin>
Mesh build_mesh(const ngi::VoxelScene& scene, const std::vector<ExposedFace>& faces, TileOrigin tile_origin);

}  // namespace ngi_gl

#include "voxel_mesh_impl.hpp"

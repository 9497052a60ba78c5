// build_mesh: a template only because the tile origin comes from the bake (kept out of the mesh's header logic).
#pragma once
#include "voxel_dda.hpp"

namespace ngi_gl {

template <class TileOrigin>
Mesh build_mesh(const ngi::VoxelScene& scene, const std::vector<ExposedFace>& faces, TileOrigin tile_origin) {
    Mesh m;
    m.faces = faces.size();
    m.vertices.reserve(faces.size() * 4);
    m.indices.reserve(faces.size() * 6);
    for (std::size_t i = 0; i < faces.size(); ++i) {
        const ExposedFace& f = faces[i];
        const ngi::Material& mat = scene.palette[f.mat];
        const QuadCorners q = quad_corners(f);
        const glm::vec2 tile = tile_origin(i);
        const auto base = std::uint32_t(m.vertices.size());
        for (int k = 0; k < 4; ++k)
            m.vertices.push_back({q.p[k], face_normal(f.face), mat.albedo, mat.emission, mat.lamp ? 1.0f : 0.0f,
                                  tile, q.uv[k]});
        for (std::uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + k);
    }
    return m;
}

}  // namespace ngi_gl

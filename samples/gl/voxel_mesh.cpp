#include "voxel_mesh.hpp"

#include "voxel_dda.hpp"

namespace ngi_gl {

std::vector<ExposedFace> exposed_faces(const ngi::VoxelScene& scene) {
    std::vector<ExposedFace> out;
    for (int z = 0; z < scene.size.z; ++z)
        for (int y = 0; y < scene.size.y; ++y)
            for (int x = 0; x < scene.size.x; ++x) {
                const glm::ivec3 c(x, y, z);
                const std::uint8_t m = scene.voxels[scene.index(c)];
                if (m == 0) continue;
                for (int f = 0; f < 6; ++f)
                    if (!scene.solid(c + glm::ivec3(face_normal(f)))) out.push_back({c, f, m});
            }
    return out;
}

QuadCorners quad_corners(const ExposedFace& f) {
    const int a = f.face >> 1, a1 = (a + 1) % 3, a2 = (a + 2) % 3;
    glm::vec3 o(f.cell);
    if (!(f.face & 1)) o[a] += 1.0f;  // +axis faces lie on the block's far plane
    glm::vec3 e1(0.0f), e2(0.0f);
    e1[a1] = 1.0f;
    e2[a2] = 1.0f;  // e1 x e2 = +axis: (0, e1, e1 + e2, e2) is counter-clockwise seen from +axis
    QuadCorners q;
    const glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const int order_pos[4] = {0, 1, 2, 3}, order_neg[4] = {0, 3, 2, 1};
    const int* order = (f.face & 1) ? order_neg : order_pos;
    for (int k = 0; k < 4; ++k) {
        const glm::vec2 t = uv[order[k]];
        q.p[k] = o + t.x * e1 + t.y * e2;
        q.uv[k] = t;
    }
    return q;
}

}  // namespace ngi_gl

// Sky portals and sunlit patches of a voxel scene (render/light_regions.hpp).
#include "render/light_regions.hpp"

#include <glm/glm.hpp>

namespace ngi::detail {

Portals find_portals(const VoxelScene& s) {
    Portals p;
    const std::size_t blocks = s.voxels.size();
    p.region.assign(blocks, -1);
    std::vector<std::uint8_t> covered(blocks, 0);
    for (int z = 0; z < s.size.z; ++z)
        for (int x = 0; x < s.size.x; ++x) {
            bool roof = false;
            for (int y = s.size.y - 1; y >= 0; --y) {
                const std::size_t i = s.index({x, y, z});
                if (s.voxels[i]) roof = true;
                else covered[i] = roof;
            }
        }
    const glm::ivec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    std::vector<glm::ivec3> stack;
    int regions = 0;
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x) {
                const glm::ivec3 start(x, y, z);
                if (!covered[s.index(start)] || p.region[s.index(start)] >= 0) continue;
                const int id = regions++;
                const std::size_t first = p.faces.size() / 4;
                p.region[s.index(start)] = id;
                stack.push_back(start);
                while (!stack.empty()) {  // flood fill; collect the region's portals on the way
                    const glm::ivec3 c = stack.back();
                    stack.pop_back();
                    for (int f = 0; f < 6; ++f) {
                        const glm::ivec3 nb = c + dirs[f];
                        if (!s.inside(nb)) {
                            p.faces.insert(p.faces.end(), {c.x, c.y, c.z, f});
                            continue;
                        }
                        const std::size_t j = s.index(nb);
                        if (s.voxels[j]) continue;
                        if (!covered[j]) {
                            p.faces.insert(p.faces.end(), {c.x, c.y, c.z, f});
                        } else if (p.region[j] < 0) {
                            p.region[j] = id;
                            stack.push_back(nb);
                        }
                    }
                }
                p.range.insert(p.range.end(), {std::int32_t(first), std::int32_t(p.faces.size() / 4 - first)});
            }
    return p;
}

Patches find_patches(const VoxelScene& s, const std::vector<std::int32_t>& region, int regions) {
    const glm::ivec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    std::vector<std::vector<glm::ivec4>> per(static_cast<std::size_t>(regions));
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x) {
                const glm::ivec3 c(x, y, z);
                if (!s.solid(c)) continue;
                for (int f = 0; f < 6; ++f) {
                    const glm::ivec3 nb = c + dirs[f];
                    if (s.inside(nb) && !s.solid(nb) && region[s.index(nb)] >= 0)
                        per[std::size_t(region[s.index(nb)])].push_back({c, f});
                }
            }
    Patches p;
    p.slot.assign(s.voxels.size(), -1);
    for (const auto& list : per) {
        p.range.insert(p.range.end(), {std::int32_t(p.faces.size() / 4), std::int32_t(list.size())});
        for (const auto& e : list) {
            const std::size_t b = s.index(glm::ivec3(e));
            if (p.slot[b] < 0) {
                p.slot[b] = std::int32_t(p.index.size() / 6);
                p.index.insert(p.index.end(), 6, -1);
            }
            p.index[std::size_t(p.slot[b]) * 6 + std::size_t(e.w)] = std::int32_t(p.faces.size() / 4);
            p.faces.insert(p.faces.end(), {e.x, e.y, e.z, e.w});
        }
    }
    return p;
}

}  // namespace ngi::detail

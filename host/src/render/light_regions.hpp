// Sky portals and sunlit patches (docs/RENDERER.md "Sky portals", "Sunlit patches"): the light-sampling structures
// of a scene's covered regions, found on the host once per scene and uploaded by the Renderer (renderer.cpp), whose
// kernels sample them (kernels/lighting.cl). Library-internal.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ngi/scene.hpp"

namespace ngi::detail {

// Sky portals: air blocks with a solid block somewhere above them are "covered"; 6-connected covered blocks form
// regions (rooms, tunnels, the space under a roof). A portal is a face between a covered block and open air or the
// outside of the grid. Every ray that escapes to the sky from inside a region first crosses one of that region's
// portals, so sampling points on the portals is a valid (MIS-weighted) sky-sampling strategy there.
inline constexpr std::size_t kMaxPortalGrid = std::size_t(1) << 24;  // region ids cost 4 bytes per block

struct Portals {
    std::vector<std::int32_t> region;  // per block: region id, -1 = solid or open air
    std::vector<std::int32_t> faces;   // per portal: covered cell x, y, z, face id; grouped by region
    std::vector<std::int32_t> range;   // per region: first portal, portal count
};

Portals find_portals(const VoxelScene& s);

// Sunlit patches: faces of blocks that border covered air, grouped by that air's region. Per frame they are
// weighted by the sunlight they reflect (kernel pt_patch_weights), and points in the region sample them as
// secondary lights (lighting.cl: patch_light).
struct Patches {
    std::vector<std::int32_t> faces;  // per patch: cell x, y, z, face id; grouped by region
    std::vector<std::int32_t> range;  // per region: first patch, patch count
    std::vector<std::int32_t> slot;   // per block: slot in `index` (-1: no patch faces)
    std::vector<std::int32_t> index;  // per slot, 6 faces: patch index (-1: not a patch)
};

// `region`, `regions`: Portals::region of the scene and its region count.
Patches find_patches(const VoxelScene& s, const std::vector<std::int32_t>& region, int regions);

}  // namespace ngi::detail

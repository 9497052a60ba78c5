// The scene around a triangle mesh (mesh_scene.hpp): a grid of air covering the mesh, like a .vox model's grid.
#include <algorithm>
#include <cmath>

#include "ngi/error.hpp"
#include "render/mesh_scene.hpp"

namespace ngi::detail {
namespace {

// Air around the object on every side: the tracer's rays enter the grid through its boundary, so the margin only
// keeps the object off the grid's faces (and gives the smooth-normal blur of render_geometry room).
constexpr float kMargin = 2.0f;
// With a floor, the floor reaches this far beyond the object on every side, so that its shadow and the light it
// bounces land on blocks rather than falling off the edge.
constexpr float kFloorReach = 10.0f;
const glm::vec3 kFloorAlbedo(0.45f, 0.44f, 0.42f);

}  // namespace

VoxelScene mesh_scene(LoadedMesh loaded, const std::string& name, bool floor) {
    TriangleMesh& mesh = loaded.mesh;
    const auto [lo, hi] = mesh_bounds(mesh);
    const glm::vec3 extent = hi - lo;
    const float side = floor ? kFloorReach : kMargin;
    // Whole blocks around the object; x and z centre it, y puts it kMargin above the grid's bottom, or standing on
    // the floor's top face (y = 1) with a floor.
    const glm::dvec3 want(double(extent.x) + 2.0 * side, double(extent.y) + (floor ? 1.0 : kMargin) + kMargin,
                          double(extent.z) + 2.0 * side);
    for (int a = 0; a < 3; ++a)
        if (!(want[a] <= double(kMaxVoxAxis)))
            throw InputError("mesh " + name + ": " + std::to_string(extent[a]) + " m along " + "xyz"[a] +
                             " needs a grid of more than " + std::to_string(kMaxVoxAxis) +
                             " blocks (mesh files are read as metres: is it in millimetres?)");
    const glm::ivec3 size(glm::ceil(want));
    if (std::uint64_t(size.x) * std::uint64_t(size.y) * std::uint64_t(size.z) > kMaxVoxBlocks)
        throw InputError("mesh " + name + ": a grid of " + std::to_string(size.x) + " x " + std::to_string(size.y) +
                         " x " + std::to_string(size.z) + " blocks around it is more than the limit of " +
                         std::to_string(kMaxVoxBlocks) + " (mesh files are read as metres)");
    const std::size_t first = 1;  // palette index of loaded.materials[0]: the scene's palette holds only air so far
    if (loaded.materials.size() + (floor ? 1 : 0) > std::size_t(VoxelScene::kMaxMaterials - 1))
        throw InputError("mesh " + name + ": " + std::to_string(loaded.materials.size()) +
                         " materials and a floor do not fit the palette of " +
                         std::to_string(VoxelScene::kMaxMaterials - 1));

    VoxelScene s(size, name);
    for (const Material& m : loaded.materials) s.add_material(m);
    const glm::vec3 offset = glm::vec3((float(size.x) - extent.x) * 0.5f, floor ? 1.0f : kMargin,
                                       (float(size.z) - extent.z) * 0.5f) - lo;
    for (glm::vec3& p : mesh.positions) p += offset;
    for (std::uint8_t& m : mesh.materials) m = std::uint8_t(m + first - 1);
    validate_mesh(mesh, s.palette.size(), name);
    s.mesh = std::move(mesh);
    if (floor) s.fill({0, 0, 0}, {size.x, 1, size.z}, s.add_material({kFloorAlbedo, glm::vec3(0.0f), false}));
    // As a .vox model: the automatic camera path orbits it from the air around the grid, up to one grid size away,
    // never below its base.
    const float reach = float(std::max({size.x, size.y, size.z}));
    s.camera.orbit = true;
    s.camera.region_lo = glm::vec3(-reach, 0.0f, -reach);
    s.camera.region_hi = glm::vec3(size) + reach;
    return s;
}

}  // namespace ngi::detail

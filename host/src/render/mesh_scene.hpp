// Scenes made of a triangle mesh: the procedural smooth objects (mesh_procedural.cpp), the scene built around any
// mesh (mesh_scene.cpp), and the block occupancy of a mesh that the camera-path code sees (mesh_occupancy.cpp).
// Library-internal.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "ngi/mesh.hpp"
#include "ngi/scene.hpp"

namespace ngi::detail {

// The families of smooth objects: "knot", "superquadric", "blob" (docs/RENDERER.md "Triangle meshes").
const std::vector<std::string>& mesh_families();
bool is_mesh_family(const std::string& family);

// One closed, smooth object of `family`, about 40 m across, with its one material. Deterministic in `seed`.
// Throws InputError for an unknown family.
LoadedMesh generate_mesh_object(const std::string& family, std::uint32_t seed);

// A scene holding `loaded` and no blocks (but the optional floor): the grid covers the mesh's bounds plus a margin,
// the mesh is moved to sit in it (the grid's minimum corner is the world origin, as for every scene), its
// materials join the palette, and the camera orbits it as it does a .vox model. `floor` adds a one-block-thick
// floor of blocks under the object, reaching beyond it. Throws InputError naming `name` when the grid would exceed
// the .vox limits (kMaxVoxAxis, kMaxVoxBlocks): a mesh in millimetres, say.
VoxelScene mesh_scene(LoadedMesh loaded, const std::string& name, bool floor);

// mesh_scene(generate_mesh_object(family, seed), name, floor).
VoxelScene mesh_family_scene(const std::string& family, std::uint32_t seed, bool floor, const std::string& name);

// `scene` with every block that a triangle of scene.mesh passes through, or that the mesh encloses, made solid
// (the first palette entry; blocks outside the grid are left out): the geometry the host-side camera code
// (camera_path.cpp's DDA and clearance tests) sees. Conservative: a block a triangle only grazes counts whole.
// The copy has no mesh (its blocks stand for it); a scene without triangles is copied unchanged.
VoxelScene with_mesh_blocks(const VoxelScene& scene);

}  // namespace ngi::detail

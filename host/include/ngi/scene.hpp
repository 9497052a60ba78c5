// Voxel scenes for the path tracer: a grid of blocks, each a palette index into a small table of diffuse
// materials. Procedural families (seeded), MagicaVoxel .vox files, and the scene spec strings of the CLI.
// Units and axes (docs/RENDERER.md): 1 block = 1 metre; block (x, y, z) covers [x, x+1) x [y, y+1) x [z, z+1) in
// world space; +y is up; the grid's minimum corner is the world origin.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/material.hpp"
#include "ngi/mesh.hpp"

namespace ngi {

// Where the automatic camera path may go, and which way it prefers to look (scene-family knowledge).
struct CameraHints {
    glm::vec3 region_lo{0.0f}, region_hi{0.0f};  // keyframes lie inside this box (world metres)
    std::optional<glm::vec3> look;                // preferred horizontal look direction (e.g. away from an opening)
    // The default path ("auto") orbits the occupied blocks instead of flying through free space: set for a model
    // without a world around it (.vox files), whose free space is mostly sky. The region then reaches beyond the
    // grid (outside it is air: primary rays enter the grid through its boundary).
    bool orbit = false;
};

struct VoxelScene {
    static constexpr int kMaxMaterials = 256;  // palette index 0 is air, so 255 usable materials

    std::string name;                          // the spec it was made from ("room:seed=3", "a/b.vox")
    glm::ivec3 size{0};                        // blocks per axis
    std::vector<std::uint8_t> voxels;          // palette index per block, 0 = empty; x + size.x * (y + size.y * z)
    std::vector<Material> palette{Material{}}; // palette[0] = air (never looked up)
    TriangleMesh mesh;                         // triangles beside the blocks (world metres; materials index palette)
    float sun_azimuth = 0.6f;                  // radians about +y; the sun's heading at noon (see lighting)
    float default_time = 13.0f;                // hours, for renders that do not give a time of day
    CameraHints camera;

    VoxelScene() = default;
    VoxelScene(glm::ivec3 size, std::string name);  // all air; camera region = the whole grid

    bool inside(glm::ivec3 c) const { return glm::all(glm::greaterThanEqual(c, glm::ivec3(0))) && glm::all(glm::lessThan(c, size)); }
    std::size_t index(glm::ivec3 c) const { return std::size_t(c.x) + std::size_t(size.x) * (std::size_t(c.y) + std::size_t(size.y) * std::size_t(c.z)); }
    std::uint8_t at(glm::ivec3 c) const { return inside(c) ? voxels[index(c)] : 0; }  // air outside the grid
    bool solid(glm::ivec3 c) const { return at(c) != 0; }
    void set(glm::ivec3 c, std::uint8_t m) { if (inside(c)) voxels[index(c)] = m; }
    void fill(glm::ivec3 lo, glm::ivec3 hi, std::uint8_t m);  // the box [lo, hi) clipped to the grid
    std::uint8_t add_material(const Material& m);             // new palette index; throws Error when full
    std::size_t solid_count() const;
};

// Procedural families. Each is deterministic in its seed (std::mt19937 + explicit distributions of our own, so the
// same seed gives the same scene on every platform):
//   room     indoor rooms with windows, a door and holes in the walls/roof; furniture; ceiling lamps
//   street   outdoor street: road, pavement, houses with windows and doors, street lamps, trees
//   cave     tunnels carved through rock plus straight mine corridors, a few openings to the sky, glowing crystals
//   backlit  a room lit only through a large opening behind the camera (the camera looks away from it)
//   bleed    a room with strongly coloured walls and blocks in sunlight through a skylight (colour bleeding)
//   sculpture  one free-standing smooth object (metaballs, a torus, dents) in a 64^3 grid: per-object networks (AO)
//   cornell    seed 004's voxel Cornell boxes: a closed 40^3 box (red, green, white walls), 1-2 ceiling panels, a
//              skylight for the sun, 2-4 coloured boxes; cornell_pink: one more box and a pink back wall (its test)
// and three families of smooth triangle-mesh objects (VoxelScene::mesh, ~40 m across like a sculpture, in a grid of
// air around them; orbit camera like a .vox model; docs/RENDERER.md "Triangle meshes"):
//   knot          a (p, q) torus-knot tube
//   superquadric  a superellipsoid or supertoroid
//   blob          a displaced icosphere (bumps and dents)
const std::vector<std::string>& scene_families();
VoxelScene generate_scene(const std::string& family, std::uint32_t seed);

// MagicaVoxel .vox (versions 150 and 200): SIZE/XYZI models placed through the scene graph (nTRN translation and
// rotation, nGRP, nSHP) or, without one, side by side at the origin; RGBA palette (else the default palette);
// MATL emission (_type _emit). Every other chunk (LAYR, rOBJ, rCAM, NOTE, IMAP, MATT, ...) is skipped by its size.
// Colours are sRGB in the file and become linear albedo. MagicaVoxel's z-up axes map to ours as
// (x, y, z)_vox -> (x, z, -y) (a rotation: handedness is kept), then the scene is moved to start at the origin.
// Throws InputError naming the file for truncated data, malformed chunk structure, models over 256 blocks per
// axis, voxels outside their model, and files over any of the limits below. The limits keep a hostile file from
// costing more time or memory than the largest scene the renderer takes (docs/RENDERER.md, ".vox limits").
constexpr std::size_t kMaxVoxBlocks = std::size_t(1) << 26;  // 64 Mi blocks = 64 MiB of palette indices
constexpr int kMaxVoxAxis = 4096;           // blocks per scene axis (the tracer's DDA walks up to X + Y + Z cells)
constexpr int kMaxVoxDepth = 64;            // scene-graph nodes on one path from the root (real files: < 10)
constexpr std::size_t kMaxVoxNodeVisits = std::size_t(1) << 18;  // node visits of the whole walk (shared subtrees
                                                                 // count once per reference)
constexpr std::size_t kMaxVoxInstances = std::size_t(1) << 16;   // shape instances (model placements)
// Largest .vox file load_vox reads, checked (stat) before reading: 4 bytes per listed voxel for a grid of
// kMaxVoxBlocks blocks, plus 16 MiB of palette, materials and scene graph (real files: < 1 MiB; the largest public
// scene used here is 0.9 MiB). A 14 KB scene padded with an unknown 3 GiB chunk was once read whole (4 GB RSS).
constexpr std::uint64_t kMaxVoxFileBytes = 4 * std::uint64_t(kMaxVoxBlocks) + (std::uint64_t(16) << 20);
constexpr std::size_t kMaxVoxPlaced = kMaxVoxBlocks;             // voxels placed, summed over instances
constexpr std::int64_t kMaxVoxCoord = std::int64_t(1) << 20;     // |translation| per axis, per nTRN and summed
VoxelScene load_vox(const std::string& path);
// The same from the file's bytes; `name` stands for the path in errors and VoxelScene::name.
VoxelScene parse_vox(const std::string& bytes, const std::string& name);

// "family:seed=S" (a key=value list after the colon: seed, default 0; for the mesh families also floor=0|1, a
// one-block-thick floor of blocks under the object), a path to a .vox file, or a path to a mesh file (is_mesh_path:
// load_mesh, in the file's units taken as metres, in a grid of air around it like the mesh families).
// Throws InputError for unknown families, keys or bad numbers.
VoxelScene make_scene(const std::string& spec);
// The canonical name of a spec ("room" -> "room:seed=0", "knot:floor=1" -> "knot:seed=0,floor=1" (floor=0 is left
// out); a .vox or mesh path stays as it is), validated like make_scene
// but without building the scene. VoxelScene::name of make_scene(spec) equals it.
std::string scene_spec_name(const std::string& spec);

}  // namespace ngi

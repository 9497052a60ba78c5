// Surface-voxel compaction of seed 004's voxel radiance field (kernels/voxel_compact.cl); the path-traced field
// itself is Renderer::render_voxel_field (renderer.cpp). Definitions: docs/VOXEL_FIELD.md.
#include "ngi/voxel_field.hpp"

#include <algorithm>
#include <string>

#include "ngi/error.hpp"
#include "render/tracer_constants.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi {
namespace {

constexpr int kCompactLocal = 64;  // work-group size of every voxel_compact.cl kernel (VC_LOCAL)
constexpr int kCompactItems = 64;  // consecutive blocks per work-item (VC_ITEMS)

// The build options of kernels/voxel_compact.cl.
std::string compact_defines() {
    return detail::join_defines({detail::define("VC_LOCAL", kCompactLocal), detail::define("VC_ITEMS", kCompactItems),
                                 detail::define("VC_ATTRIBUTES", kVoxelAttributes)});
}

std::string dims(glm::ivec3 s) {
    return std::to_string(s.x) + "x" + std::to_string(s.y) + "x" + std::to_string(s.z);
}

}  // namespace

SurfaceVoxels surface_voxels(const Device& device, const VoxelScene& scene, const Lighting& lighting) {
    const std::string what = "surface voxels of scene " + scene.name;
    if (scene.size.x < 1 || scene.size.y < 1 || scene.size.z < 1)
        throw InputError(what + ": grid " + dims(scene.size) + " has no blocks");
    const std::size_t blocks = std::size_t(scene.size.x) * std::size_t(scene.size.y) * std::size_t(scene.size.z);
    if (blocks > kMaxFieldGridBlocks)
        throw InputError(what + ": grid " + dims(scene.size) + " has " + std::to_string(blocks) +
                         " blocks, more than the " + std::to_string(kMaxFieldGridBlocks) +
                         " (2^24) whose ids are exact as float attributes");
    if (scene.voxels.size() != blocks)
        throw InputError(what + ": " + std::to_string(scene.voxels.size()) + " voxels for a grid of " +
                         std::to_string(blocks));
    for (std::uint8_t v : scene.voxels)
        if (v >= scene.palette.size())
            throw InputError(what + ": material " + std::to_string(v) + " of a palette of " +
                             std::to_string(scene.palette.size()));

    detail::Context& ctx = detail::context_of(device);
    std::vector<float> mats(scene.palette.size() * 8, 0.0f);
    for (std::size_t i = 0; i < scene.palette.size(); ++i) {
        const Material& p = scene.palette[i];
        const glm::vec3 e = p.emission * (p.lamp ? lighting.lamp_level : 1.0f);  // as the renderer's upload_frame
        const float v[8] = {p.albedo.r, p.albedo.g, p.albedo.b, 0, e.r, e.g, e.b, 0};
        std::copy(v, v + 8, mats.begin() + std::ptrdiff_t(i * 8));
    }
    const std::size_t tile = std::size_t(kCompactLocal) * kCompactItems;
    const std::size_t tiles = (blocks + tile - 1) / tile;
    detail::Buffer grid = ctx.alloc(blocks, "surface voxels: grid");
    ctx.write(grid, 0, blocks, scene.voxels.data(), "surface voxels: upload grid");
    detail::Buffer mat_buf = ctx.alloc(mats.size() * sizeof(float), "surface voxels: materials");
    ctx.write(mat_buf, 0, mats.size() * sizeof(float), mats.data(), "surface voxels: upload materials");
    detail::Buffer mask = ctx.alloc(blocks, "surface voxels: exposed faces");
    detail::Buffer tile_count = ctx.alloc(tiles * sizeof(std::int32_t), "surface voxels: tile counts");
    detail::Buffer tile_offset = ctx.alloc((tiles + 1) * sizeof(std::int32_t), "surface voxels: tile offsets");

    detail::Kernel flag = ctx.kernel("voxel_compact", "vc_flag", compact_defines());
    detail::Kernel scan = ctx.kernel("voxel_compact", "vc_scan_tiles", compact_defines());
    detail::Kernel scatter = ctx.kernel("voxel_compact", "vc_scatter", compact_defines());
    const glm::ivec3 s = scene.size;
    const std::size_t local = kCompactLocal, global = tiles * local;
    flag.args(grid, s.x, s.y, s.z, mask, tile_count);
    ctx.launch(flag, 1, &global, &local);
    scan.args(tile_count, int(tiles), tile_offset);
    ctx.launch(scan, 1, &local, &local);
    std::int32_t count = 0;
    ctx.read(tile_offset, tiles * sizeof(std::int32_t), sizeof count, &count, "surface voxels: read count");
    if (count == 0) throw InputError(what + ": no surface voxels (the grid " + dims(s) + " has no solid block)");
    const std::size_t V = std::size_t(count);
    if (V > kMaxFieldVoxels)
        throw InputError(what + ": " + std::to_string(V) + " surface voxels, more than the " +
                         std::to_string(kMaxFieldVoxels) + " a voxel field takes");

    detail::Buffer cell = ctx.alloc(V * 4 * sizeof(std::int32_t), "surface voxels: cells");
    detail::Buffer attr = ctx.alloc(V * kVoxelAttributes * sizeof(float), "surface voxels: attributes");
    detail::Buffer normal = ctx.alloc(V * 3 * sizeof(float), "surface voxels: normals");
    detail::Buffer probe = ctx.alloc(V * 3 * sizeof(float), "surface voxels: probe points");
    detail::Buffer index = ctx.alloc(blocks * sizeof(std::int32_t), "surface voxels: index");
    scatter.args(grid, s.x, s.y, s.z, mask, tile_offset, mat_buf, detail::kRayOffset, cell, attr, normal, probe, index);
    ctx.launch(scatter, 1, &global, &local);

    SurfaceVoxels out;
    out.grid = s;
    std::vector<std::int32_t> c(V * 4);
    std::vector<float> n(V * 3), p(V * 3);
    out.attributes.resize(V * kVoxelAttributes);
    out.index_of.resize(blocks);
    ctx.read(cell, 0, c.size() * sizeof(std::int32_t), c.data(), "surface voxels: read cells");
    ctx.read(attr, 0, out.attributes.size() * sizeof(float), out.attributes.data(), "surface voxels: read attributes");
    ctx.read(normal, 0, n.size() * sizeof(float), n.data(), "surface voxels: read normals");
    ctx.read(probe, 0, p.size() * sizeof(float), p.data(), "surface voxels: read probe points");
    ctx.read(index, 0, blocks * sizeof(std::int32_t), out.index_of.data(), "surface voxels: read index");
    out.cell.resize(V);
    out.exposed.resize(V);
    out.normal.resize(V);
    out.probe.resize(V);
    for (std::size_t i = 0; i < V; ++i) {
        out.cell[i] = {c[4 * i], c[4 * i + 1], c[4 * i + 2]};
        out.exposed[i] = std::uint8_t(c[4 * i + 3]);
        out.normal[i] = {n[3 * i], n[3 * i + 1], n[3 * i + 2]};
        out.probe[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    }
    return out;
}

}  // namespace ngi

// Seed 004's voxel radiance field (docs/VOXEL_FIELD.md): the surface voxels compacted on the device
// (kernels/voxel_compact.cl) and the path-traced ground truth of a Renderer's scene for them, the SH field, probe
// and face lighting (the vf_* kernels of kernels/voxel_field.cl) and the voxel-pair visibility
// (kernels/voxel_visibility.cl).
#include "ngi/voxel_field.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "ngi/error.hpp"
#include "ngi/render.hpp"
#include "render/renderer_impl.hpp"
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

constexpr int kMaxFieldSamples = 1 << 20;  // per-voxel sample counts (directions, sun rays, point samples)

// Voxels usable with a renderer of grid `size`: from surface_voxels() of a scene of that size, consistent arrays.
void check_voxels(const SurfaceVoxels& v, glm::ivec3 size, const std::string& what, std::size_t limit) {
    if (v.grid != size)
        throw InputError(what + ": surface voxels of a " + dims(v.grid) + " grid, the renderer's scene is " +
                         dims(size));
    const std::size_t blocks = std::size_t(size.x) * std::size_t(size.y) * std::size_t(size.z);
    if (blocks > kMaxFieldGridBlocks)
        throw InputError(what + ": the scene's grid " + dims(size) + " has more than " +
                         std::to_string(kMaxFieldGridBlocks) + " blocks");
    const std::size_t V = v.size();
    if (V == 0) throw InputError(what + ": no surface voxels");
    if (V > limit)
        throw InputError(what + ": " + std::to_string(V) + " surface voxels, more than the " + std::to_string(limit) +
                         " it takes");
    if (v.probe.size() != V || v.normal.size() != V || v.exposed.size() != V ||
        v.attributes.size() != V * kVoxelAttributes || v.index_of.size() != blocks)
        throw InputError(what + ": inconsistent surface voxels (" + std::to_string(V) + " cells, " +
                         std::to_string(v.probe.size()) + " probe points, " + std::to_string(v.normal.size()) +
                         " normals, " + std::to_string(v.exposed.size()) + " exposed masks, " +
                         std::to_string(v.attributes.size()) + " attribute values, " +
                         std::to_string(v.index_of.size()) + " index entries)");
    for (std::size_t i = 0; i < V; ++i) {
        const glm::ivec3 c = v.cell[i];
        if (glm::any(glm::lessThan(c, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(c, size)) ||
            v.exposed[i] == 0 || v.exposed[i] >= 64)
            throw InputError(what + ": surface voxel " + std::to_string(i) + " at (" + std::to_string(c.x) + ", " +
                             std::to_string(c.y) + ", " + std::to_string(c.z) + ") with exposed mask " +
                             std::to_string(v.exposed[i]) + " is not a surface voxel of a " + dims(size) +
                             " grid");
    }
}

void check_field_settings(const VoxelFieldSettings& s) {
    const int m = int(std::lround(std::sqrt(double(std::max(s.directions, 0)))));
    if (s.directions < 1 || s.directions > kMaxFieldSamples || m * m != s.directions)
        throw InputError("voxel field: directions " + std::to_string(s.directions) +
                         " is not a perfect square m * m in 1..2^20");
    if (s.sun_rays < 1 || s.sun_rays > kMaxFieldSamples)
        throw InputError("voxel field: sun_rays " + std::to_string(s.sun_rays) + " not in 1..2^20");
    if (s.point_samples < 1 || s.point_samples > kMaxFieldSamples)
        throw InputError("voxel field: point_samples " + std::to_string(s.point_samples) + " not in 1..2^20");
    if (s.max_bounces < 0) throw InputError("voxel field: max_bounces " + std::to_string(s.max_bounces) + " < 0");
    if (s.rr_start < 0) throw InputError("voxel field: rr_start " + std::to_string(s.rr_start) + " < 0");
    if (s.max_samples_per_launch < 0)
        throw InputError("voxel field: max_samples_per_launch " + std::to_string(s.max_samples_per_launch) + " < 0");
}

// The voxels' probe points, shading normals (normalize(probe - centre): the Eq. 3 normal except at creases, where
// the probe moved to a face centre) and cells with their exposed masks, as the vf_* kernels read them.
struct VoxelBuffers {
    detail::Buffer probe, normal, cells;
};

VoxelBuffers upload_voxels(detail::Context& ctx, const SurfaceVoxels& v, bool normals) {
    const std::size_t V = v.size();
    std::vector<float> p(3 * V), n(normals ? 3 * V : 0);
    std::vector<std::int32_t> c(4 * V);
    for (std::size_t i = 0; i < V; ++i) {
        for (int k = 0; k < 3; ++k) p[3 * i + k] = v.probe[i][k];
        if (normals) {
            const glm::vec3 d = glm::normalize(v.probe[i] - (glm::vec3(v.cell[i]) + 0.5f));
            for (int k = 0; k < 3; ++k) n[3 * i + k] = d[k];
        }
        c[4 * i] = v.cell[i].x; c[4 * i + 1] = v.cell[i].y; c[4 * i + 2] = v.cell[i].z; c[4 * i + 3] = v.exposed[i];
    }
    VoxelBuffers b;
    b.probe = ctx.alloc(p.size() * 4, "voxel field: probe points");
    ctx.write(b.probe, 0, p.size() * 4, p.data(), "voxel field: upload probe points");
    if (normals) {
        b.normal = ctx.alloc(n.size() * 4, "voxel field: normals");
        ctx.write(b.normal, 0, n.size() * 4, n.data(), "voxel field: upload normals");
    }
    b.cells = ctx.alloc(c.size() * 4, "voxel field: cells");
    ctx.write(b.cells, 0, c.size() * 4, c.data(), "voxel field: upload cells");
    return b;
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

namespace {

// The settings of the tracer's frame upload that a voxel field or point SH call shares with RenderSettings.
RenderSettings field_render_settings(const VoxelFieldSettings& s) {
    RenderSettings rs;
    rs.max_bounces = s.max_bounces;
    rs.rr_start = s.rr_start;
    rs.seed = s.seed;
    rs.sky_portals = s.sky_portals;
    rs.sunlit_patches = s.sunlit_patches;
    return rs;
}

// vf_sh projects the radiance its rays meet; rays never meet the area light (it is not geometry), so its SH would
// miss the light's direct part while every other output includes it. Refused rather than inconsistent.
void refuse_area_light(const Lighting& lighting, const std::string& what) {
    if (lighting.area_light.enabled())
        throw InputError(what + ": the lighting has an area light, which the voxel field does not support");
}

}  // namespace

// The SH projection at V points (probe points and cells uploaded, the frame uploaded): the sun's visibility first
// (vf_sh's last launch adds the sun with it; skipped for indirect light, which has no sun term), then vf_sh.
// Returns the [V][27] buffer; adds the rays traced to `rays_total`.
detail::Buffer Renderer::Impl::project_sh(const detail::Buffer& probe, const detail::Buffer& cells, std::size_t V,
                                          const Lighting& lighting, const VoxelFieldSettings& s, bool indirect_only,
                                          const detail::Buffer& rays, std::uint64_t& rays_total) {
    detail::Context& c = *ctx;
    kernel(k_vf_sun, "voxel_field", "vf_sun_visibility");
    kernel(k_vf_sh, "voxel_field", "vf_sh");
    const std::size_t local_sun = local_size(k_vf_sun), local_sh = local_size(k_vf_sh), global = V;
    const RenderSettings rs = field_render_settings(s);
    const int nvox = int(V), cap = s.max_samples_per_launch;
    const long walk = trace_loops(), bounce = bounce_loops();
    detail::Buffer vis = c.alloc(V * 4, "voxel field: sun visibility");
    detail::Buffer sh = c.alloc(V * 27 * 4, "voxel field: SH");
    const glm::vec3 E = lighting.sun.irradiance;
    if (E.r + E.g + E.b > 0.0f && !indirect_only) {
        const int chunk = items_per_launch(64, walk + 8, cap, "voxel field: sun visibility");
        for (int first = 0; first < s.sun_rays; first += chunk) {
            const int last = int(std::min<long>(s.sun_rays, long(first) + chunk));
            set_scene_args(k_vf_sun, rs, probe, cells, nvox, s.sun_rays, first, last, s.seed, vis, rays);
            c.launch(k_vf_sun, 1, &global, &local_sun);
        }
        rays_total += sum_rays(rays, V);
    } else {
        c.fill_zero(vis, 0, V * 4, "voxel field: sun visibility");
    }
    const int side = int(std::lround(std::sqrt(double(s.directions))));
    const long per_direction = walk + long(s.max_bounces) * bounce + 32;
    const int chunk = items_per_launch(4 * 27 + 64, per_direction, cap, "voxel field: SH projection");
    for (int first = 0; first < s.directions; first += chunk) {
        const int last = int(std::min<long>(s.directions, long(first) + chunk));
        set_scene_args(k_vf_sh, rs, probe, cells, nvox, side, first, last, s.max_bounces, s.rr_start,
                       int(indirect_only), s.seed, vis, sh, rays);
        c.launch(k_vf_sh, 1, &global, &local_sh);
    }
    rays_total += sum_rays(rays, V);
    return sh;
}

VoxelField Renderer::render_voxel_field(const SurfaceVoxels& voxels, const Lighting& lighting,
                                        const VoxelFieldSettings& s) {
    Impl& m = *impl_;
    check_voxels(voxels, m.size, "voxel field", kMaxFieldVoxels);
    check_field_settings(s);
    refuse_area_light(lighting, "voxel field");
    const auto t0 = std::chrono::steady_clock::now();
    detail::Context& ctx = *m.ctx;
    m.kernel(m.k_vf_probe, "voxel_field", "vf_probe_lighting");
    m.kernel(m.k_vf_face, "voxel_field", "vf_face_lighting");
    const std::size_t local_probe = Impl::local_size(m.k_vf_probe), local_face = Impl::local_size(m.k_vf_face);
    const RenderSettings rs = field_render_settings(s);
    m.upload_frame(CameraPose{}, lighting, rs, "voxel_field");
    const std::size_t V = voxels.size();
    const VoxelBuffers in = upload_voxels(ctx, voxels, true);
    detail::Buffer direct = ctx.alloc(V * 3 * 4, "voxel field: direct lighting");
    detail::Buffer full = ctx.alloc(V * 3 * 4, "voxel field: lighting");
    detail::Buffer face = ctx.alloc(V * 18 * 4, "voxel field: face lighting");
    detail::Buffer rays = ctx.alloc(V * 6 * 4, "voxel field: ray counts");
    const int nvox = int(V);
    const std::uint32_t seed = s.seed;
    const std::size_t global = V, global6 = 6 * V;
    VoxelField out;
    const long bounce = m.bounce_loops();
    const int cap = s.max_samples_per_launch;
    const detail::Buffer sh = m.project_sh(in.probe, in.cells, V, lighting, s, false, rays, out.rays);

    for (const bool is_direct : {true, false}) {
        const int bounces = is_direct ? 0 : s.max_bounces;
        const detail::Buffer& dst = is_direct ? direct : full;
        const int chunk =
            m.items_per_launch(64, (long(bounces) + 1) * bounce, cap, "voxel field: lighting at probe points");
        for (int first = 0; first < s.point_samples; first += chunk) {
            const int last = int(std::min<long>(s.point_samples, long(first) + chunk));
            m.set_scene_args(m.k_vf_probe, rs, in.probe, in.normal, in.cells, nvox, s.point_samples, first, last,
                             bounces, s.rr_start, seed, dst, rays);
            ctx.launch(m.k_vf_probe, 1, &global, &local_probe);
        }
        out.rays += m.sum_rays(rays, V);
    }

    {
        const int chunk =
            m.items_per_launch(64, (long(s.max_bounces) + 1) * bounce + 8, cap, "voxel field: face lighting");
        for (int first = 0; first < s.point_samples; first += chunk) {
            const int last = int(std::min<long>(s.point_samples, long(first) + chunk));
            m.set_scene_args(m.k_vf_face, rs, in.cells, nvox, s.point_samples, first, last, s.max_bounces,
                             s.rr_start, seed, face, rays);
            ctx.launch(m.k_vf_face, 1, &global6, &local_face);
        }
        out.rays += m.sum_rays(rays, 6 * V);
    }

    out.sh.resize(V * 27);
    out.direct.resize(V * 3);
    out.lighting.resize(V * 3);
    out.face_lighting.resize(V * 18);
    ctx.read(sh, 0, out.sh.size() * 4, out.sh.data(), "voxel field: read SH");
    ctx.read(direct, 0, out.direct.size() * 4, out.direct.data(), "voxel field: read direct lighting");
    ctx.read(full, 0, out.lighting.size() * 4, out.lighting.data(), "voxel field: read lighting");
    ctx.read(face, 0, out.face_lighting.size() * 4, out.face_lighting.data(), "voxel field: read face lighting");
    out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

PointSh Renderer::project_points_sh(const std::vector<glm::vec3>& points, const Lighting& lighting,
                                   const VoxelFieldSettings& s, bool indirect_only) {
    Impl& m = *impl_;
    const std::string what = "point SH";
    check_field_settings(s);
    refuse_area_light(lighting, what);
    const std::size_t P = points.size();
    if (P == 0) throw InputError(what + ": no points");
    if (P > kMaxFieldVoxels)
        throw InputError(what + ": " + std::to_string(P) + " points, more than the " +
                         std::to_string(kMaxFieldVoxels) + " one call takes");
    // The cell of each point: its block (a point on the grid's far faces belongs to the last block), whose id
    // seeds its random numbers and whose own surface it does not see.
    std::vector<float> p(3 * P);
    std::vector<std::int32_t> c(4 * P, 0);
    const glm::vec3 box(m.size);
    for (std::size_t i = 0; i < P; ++i) {
        const glm::vec3 q = points[i];
        if (!(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z)) || glm::any(glm::lessThan(q, glm::vec3(0.0f))) ||
            glm::any(glm::greaterThan(q, box)))
            throw InputError(what + ": point " + std::to_string(i) + " (" + std::to_string(q.x) + ", " +
                             std::to_string(q.y) + ", " + std::to_string(q.z) + ") is not inside the scene's grid " +
                             dims(m.size));
        const glm::ivec3 cell = glm::min(glm::ivec3(glm::floor(q)), m.size - 1);
        for (int k = 0; k < 3; ++k) {
            p[3 * i + std::size_t(k)] = q[k];
            c[4 * i + std::size_t(k)] = cell[k];
        }
    }
    const auto t0 = std::chrono::steady_clock::now();
    detail::Context& ctx = *m.ctx;
    m.upload_frame(CameraPose{}, lighting, field_render_settings(s), "voxel_field");
    detail::Buffer probe = ctx.alloc(p.size() * 4, "point SH: points");
    ctx.write(probe, 0, p.size() * 4, p.data(), "point SH: upload points");
    detail::Buffer cells = ctx.alloc(c.size() * 4, "point SH: cells");
    ctx.write(cells, 0, c.size() * 4, c.data(), "point SH: upload cells");
    detail::Buffer rays = ctx.alloc(P * 4, "point SH: ray counts");
    PointSh out;
    const detail::Buffer sh = m.project_sh(probe, cells, P, lighting, s, indirect_only, rays, out.rays);
    out.sh.resize(P * 27);
    ctx.read(sh, 0, out.sh.size() * 4, out.sh.data(), "point SH: read SH");
    out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

std::vector<std::uint32_t> Renderer::voxel_visibility(const SurfaceVoxels& voxels) {
    Impl& m = *impl_;
    check_voxels(voxels, m.size, "voxel visibility", kMaxVisibilityVoxels);
    detail::Context& ctx = *m.ctx;
    m.kernel(m.k_vf_vis, "voxel_visibility", "vf_visibility");
    const std::size_t V = voxels.size(), words = (V + 31) / 32;
    const VoxelBuffers in = upload_voxels(ctx, voxels, false);
    detail::Buffer mask = ctx.alloc(V * words * 4, "voxel visibility: mask");
    const int chunk = std::min(32, m.items_per_launch(64, m.trace_loops() + 8, 0, "voxel visibility"));
    const std::size_t global[2] = {V, words}, local[2] = {Impl::local_size(m.k_vf_vis), 1};
    for (int first = 0; first < 32; first += chunk) {
        const int last = std::min(32, first + chunk);
        m.k_vf_vis.args(m.grid, m.size.x, m.size.y, m.size.z, in.probe, in.cells, int(V), int(words), first, last,
                        mask);
        ctx.launch(m.k_vf_vis, 2, global, local);
    }
    std::vector<std::uint32_t> out(V * words);
    ctx.read(mask, 0, out.size() * 4, out.data(), "voxel visibility: read mask");
    return out;
}

}  // namespace ngi

// Host side of the path tracer (the tracer programs of runtime/programs.cpp: kernels/scene.cl, lighting.cl,
// pathtrace.cl, ...): scene upload, per-frame lights and camera, read-back into a Frame.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "ngi/camera.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/render.hpp"
#include "ngi/voxel_field.hpp"
#include "ops/luminance.hpp"
#include "pipeline/frame_planes.hpp"
#include "render/bvh.hpp"
#include "render/tracer_constants.hpp"
#include "runtime/context.hpp"

namespace ngi {
namespace {

constexpr std::size_t kLocal = 64;   // fixed work-group size (PoCL compiles one work-group function per size)

// Layout of the tracer's `light` parameter array (what each holds: the comment in kernels/lighting.cl). Defined here
// only: every tracer program is built with these as -D options (pathtrace_defines()), so host and device cannot
// disagree.
struct LightSlot {
    const char* name;
    int offset;
};
constexpr LightSlot kLightLayout[] = {
    {"L_SUN_DIR", 0},       {"L_SUN_E", 3},         {"L_SUN_COS", 6},     {"L_ZENITH", 8},
    {"L_HORIZON", 11},      {"L_GROUND", 14},       {"L_GLOW", 17},       {"L_AREA_CENTRE", 20},
    {"L_AREA_U", 23},       {"L_AREA_V", 26},       {"L_AREA_RADIANCE", 29}, {"L_AREA_NORMAL", 32},
    {"L_AREA_AREA", 35}};
constexpr int kLightParams = 36;
// The sun and sky part (what the sunlit-patch weights depend on, with the materials).
constexpr int kSunSkyParams = 20;

// The build options of every tracer program (pathtrace, ao_geometry, voxel_field, voxel_visibility in
// runtime/programs.cpp): one set for all, whichever of them a program's files check.
std::string pathtrace_defines() {
    std::string d;
    for (const LightSlot& l : kLightLayout) d += std::string(d.empty() ? "" : " ") + "-D" + l.name + "=" + std::to_string(l.offset);
    return detail::join_defines({d, detail::define("SKY_DEPTH", detail::kSkyDepth),
                                 detail::define("RAY_OFFSET", detail::kRayOffset), detail::frame_plane_defines(),
                                 detail::luminance_defines(), detail::bvh_defines()});
}

float luminance(glm::vec3 c) { return detail::luminance(c.r, c.g, c.b); }

// A face of an emissive block that borders air inside the grid (only such faces can be seen or sampled).
struct EmitterFace {
    glm::ivec3 cell;
    int face;  // 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z
    std::uint8_t material;
};

// Sky portals: air blocks with a solid block somewhere above them are "covered"; 6-connected covered blocks form
// regions (rooms, tunnels, the space under a roof). A portal is a face between a covered block and open air or the
// outside of the grid. Every ray that escapes to the sky from inside a region first crosses one of that region's
// portals, so sampling points on the portals is a valid (MIS-weighted) sky-sampling strategy there.
constexpr std::size_t kMaxPortalGrid = std::size_t(1) << 24;  // region ids cost 4 bytes per block

struct Portals {
    std::vector<std::int32_t> region;  // per block: region id, -1 = solid or open air
    std::vector<std::int32_t> faces;   // per portal: covered cell x, y, z, face id; grouped by region
    std::vector<std::int32_t> range;   // per region: first portal, portal count
};

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

// Sunlit patches: faces of blocks that border covered air, grouped by that air's region. Per frame they are
// weighted by the sunlight they reflect (kernel pt_patch_weights), and points in the region sample them as
// secondary lights (lighting.cl: patch_light).
struct Patches {
    std::vector<std::int32_t> faces;  // per patch: cell x, y, z, face id; grouped by region
    std::vector<std::int32_t> range;  // per region: first patch, patch count
    std::vector<std::int32_t> slot;   // per block: slot in `index` (-1: no patch faces)
    std::vector<std::int32_t> index;  // per slot, 6 faces: patch index (-1: not a patch)
};

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

void check_settings(const RenderSettings& s) {
    if (s.n < 1 || s.n > 8192) throw InputError("render: face size n must be in 1..8192, got " + std::to_string(s.n));
    if (s.feature_spp < 1 || s.reference_spp < 1) throw InputError("render: samples per pixel must be at least 1");
    if (s.max_bounces < 0 || s.rr_start < 0) throw InputError("render: bounces must not be negative");
}

}  // namespace

struct Renderer::Impl {
    std::shared_ptr<detail::Context> ctx;
    std::vector<Material> palette;
    std::vector<EmitterFace> emitters;
    glm::ivec3 size;
    detail::Buffer grid, mats, lights, cdf, light, cam, region, portals, portal_range;
    detail::Buffer patches, patch_prob, patch_cdf, patch_range, face_slot, face_index, patch_weight;
    std::unique_ptr<detail::DeviceBvh> bvh;  // the triangle mesh (placeholder buffers when there is none)
    bool has_mesh = false, has_blocks = false;
    int bvh_depth = 0;
    bool have_regions = false, have_portals = false;
    int npatches = 0;
    std::vector<std::int32_t> patch_static_range;  // per region: first, count
    bool patches_lit = false;                        // any region has sunlit patches this frame
    std::vector<float> patch_light_key;              // light parameters the patch weights were computed for
    // pt_patch_weights of each program that lights the scene (pathtrace, voxel_field: both list patch_weights.cl),
    // so a frame runs it from the program it is rendered with and never builds another one for it.
    std::map<std::string, detail::Kernel> k_patch;
    detail::Buffer features, feature_rays, mean, var, ref_rays;
    int buffers_n = 0;
    int nlights = 0;
    float inv_total = 0.0f;
    bool area_on = false;  // this frame has an area light (one more shadow ray per path vertex)
    detail::Kernel k_features, k_reference, k_ao, k_geometry, k_surface;
    detail::Buffer ao;  // render_ao's output
    detail::Buffer geometry;  // render_geometry's and render_surface's output

    // The kernel `name` of the tracer program `program` in slot k, built at its first use: each render call compiles
    // only the program it runs (an AO-only renderer never builds the path tracer's lighting).
    detail::Kernel& kernel(detail::Kernel& k, const char* program, const char* name) {
        if (!k.get()) k = ctx->kernel(program, name, pathtrace_defines());
        return k;
    }
    // Work-group size of a tracer launch: kLocal, or less where the driver allows fewer work-items for these
    // register-heavy kernels (Mesa 22.3 rusticl on llvmpipe reports a CL_KERNEL_WORK_GROUP_SIZE of 32 and a
    // conforming driver rejects a larger local size). Results do not depend on it.
    static std::size_t local_size(const detail::Kernel& k) {
        const std::size_t wg = k.max_work_group();
        return wg > 0 ? std::min(kLocal, wg) : kLocal;
    }

    // Per frame: lamp level into the material table, the emitter list and its CDF, sun/sky, camera.
    // `lit_program`: the program of the frame's kernels when they light the scene (the sunlit-patch weights are
    // updated only for those, by its pt_patch_weights), else nullptr.
    void upload_frame(const CameraPose& pose, const Lighting& l, const RenderSettings& rs, const char* lit_program) {
        check_area_light(l.area_light, "render");
        std::vector<float> m(palette.size() * 8, 0.0f);
        for (std::size_t i = 0; i < palette.size(); ++i) {
            const Material& p = palette[i];
            const glm::vec3 e = p.emission * (p.lamp ? l.lamp_level : 1.0f);
            const float v[8] = {p.albedo.r, p.albedo.g, p.albedo.b, 0, e.r, e.g, e.b, 0};
            std::copy(v, v + 8, m.begin() + std::ptrdiff_t(i * 8));
        }
        ctx->write(mats, 0, m.size() * sizeof(float), m.data(), "render: upload materials");

        std::vector<std::int32_t> faces;
        std::vector<double> weight;
        double total = 0;
        for (const auto& f : emitters) {
            const float w = luminance(glm::vec3(m[f.material * 8 + 4], m[f.material * 8 + 5], m[f.material * 8 + 6]));
            if (!(w > 0.0f)) continue;  // a lamp that is off
            faces.insert(faces.end(), {f.cell.x, f.cell.y, f.cell.z, f.face});
            weight.push_back(w);
            total += w;
        }
        nlights = int(weight.size());
        inv_total = nlights ? float(1.0 / total) : 0.0f;
        std::vector<float> c(std::max<std::size_t>(weight.size(), 1), 1.0f);
        double acc = 0;
        for (std::size_t i = 0; i < weight.size(); ++i) c[i] = float((acc += weight[i]) / total);
        if (nlights) c.back() = 1.0f;
        faces.resize(std::max<std::size_t>(faces.size(), 4), 0);
        if (lights.bytes() < faces.size() * 4) lights = ctx->alloc(faces.size() * 4, "render: emitter list");
        if (cdf.bytes() < c.size() * 4) cdf = ctx->alloc(c.size() * 4, "render: emitter CDF");
        ctx->write(lights, 0, faces.size() * 4, faces.data(), "render: upload emitter list");
        ctx->write(cdf, 0, c.size() * 4, c.data(), "render: upload emitter CDF");

        const AreaLight& a = l.area_light;
        area_on = a.enabled();
        // The area light's normal and area in double (a thin panel's cross product loses float bits); all zero
        // when it is off, so the kernel never reads what it does not use.
        const glm::dvec3 cross = glm::cross(glm::dvec3(a.half_u), glm::dvec3(a.half_v));
        const double cross_len = glm::length(cross);
        const glm::vec3 area_normal = area_on ? glm::vec3(cross / cross_len) : glm::vec3(0.0f);
        const float area = area_on ? float(4.0 * cross_len) : 0.0f;
        const glm::vec3 zero(0.0f);
        const glm::vec3 centre = area_on ? a.centre : zero, half_u = area_on ? a.half_u : zero,
                        half_v = area_on ? a.half_v : zero, radiance = area_on ? a.radiance : zero;
        const float L[kLightParams] = {
            l.sun.direction.x, l.sun.direction.y, l.sun.direction.z,
            l.sun.irradiance.r, l.sun.irradiance.g, l.sun.irradiance.b,
            std::cos(l.sun.angular_radius), 0.0f,
            l.sky.zenith.r, l.sky.zenith.g, l.sky.zenith.b,
            l.sky.horizon.r, l.sky.horizon.g, l.sky.horizon.b,
            l.sky.ground.r, l.sky.ground.g, l.sky.ground.b,
            l.sky.glow.r, l.sky.glow.g, l.sky.glow.b,
            centre.x, centre.y, centre.z,
            half_u.x, half_u.y, half_u.z,
            half_v.x, half_v.y, half_v.z,
            radiance.r, radiance.g, radiance.b,
            area_normal.x, area_normal.y, area_normal.z,
            area};
        ctx->write(light, 0, sizeof(L), L, "render: upload lighting");
        if (lit_program) update_patches(L, m, rs, lit_program);

        const CameraCluster cluster = CameraCluster::from_look_up(pose.look, pose.up);
        float cb[3 + 9 * kFaceCount] = {pose.position.x, pose.position.y, pose.position.z};
        for (int f = 0; f < kFaceCount; ++f) {
            const FaceBasis b = cluster.face(Face(f));
            const glm::vec3 v[3] = {b.look, b.right, b.up};
            for (int k = 0; k < 3; ++k)
                for (int j = 0; j < 3; ++j) cb[3 + 9 * f + 3 * k + j] = v[k][j];
        }
        ctx->write(cam, 0, sizeof(cb), cb, "render: upload camera");
    }

    // Samples per pixel one launch may take. Unlimited (INT_MAX) unless the driver ends loops after a fixed number
    // of iterations per work-item (Context::loop_limit; llvmpipe: 65,535, counted over every loop of the kernel).
    // Bound per sample: per bounce up to six DDA walks (primary or continuation, sun, emitter, portal, patch and
    // its sun ray; a seventh with an area light) of at most dims.x + dims.y + dims.z + 3 steps, plus three binary
    // searches of at most 32 steps. Call after upload_frame (area_on).
    int samples_per_launch(int max_bounces, const char* what) const {
        const long limit = ctx->loop_limit();
        if (limit <= 0) return std::numeric_limits<int>::max();
        const long walk = trace_loops();
        const long per_bounce = (area_on ? 7 : 6) * walk + 3 * 32;
        const long per_sample = (long(max_bounces) + 1) * per_bounce;
        const long fixed = walk + 64;  // the primary ray and the kernel's own loops
        if (fixed + per_sample > limit)
            throw Error(std::string(what) + ": one sample may need " + std::to_string(fixed + per_sample) +
                        " loop iterations, beyond the " + std::to_string(limit) + " that " + ctx->info().name +
                        " runs per work-item before it ends every loop (docs/RELIABILITY.md); use another device "
                        "or fewer bounces");
        return int(std::min<long>((limit - fixed) / per_sample, std::numeric_limits<int>::max()));
    }

    // Renders the six faces' features into `out` (layout: pathtrace.cl's F_CHANNELS planes per face).
    void enqueue_features(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s, cl_mem out);

    void ensure_buffers(int n) {
        if (n == buffers_n) return;
        const std::size_t npix = std::size_t(n) * n;
        features = ctx->alloc(npix * kFaceCount * kFramePlanes * sizeof(float), "render: feature buffers");
        feature_rays = ctx->alloc(npix * kFaceCount * sizeof(std::uint32_t), "render: ray counts");
        mean = ctx->alloc(npix * 3 * sizeof(float), "render: reference");
        var = ctx->alloc(npix * 3 * sizeof(float), "render: reference variance");
        ref_rays = ctx->alloc(npix * sizeof(std::uint32_t), "render: ray counts");
        buffers_n = n;
    }

    template <class... A>
    void set_scene_args(detail::Kernel& k, const RenderSettings& rs, const A&... rest) {
        k.args(grid, size.x, size.y, size.z, mats, lights, cdf, nlights, inv_total, light, region, portals,
               portal_range, int(have_regions), int(rs.sky_portals && have_portals), patches, patch_prob, patch_cdf,
               patch_range, face_slot, face_index, int(rs.sunlit_patches && patches_lit), bvh->nodes(),
               bvh->triangles(), bvh->triangle_info(), bvh->vertex_normals(), int(has_mesh), int(has_blocks), rest...);
    }

    // Per-frame patch probabilities (only when the sun or the materials changed): weights on the device, then
    // normalized per region on the host.
    void update_patches(const float* L, const std::vector<float>& m, const RenderSettings& rs, const char* program) {
        if (npatches == 0) return;
        std::vector<float> key(L, L + kSunSkyParams);
        key.insert(key.end(), m.begin(), m.end());
        if (key == patch_light_key) return;
        patch_light_key = key;
        std::vector<float> w(static_cast<std::size_t>(npatches));
        detail::Kernel& k = kernel(k_patch[program], program, "pt_patch_weights");
        set_scene_args(k, rs, npatches, patch_weight);
        const std::size_t global = std::size_t(npatches), local = local_size(k);
        ctx->launch(k, 1, &global, &local);
        ctx->read(patch_weight, 0, w.size() * 4, w.data(), "render: read patch weights");
        std::vector<float> prob(w.size(), 0.0f), cum(w.size(), 1.0f);
        std::vector<std::int32_t> range = patch_static_range;
        patches_lit = false;
        for (std::size_t r = 0; r < range.size() / 2; ++r) {
            const std::size_t first = std::size_t(range[2 * r]), count = std::size_t(range[2 * r + 1]);
            double total = 0;
            for (std::size_t i = first; i < first + count; ++i) total += w[i];
            if (!(total > 0)) {
                range[2 * r + 1] = 0;  // nothing sunlit in this region
                continue;
            }
            patches_lit = true;
            double acc = 0;
            for (std::size_t i = first; i < first + count; ++i) {
                prob[i] = float(w[i] / total);
                cum[i] = float((acc += w[i]) / total);
            }
            cum[first + count - 1] = 1.0f;
        }
        ctx->write(patch_prob, 0, prob.size() * 4, prob.data(), "render: upload patch probabilities");
        ctx->write(patch_cdf, 0, cum.size() * 4, cum.data(), "render: upload patch CDF");
        ctx->write(patch_range, 0, range.size() * 4, range.data(), "render: upload patch ranges");
    }

    // Seed 004's voxel field (render_voxel_field, voxel_visibility): kernels made on first use.
    detail::Kernel k_vf_sun, k_vf_sh, k_vf_probe, k_vf_face, k_vf_vis;

    // Samples one launch of a kernel may take when each work-item loops `fixed` times plus `per_sample` times per
    // sample (llvmpipe's loop limit, as samples_per_launch), at most `cap` when cap > 0.
    int items_per_launch(long fixed, long per_sample, int cap, const char* what) const {
        long n = std::numeric_limits<int>::max();
        if (const long limit = ctx->loop_limit(); limit > 0) {
            if (fixed + per_sample > limit)
                throw Error(std::string(what) + ": one sample may need " + std::to_string(fixed + per_sample) +
                            " loop iterations, beyond the " + std::to_string(limit) + " that " + ctx->info().name +
                            " runs per work-item before it ends every loop (docs/RELIABILITY.md); use another "
                            "device or fewer bounces");
            n = (limit - fixed) / per_sample;
        }
        if (cap > 0) n = std::min<long>(n, cap);
        return int(n);
    }
    // Loop iterations of one trace(): the DDA walk at most, plus the BVH's node visits and triangle tests. The
    // latter have no useful bound (a ray may visit every node); 32 per level of the tree is an estimate well
    // above what rays measure (bvh_trace_rays reports the steps; tests/test_bvh.cpp), so a launch's loop budget
    // on llvmpipe holds in practice, not by proof (docs/RELIABILITY.md).
    long trace_loops() const {
        return (has_blocks ? long(size.x) + size.y + size.z + 3 : 1) + (has_mesh ? 32L * bvh_depth : 0);
    }
    long bounce_loops() const { return 6 * trace_loops() + 3 * 32; }  // as samples_per_launch

    std::uint64_t sum_rays(const detail::Buffer& b, std::size_t count) {
        std::vector<std::uint32_t> r(count);
        ctx->read(b, 0, count * sizeof(std::uint32_t), r.data(), "render: read ray counts");
        std::uint64_t s = 0;
        for (auto v : r) s += v;
        return s;
    }
};

Renderer::Renderer(const Device& device, const VoxelScene& scene) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.ctx = ngi::detail::shared_context_of(device);
    m.size = scene.size;
    m.palette = scene.palette;
    const std::size_t blocks = std::size_t(scene.size.x) * scene.size.y * scene.size.z;
    if (blocks == 0 || scene.voxels.size() != blocks)
        throw InputError("render: scene " + scene.name + " has " + std::to_string(scene.voxels.size()) +
                         " voxels for a grid of " + std::to_string(blocks));
    for (std::uint8_t v : scene.voxels)
        if (v >= scene.palette.size())
            throw InputError("render: scene " + scene.name + " uses material " + std::to_string(v) + " of " +
                             std::to_string(scene.palette.size()));
    const glm::ivec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int z = 0; z < scene.size.z; ++z)
        for (int y = 0; y < scene.size.y; ++y)
            for (int x = 0; x < scene.size.x; ++x) {
                const glm::ivec3 c(x, y, z);
                const std::uint8_t mat = scene.voxels[scene.index(c)];
                if (mat == 0 || scene.palette[mat].emission == glm::vec3(0.0f)) continue;
                for (int f = 0; f < 6; ++f)
                    if (scene.inside(c + dirs[f]) && !scene.solid(c + dirs[f])) m.emitters.push_back({c, f, mat});
            }
    m.has_blocks = std::any_of(scene.voxels.begin(), scene.voxels.end(), [](std::uint8_t v) { return v != 0; });
    m.has_mesh = !scene.mesh.empty();
    {
        // The mesh: validated, its BVH built here and uploaded once.
        if (m.has_mesh) validate_mesh(scene.mesh, scene.palette.size(), "scene " + scene.name);
        const detail::Bvh bvh = detail::build_bvh(scene.mesh);
        m.bvh_depth = bvh.depth;
        m.bvh = std::make_unique<detail::DeviceBvh>(device, bvh);
    }
    m.grid = m.ctx->alloc(blocks, "render: voxel grid");
    m.ctx->write(m.grid, 0, blocks, scene.voxels.data(), "render: upload voxel grid");
    m.mats = m.ctx->alloc(scene.palette.size() * 8 * sizeof(float), "render: materials");
    m.light = m.ctx->alloc(kLightParams * sizeof(float), "render: lighting");
    m.cam = m.ctx->alloc((3 + 9 * kFaceCount) * sizeof(float), "render: camera");
    auto upload_ints = [&](const std::vector<std::int32_t>& v, const char* what) {
        const std::vector<std::int32_t> data = v.empty() ? std::vector<std::int32_t>(4, 0) : v;  // never empty
        detail::Buffer b = m.ctx->alloc(data.size() * 4, what);
        m.ctx->write(b, 0, data.size() * 4, data.data(), what);
        return b;
    };
    Portals portals;
    if (blocks <= kMaxPortalGrid) portals = find_portals(scene);
    m.have_regions = !portals.range.empty();
    m.have_portals = !portals.faces.empty();
    m.region = upload_ints(m.have_regions ? portals.region : std::vector<std::int32_t>{}, "render: sky regions");
    m.portals = upload_ints(portals.faces, "render: sky portals");
    m.portal_range = upload_ints(portals.range, "render: sky portal ranges");
    Patches patches;
    if (m.have_regions) patches = find_patches(scene, portals.region, int(portals.range.size() / 2));
    m.npatches = int(patches.faces.size() / 4);
    m.patch_static_range = patches.range;
    m.patches = upload_ints(patches.faces, "render: sunlit patches");
    m.patch_range = upload_ints(patches.range, "render: sunlit patch ranges");
    m.face_slot = upload_ints(m.npatches ? patches.slot : std::vector<std::int32_t>{}, "render: patch lookup");
    m.face_index = upload_ints(patches.index, "render: patch lookup");
    const std::size_t np = std::max<std::size_t>(std::size_t(m.npatches), 1) * 4;
    m.patch_prob = m.ctx->alloc(np, "render: patch probabilities");
    m.patch_cdf = m.ctx->alloc(np, "render: patch CDF");
    m.patch_weight = m.ctx->alloc(np, "render: patch weights");
}

Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

void Renderer::Impl::enqueue_features(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s,
                                      cl_mem out) {
    upload_frame(pose, lighting, s, "pathtrace");
    ensure_buffers(s.n);
    kernel(k_features, "pathtrace", "pt_features");
    const std::size_t global = std::size_t(s.n) * s.n * kFaceCount, local = local_size(k_features);
    const int feature_chunk = samples_per_launch(0, "render: feature buffers");
    for (int first = 0; first < s.feature_spp; first += feature_chunk) {
        const int last = std::min(s.feature_spp, first + feature_chunk);
        set_scene_args(k_features, s, cam, s.n, s.feature_spp, first, last, std::uint32_t(s.seed), out, feature_rays);
        ctx->launch(k_features, 1, &global, &local);
    }
}

void Renderer::render_planes(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s,
                             const DeviceBuffer& planes, RenderStats* stats) {
    check_settings(s);
    Impl& m = *impl_;
    const std::size_t need = std::size_t(s.n) * s.n * kFaceCount * kFramePlanes * sizeof(float);
    if (!planes) throw InputError("render planes: the planes buffer is empty");
    if (detail::shared_context_of(planes.device()) != m.ctx)
        throw InputError("render planes: the planes buffer belongs to another device than the renderer");
    if (planes.bytes() < need)
        throw InputError("render planes: the planes buffer holds " + std::to_string(planes.bytes()) + " bytes, " +
                         std::to_string(s.n) + "x" + std::to_string(s.n) + " faces need " + std::to_string(need));
    if (!planes.writable()) throw InputError("render planes: the planes buffer was created CL_MEM_READ_ONLY");
    const auto t0 = std::chrono::steady_clock::now();
    m.enqueue_features(pose, lighting, s, planes.opencl_mem());
    if (stats) {
        stats->feature_rays = m.sum_rays(m.feature_rays, std::size_t(s.n) * s.n * kFaceCount);
        stats->feature_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
}

Frame Renderer::render(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s, RenderStats* stats) {
    check_settings(s);
    // Held at once on the host: the downloaded planes and the frame's images (the same size), and the reference.
    const std::uint64_t frame_floats = std::uint64_t(s.n) * std::uint64_t(s.n) * (kFaceCount * kFramePlanes * 2 + 3);
    check_host_memory("render: a frame of face size " + std::to_string(s.n), frame_floats * sizeof(float));
    Impl& m = *impl_;
    const auto t0 = std::chrono::steady_clock::now();
    m.ensure_buffers(s.n);
    m.enqueue_features(pose, lighting, s, m.features.get());
    const std::size_t npix = std::size_t(s.n) * s.n;
    const std::size_t global = npix * kFaceCount;
    std::vector<float> out(npix * kFaceCount * kFramePlanes);
    m.ctx->read(m.features, 0, out.size() * sizeof(float), out.data(), "render: read feature buffers");

    Frame fr;
    fr.n = s.n;
    fr.look = pose.look;
    fr.up = pose.up;
    if (lighting.area_light.enabled()) {  // what a consumer needs to place the light relative to each pixel
        fr.area_light = lighting.area_light;
        fr.position = pose.position;
    }
    for (int f = 0; f < kFeatureCount; ++f)
        for (int face = 0; face < kFaceCount; ++face) {
            Image img(s.n, s.n, feature_channels(Feature(f)));
            const float* src = out.data() + (std::size_t(face) * kFramePlanes + frame_plane(Feature(f))) * npix;
            std::copy(src, src + img.data.size(), img.data.begin());
            fr.faces[f][face] = std::move(img);
        }
    const auto t1 = std::chrono::steady_clock::now();
    if (stats) {
        stats->feature_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
        stats->feature_rays = m.sum_rays(m.feature_rays, global);
    }
    if (s.reference) fr.reference = render_reference(pose, lighting, s, nullptr, stats);
    return fr;
}

Image Renderer::render_ao(const CameraPose& pose, const RenderSettings& s, int rays, float max_distance, Face face) {
    check_settings(s);
    if (rays < 1 || rays > (1 << 20))
        throw InputError("render ambient occlusion: rays per pixel " + std::to_string(rays) + " not in 1..1048576");
    if (!(max_distance > 0.0f))
        throw InputError("render ambient occlusion: max distance " + std::to_string(max_distance) + " must be > 0");
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    const std::size_t local = Impl::local_size(m.kernel(m.k_ao, "ao_geometry", "pt_ao"));
    if (m.ao.bytes() < npix * sizeof(float)) m.ao = m.ctx->alloc(npix * sizeof(float), "render: ambient occlusion");
    const int chunk = m.samples_per_launch(0, "render: ambient occlusion");
    const float dist = std::min(max_distance, 1.0e30f);  // the tracer's "no limit"
    for (int first = 0; first < rays; first += chunk) {
        const int last = std::min(rays, first + chunk);
        m.set_scene_args(m.k_ao, s, m.cam, int(face), s.n, rays, first, last, dist, std::uint32_t(s.seed), m.ao);
        m.ctx->launch(m.k_ao, 1, &npix, &local);
    }
    Image ao(s.n, s.n, 1);
    m.ctx->read(m.ao, 0, npix * sizeof(float), ao.data.data(), "render: read ambient occlusion");
    return ao;
}

Image Renderer::render_geometry(const CameraPose& pose, const RenderSettings& s, float smooth_sigma, Face face) {
    check_settings(s);
    if (!(smooth_sigma >= 0.0f && smooth_sigma <= kMaxSmoothSigma))
        throw InputError("render geometry: smoothing sigma " + std::to_string(smooth_sigma) + " not in 0.." +
                         std::to_string(kMaxSmoothSigma) + " blocks");
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    if (m.geometry.bytes() < 7 * npix * sizeof(float))
        m.geometry = m.ctx->alloc(7 * npix * sizeof(float), "render: geometry");
    m.set_scene_args(m.kernel(m.k_geometry, "ao_geometry", "pt_geometry"), s, m.cam, int(face), s.n, smooth_sigma,
                     m.geometry);
    const std::size_t local = Impl::local_size(m.k_geometry);
    m.ctx->launch(m.k_geometry, 1, &npix, &local);
    Image g(s.n, s.n, 7);
    m.ctx->read(m.geometry, 0, 7 * npix * sizeof(float), g.data.data(), "render: read geometry");
    return g;
}

Image Renderer::render_surface(const CameraPose& pose, const RenderSettings& s, Face face) {
    check_settings(s);
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    if (m.geometry.bytes() < 7 * npix * sizeof(float))
        m.geometry = m.ctx->alloc(7 * npix * sizeof(float), "render: geometry");
    m.set_scene_args(m.kernel(m.k_surface, "ao_geometry", "pt_surface"), s, m.cam, int(face), s.n, m.geometry);
    const std::size_t local = Impl::local_size(m.k_surface);
    m.ctx->launch(m.k_surface, 1, &npix, &local);
    Image g(s.n, s.n, 6);
    m.ctx->read(m.geometry, 0, 6 * npix * sizeof(float), g.data.data(), "render: read surface");
    return g;
}

Image Renderer::render_reference(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s,
                                 Image* variance, RenderStats* stats) {
    check_settings(s);
    Impl& m = *impl_;
    const auto t0 = std::chrono::steady_clock::now();
    m.upload_frame(pose, lighting, s, "pathtrace");
    m.ensure_buffers(s.n);
    const std::size_t npix = std::size_t(s.n) * s.n;
    const std::size_t local = Impl::local_size(m.kernel(m.k_reference, "pathtrace", "pt_reference"));
    const int chunk = m.samples_per_launch(s.max_bounces, "render: reference");
    for (int first = 0; first < s.reference_spp; first += chunk) {
        const int last = std::min(s.reference_spp, first + chunk);
        m.set_scene_args(m.k_reference, s, m.cam, int(s.reference_face), s.n, s.reference_spp, first, last,
                         s.max_bounces, s.rr_start, std::uint32_t(s.seed), m.mean, m.var, m.ref_rays);
        m.ctx->launch(m.k_reference, 1, &npix, &local);
    }
    Image mean(s.n, s.n, 3), var(s.n, s.n, 3);
    m.ctx->read(m.mean, 0, mean.data.size() * sizeof(float), mean.data.data(), "render: read reference");
    m.ctx->read(m.var, 0, var.data.size() * sizeof(float), var.data.data(), "render: read reference variance");
    const auto t1 = std::chrono::steady_clock::now();
    if (stats) {
        stats->reference_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
        stats->reference_rays = m.sum_rays(m.ref_rays, npix);
        // Mean relative standard error over lit pixel channels.
        double sum = 0;
        std::size_t cnt = 0;
        for (std::size_t i = 0; i < mean.data.size(); ++i)
            if (mean.data[i] > 1e-4f) {
                sum += std::sqrt(double(var.data[i])) / mean.data[i];
                ++cnt;
            }
        stats->reference_rel_stderr = cnt ? sum / double(cnt) : 0.0;
    }
    if (variance) *variance = std::move(var);
    return mean;
}

// ---- seed 004's voxel radiance field (docs/VOXEL_FIELD.md) --------------------------------------------------

namespace {

constexpr int kMaxFieldSamples = 1 << 20;  // per-voxel sample counts (directions, sun rays, point samples)

std::string grid_text(glm::ivec3 s) {
    return std::to_string(s.x) + "x" + std::to_string(s.y) + "x" + std::to_string(s.z);
}

// Voxels usable with a renderer of grid `size`: from surface_voxels() of a scene of that size, consistent arrays.
void check_voxels(const SurfaceVoxels& v, glm::ivec3 size, const std::string& what, std::size_t limit) {
    if (v.grid != size)
        throw InputError(what + ": surface voxels of a " + grid_text(v.grid) + " grid, the renderer's scene is " +
                         grid_text(size));
    const std::size_t blocks = std::size_t(size.x) * std::size_t(size.y) * std::size_t(size.z);
    if (blocks > kMaxFieldGridBlocks)
        throw InputError(what + ": the scene's grid " + grid_text(size) + " has more than " +
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
                             std::to_string(v.exposed[i]) + " is not a surface voxel of a " + grid_text(size) +
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

VoxelField Renderer::render_voxel_field(const SurfaceVoxels& voxels, const Lighting& lighting,
                                        const VoxelFieldSettings& s) {
    Impl& m = *impl_;
    check_voxels(voxels, m.size, "voxel field", kMaxFieldVoxels);
    check_field_settings(s);
    // vf_sh projects the radiance its rays meet; rays never meet the area light (it is not geometry), so its SH
    // would miss the light's direct part while the other outputs include it. Refused rather than inconsistent.
    if (lighting.area_light.enabled())
        throw InputError("voxel field: the lighting has an area light, which the voxel field does not support");
    const auto t0 = std::chrono::steady_clock::now();
    detail::Context& ctx = *m.ctx;
    m.kernel(m.k_vf_sun, "voxel_field", "vf_sun_visibility");
    m.kernel(m.k_vf_sh, "voxel_field", "vf_sh");
    m.kernel(m.k_vf_probe, "voxel_field", "vf_probe_lighting");
    m.kernel(m.k_vf_face, "voxel_field", "vf_face_lighting");
    const std::size_t local_sun = Impl::local_size(m.k_vf_sun), local_sh = Impl::local_size(m.k_vf_sh),
                      local_probe = Impl::local_size(m.k_vf_probe), local_face = Impl::local_size(m.k_vf_face);
    RenderSettings rs;
    rs.max_bounces = s.max_bounces;
    rs.rr_start = s.rr_start;
    rs.seed = s.seed;
    rs.sky_portals = s.sky_portals;
    rs.sunlit_patches = s.sunlit_patches;
    m.upload_frame(CameraPose{}, lighting, rs, "voxel_field");
    const std::size_t V = voxels.size();
    const VoxelBuffers in = upload_voxels(ctx, voxels, true);
    detail::Buffer vis = ctx.alloc(V * 4, "voxel field: sun visibility");
    detail::Buffer sh = ctx.alloc(V * 27 * 4, "voxel field: SH");
    detail::Buffer direct = ctx.alloc(V * 3 * 4, "voxel field: direct lighting");
    detail::Buffer full = ctx.alloc(V * 3 * 4, "voxel field: lighting");
    detail::Buffer face = ctx.alloc(V * 18 * 4, "voxel field: face lighting");
    detail::Buffer rays = ctx.alloc(V * 6 * 4, "voxel field: ray counts");
    const int nvox = int(V);
    const std::uint32_t seed = s.seed;
    const std::size_t global = V, global6 = 6 * V;
    VoxelField out;
    const long walk = m.trace_loops(), bounce = m.bounce_loops();
    const int cap = s.max_samples_per_launch;

    // The sun's visibility first: vf_sh's last launch adds the sun with it.
    const glm::vec3 E = lighting.sun.irradiance;
    if (E.r + E.g + E.b > 0.0f) {
        const int chunk = m.items_per_launch(64, walk + 8, cap, "voxel field: sun visibility");
        for (int first = 0; first < s.sun_rays; first += chunk) {
            const int last = int(std::min<long>(s.sun_rays, long(first) + chunk));
            m.set_scene_args(m.k_vf_sun, rs, in.probe, in.cells, nvox, s.sun_rays, first, last, seed, vis, rays);
            ctx.launch(m.k_vf_sun, 1, &global, &local_sun);
        }
        out.rays += m.sum_rays(rays, V);
    } else {
        ctx.fill_zero(vis, 0, V * 4, "voxel field: sun visibility");
    }

    const int side = int(std::lround(std::sqrt(double(s.directions))));
    {
        const long per_direction = walk + long(s.max_bounces) * bounce + 32;
        const int chunk = m.items_per_launch(4 * 27 + 64, per_direction, cap, "voxel field: SH projection");
        for (int first = 0; first < s.directions; first += chunk) {
            const int last = int(std::min<long>(s.directions, long(first) + chunk));
            m.set_scene_args(m.k_vf_sh, rs, in.probe, in.cells, nvox, side, first, last, s.max_bounces, s.rr_start,
                             seed, vis, sh, rays);
            ctx.launch(m.k_vf_sh, 1, &global, &local_sh);
        }
        out.rays += m.sum_rays(rays, V);
    }

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

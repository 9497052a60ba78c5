// Host side of the path tracer (the tracer programs of runtime/programs.cpp: kernels/scene.cl, lighting.cl,
// pathtrace.cl, ...): scene upload, per-frame lights and camera, launch budgets, frames (features, reference).
// The Renderer's other renders: ao_geometry.cpp (AO, geometry, surface), voxel_field.cpp (seed 004's voxel field).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "ngi/camera.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/render.hpp"
#include "ops/luminance.hpp"
#include "pipeline/frame_planes.hpp"
#include "render/bvh.hpp"
#include "render/light_regions.hpp"
#include "render/renderer_impl.hpp"
#include "render/tracer_constants.hpp"
#include "runtime/context.hpp"

namespace ngi {
namespace {

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

}  // namespace

void Renderer::Impl::check_settings(const RenderSettings& s) {
    if (s.n < 1 || s.n > 8192) throw InputError("render: face size n must be in 1..8192, got " + std::to_string(s.n));
    if (s.feature_spp < 1 || s.reference_spp < 1) throw InputError("render: samples per pixel must be at least 1");
    if (s.max_bounces < 0 || s.rr_start < 0) throw InputError("render: bounces must not be negative");
}

detail::Kernel& Renderer::Impl::kernel(detail::Kernel& k, const char* program, const char* name) {
    if (!k.get()) k = ctx->kernel(program, name, pathtrace_defines());
    return k;
}

void Renderer::Impl::upload_frame(const CameraPose& pose, const Lighting& l, const RenderSettings& rs,
                                  const char* lit_program) {
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

int Renderer::Impl::samples_per_launch(int max_bounces, const char* what) const {
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

void Renderer::Impl::ensure_buffers(int n) {
    if (n == buffers_n) return;
    const std::size_t npix = std::size_t(n) * n;
    features = ctx->alloc(npix * kFaceCount * kFramePlanes * sizeof(float), "render: feature buffers");
    feature_rays = ctx->alloc(npix * kFaceCount * sizeof(std::uint32_t), "render: ray counts");
    mean = ctx->alloc(npix * 3 * sizeof(float), "render: reference");
    var = ctx->alloc(npix * 3 * sizeof(float), "render: reference variance");
    ref_rays = ctx->alloc(npix * sizeof(std::uint32_t), "render: ray counts");
    buffers_n = n;
}

void Renderer::Impl::update_patches(const float* L, const std::vector<float>& m, const RenderSettings& rs,
                                    const char* program) {
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

int Renderer::Impl::items_per_launch(long fixed, long per_sample, int cap, const char* what) const {
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

std::uint64_t Renderer::Impl::sum_rays(const detail::Buffer& b, std::size_t count) {
    std::vector<std::uint32_t> r(count);
    ctx->read(b, 0, count * sizeof(std::uint32_t), r.data(), "render: read ray counts");
    std::uint64_t s = 0;
    for (auto v : r) s += v;
    return s;
}

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
    detail::Portals portals;
    if (blocks <= detail::kMaxPortalGrid) portals = detail::find_portals(scene);
    m.have_regions = !portals.range.empty();
    m.have_portals = !portals.faces.empty();
    m.region = upload_ints(m.have_regions ? portals.region : std::vector<std::int32_t>{}, "render: sky regions");
    m.portals = upload_ints(portals.faces, "render: sky portals");
    m.portal_range = upload_ints(portals.range, "render: sky portal ranges");
    detail::Patches patches;
    if (m.have_regions) patches = detail::find_patches(scene, portals.region, int(portals.range.size() / 2));
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
    Impl::check_settings(s);
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
    Impl::check_settings(s);
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

Image Renderer::render_reference(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s,
                                 Image* variance, RenderStats* stats) {
    Impl::check_settings(s);
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

}  // namespace ngi

// The OpenGL viewer's G-buffers agree with ngi's path tracer (issue 26, item 3). One small scene with sun, sky and
// an emissive block, one camera cluster, N = 64: the six faces rasterized by samples/gl (shadow map + baked sky and
// emitters) and traced by ngi::Renderer at 1024 direct samples per pixel. Asserted and printed:
//   - albedo, normal, depth (and emission, env): the share of pixels that differ, per face and feature (only pixels on geometric edges
//     may differ: there one primary sample decides which block a pixel sees, and GL's rasterization rules and the
//     DDA's float crossings may pick differently);
//   - direct light on the pixels both see alike and away from edges: mean relative error (luminance) and the share
//     of pixels beyond a 10 % + 0.01 tolerance;
//   - the shipped indirect-light rung's lightmap from the rasterized inputs (handed over as image descriptors, as the
//     viewer does) against the one from the traced frame: SSIM (data_range = the traced lightmap's maximum,
//     docs/CONVENTIONS.md section 11) >= 0.97.
// Usage: ngi_gl_agreement MODEL.safetensors [SCENE [SKY_RAYS [TEXELS [all|sun|sky]]]]
// (sun: the sky set to black; sky: the sun's irradiance set to 0; to tell which light limits the agreement)   (device: $NGI_TEST_DEVICE, default cpu = PoCL)
// With SCENE (a spec or .vox path) it measures instead of testing: frame 0 of the scene's camera path at its default
// time, the viewer's default bake (automatic texels, 256 sky rays); it prints the same numbers (for the README).
#include <epoxy/gl.h>  // before GLFW: epoxy must come before GL/gl.h
#include <GLFW/glfw3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <ngi/camera_path.hpp>
#include <ngi/metrics.hpp>
#include <ngi/render.hpp>

#include "gbuffer_pass.hpp"
#include "light_bake.hpp"
#include "ngi_handoff.hpp"
#include "shadow_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double secs(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
float lum(float r, float g, float b) { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }

// Bounds (justified in samples/gl/README.md, "Agreement with the tracer").
constexpr double kMaxDifferingShare = 0.02;   // albedo / normal / depth pixels that differ, per face and feature
constexpr double kMaxDirectMeanRelError = 0.02;
constexpr double kMaxDirectBeyondShare = 0.02;
constexpr double kMinLightmapSsim = 0.97;

ngi::VoxelScene agreement_scene() {
    ngi::VoxelScene s(glm::ivec3(16, 10, 16), "gl_agreement");
    const auto floor = s.add_material({glm::vec3(0.55f, 0.5f, 0.45f), glm::vec3(0.0f), false});
    const auto wall = s.add_material({glm::vec3(0.7f, 0.3f, 0.2f), glm::vec3(0.0f), false});
    const auto white = s.add_material({glm::vec3(0.8f), glm::vec3(0.0f), false});
    const auto green = s.add_material({glm::vec3(0.2f, 0.6f, 0.25f), glm::vec3(0.0f), false});
    const auto glow = s.add_material({glm::vec3(0.9f, 0.8f, 0.6f), glm::vec3(6.0f, 4.0f, 2.0f), false});
    s.fill({0, 0, 0}, {16, 1, 16}, floor);
    s.fill({2, 1, 2}, {13, 5, 3}, wall);        // a wall that casts the sun's shadow
    s.fill({3, 4, 5}, {9, 5, 10}, white);       // an overhang: shadow and occluded sky below it
    s.fill({3, 1, 5}, {4, 4, 6}, white);        // its pillar
    s.fill({10, 1, 8}, {11, 6, 9}, green);      // a free-standing pillar
    s.fill({6, 1, 7}, {7, 2, 8}, glow);         // the emissive block, under the overhang
    s.fill({12, 1, 11}, {14, 3, 13}, white);    // a box
    s.default_time = 15.0f;
    return s;
}

struct Share {
    long differ = 0, total = 0, off_edge = 0;
};

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || argc > 6) {
        std::fprintf(stderr, "usage: ngi_gl_agreement MODEL.safetensors [SCENE [SKY_RAYS [TEXELS [all|sun|sky]]]]\n");
        return 2;
    }
    const auto t_start = Clock::now();
    const int n = 64, spp = 1024;
    const char* dev_env = std::getenv("NGI_TEST_DEVICE");
    ngi::Device device = ngi::Device::open(dev_env && *dev_env ? dev_env : "cpu");
    const bool measure = argc >= 3;
    const ngi::VoxelScene scene = measure ? ngi::make_scene(argv[2]) : agreement_scene();
    ngi::Lighting lighting = ngi::lighting_at(scene.default_time, scene.sun_azimuth);
    const std::string component = argc == 6 ? argv[5] : "all";
    if (component == "sun") lighting.sky = ngi::Sky{};
    if (component == "sky") lighting.sun.irradiance = glm::vec3(0.0f);
    ngi::CameraPose pose;
    pose.position = glm::vec3(8.5f, 2.3f, 13.6f);
    pose.look = glm::normalize(glm::vec3(-0.25f, -0.3f, -1.0f));
    pose.up = glm::vec3(0, 1, 0);
    if (measure) pose = ngi::make_camera_path(scene, ngi::CameraPathKind::Auto, 2, 0).at(0.0f);

    // Raster.
    ngi_gl::GlContext gl(64, 64, false, "ngi_gl_agreement");
    const auto faces = ngi_gl::exposed_faces(scene);
    ngi_gl::BakeSettings bs;
    bs.texels = argc >= 5 ? std::atoi(argv[4]) : measure ? 0 : 4;
    bs.sky_rays = argc >= 4 ? std::atoi(argv[3]) : measure ? 256 : 1024;
    const ngi_gl::LightBake bake = ngi_gl::bake_static_light(scene, faces, lighting, bs);
    ngi_gl::GpuScene gpu(ngi_gl::build_mesh(scene, faces, [&](std::size_t i) { return bake.tile_origin(i); }), bake);
    ngi_gl::ShadowMap shadow(2048);
    shadow.render(gpu, lighting.sun.direction, scene.size);
    ngi_gl::GBufferPass gbuffer(n);
    if (const char* f = std::getenv("NGI_GL_SHADOW_FILTER")) {  // "r,offset": for measuring other filters
        int r = 1;
        float off = 0.5f;
        if (std::sscanf(f, "%d,%f", &r, &off) == 2) gbuffer.set_shadow_filter(r, off);
    }
    gbuffer.render(gpu, shadow, pose, lighting);
    gbuffer.read_back();
    const ngi::Frame raster = gbuffer.to_frame(pose);
    std::printf("gl: %s; %zu faces, bake %d^2 texels x %d sky rays in %.0f ms; shadow map %d^2 (%.1f mm texels)\n",
                gl.renderer().c_str(), faces.size(), bake.k, bs.sky_rays, bake.ms, shadow.resolution(),
                1000.0 * shadow.texel_metres());

    // Trace.
    const auto t_trace = Clock::now();
    ngi::Renderer renderer(device, scene);
    ngi::RenderSettings rs;
    rs.n = n;
    rs.feature_spp = spp;
    rs.reference = false;
    rs.seed = 1;
    const ngi::Frame traced = renderer.render(pose, lighting, rs);
    // The tracer's own noise floor: the same frame with another seed, scored like the raster below.
    rs.seed = 2;
    const ngi::Frame traced2 = renderer.render(pose, lighting, rs);
    std::printf("tracer: %s, N = %d, feature_spp %d: %.1f s\n", device.info().name.c_str(), n, spp, secs(t_trace));

    bool ok = true;
    // Geometry features.
    // Emission and env follow the same rule (exact up to RGBA16F rounding): the material's emission, the sky formula.
    const ngi::Feature geo[5] = {ngi::Feature::Albedo, ngi::Feature::Normal, ngi::Feature::Depth,
                                 ngi::Feature::Emission, ngi::Feature::Env};
    double direct_abs = 0, direct_ref = 0, noise_abs = 0;
    long direct_px = 0, direct_beyond = 0;
    std::printf("%-6s %-8s %8s %8s %9s\n", "face", "feature", "differ", "share", "off-edge");
    for (int f = 0; f < ngi::kFaceCount; ++f) {
        const ngi::Face face = ngi::Face(f);
        const ngi::Image& tn = traced.get(ngi::Feature::Normal, face);
        const ngi::Image& td = traced.get(ngi::Feature::Depth, face);
        // A pixel is on an edge when a 4-neighbour in the traced image shows another face orientation, sky on one
        // side only, or a depth step beyond what a slanted plane gives between neighbours.
        auto edge = [&](int y, int x) {
            for (auto [dy, dx] : {std::pair{0, 1}, {0, -1}, {1, 0}, {-1, 0}}) {
                const int yy = y + dy, xx = x + dx;
                if (yy < 0 || xx < 0 || yy >= n || xx >= n) continue;
                for (int c = 0; c < 3; ++c)
                    if (tn.at(c, y, x) != tn.at(c, yy, xx)) return true;
                const float a = td.at(0, y, x), b = td.at(0, yy, xx);
                if (std::abs(a - b) > 0.05f + 0.1f * std::min(a, b)) return true;
            }
            return false;
        };
        std::vector<char> differs(std::size_t(n) * n, 0);
        for (const ngi::Feature feat : geo) {
            const ngi::Image& a = raster.get(feat, face);
            const ngi::Image& b = traced.get(feat, face);
            Share s;
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    bool d = false;
                    for (int c = 0; c < a.channels; ++c) {
                        const float va = a.at(c, y, x), vb = b.at(c, y, x);
                        // albedo passes through RGBA16F (relative rounding 2^-11), normals through RG16F's
                        // octahedral map (exact for face normals), depth through the D32F depth attachment
                        // (window depth: relative error ~ z / near x 2^-24, 3e-4 at this 16 m scene's 50 m).
                        // env's sky formula runs in GLSL vs OpenCL float (sqrt, pow 8): same relative bound.
                        const float tol = 1e-3f * std::max(1.0f, std::abs(vb));
                        if (!(std::abs(va - vb) <= tol)) d = true;
                    }
                    ++s.total;
                    if (d) {
                        ++s.differ;
                        differs[std::size_t(y) * n + x] = 1;
                        if (!edge(y, x)) ++s.off_edge;
                    }
                }
            const double share = double(s.differ) / double(s.total);
            std::printf("%-6s %-8s %8ld %7.2f%% %9ld\n", ngi::face_name(face), ngi::feature_name(feat), s.differ,
                        100.0 * share, s.off_edge);
            if (share > kMaxDifferingShare) ok = false;
        }
        // Direct light where both see the same surface, away from edges.
        const ngi::Image& ra = raster.get(ngi::Feature::Direct, face);
        const ngi::Image& ta = traced.get(ngi::Feature::Direct, face);
        const ngi::Image& t2 = traced2.get(ngi::Feature::Direct, face);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                if (differs[std::size_t(y) * n + x] || edge(y, x) || td.at(0, y, x) >= 1e4f) continue;
                const float lr = lum(ra.at(0, y, x), ra.at(1, y, x), ra.at(2, y, x));
                const float lt = lum(ta.at(0, y, x), ta.at(1, y, x), ta.at(2, y, x));
                direct_abs += std::abs(lr - lt);
                noise_abs += std::abs(lum(t2.at(0, y, x), t2.at(1, y, x), t2.at(2, y, x)) - lt);
                direct_ref += lt;
                ++direct_px;
                if (std::abs(lr - lt) > 0.1f * lt + 0.01f) ++direct_beyond;
            }
    }
    const double direct_rel = direct_ref > 0 ? direct_abs / direct_ref : 0;
    const double beyond_share = direct_px ? double(direct_beyond) / double(direct_px) : 0;
    std::printf("direct: %ld pixels compared; mean relative error %.4f (bound %.2f; tracer vs tracer, another seed: "
                "%.4f); beyond 10%% + 0.01: %.2f%% (bound %.0f%%)\n",
                direct_px, direct_rel, kMaxDirectMeanRelError, direct_ref > 0 ? noise_abs / direct_ref : 0.0,
                100.0 * beyond_share, 100.0 * kMaxDirectBeyondShare);
    if (direct_rel > kMaxDirectMeanRelError || beyond_share > kMaxDirectBeyondShare) ok = false;

    // The network on both.
    ngi::Model model = ngi::Model::load(device, argv[1]);
    ngi::SurroundPipeline pipeline(device, n);
    const ngi::Image lm_traced = pipeline.run(model, traced, true, false, false).lightmap;
    const ngi_gl::LitFrame lit = ngi_gl::light_frame(pipeline, model, gbuffer, pose, true, false);
    float range = 0;
    for (float v : lm_traced.data) range = std::max(range, v);
    const ngi::ImageMetrics m = ngi::compare_images(device, lm_traced, lit.lightmap, range);
    // The same network on the second trace: how far the tracer's own noise moves the lightmap.
    const ngi::Image lm_traced2 = pipeline.run(model, traced2, true, false, false).lightmap;
    const ngi::ImageMetrics m2 = ngi::compare_images(device, lm_traced, lm_traced2, range);
    std::printf("lightmap (%s, rasterized vs traced inputs): SSIM %.4f (bound %.2f), PSNR %.2f dB, data_range %.3f; "
                "traced vs traced (another seed): SSIM %.4f, PSNR %.2f dB\n",
                argv[1], m.ssim, kMinLightmapSsim, m.psnr, range, m2.ssim, m2.psnr);
    if (!(m.ssim >= kMinLightmapSsim)) ok = false;
    gbuffer.unmap();
    std::printf("%s in %.1f s\n", measure ? "MEASURED" : ok ? "PASS" : "FAIL", secs(t_start));
    return measure || ok ? 0 : 1;
}

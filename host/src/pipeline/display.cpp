// ngi::DisplayView (ngi/display.hpp): the pipeline's N x N lightmap at the display's S x S resolution, accumulated
// over frames. Kernels: kernels/display.cl (guides, the low-resolution indirect light, the temporal pass, compose),
// kernels/jbu.cl (the upsampling), compose.cl (bilinear resize, tone map). Definitions: docs/CONVENTIONS.md section 20.
#include "ngi/display.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>

#include "ngi/error.hpp"
#include "ops/jbu.hpp"
#include "pipeline/frame_planes.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "pipeline/ssgi.hpp"
#include "runtime/context.hpp"

namespace ngi {

namespace {

constexpr const char* kOp = "display view";
constexpr int kMaxSide = detail::kJbuMaxSide;
using Clock = std::chrono::steady_clock;

// Display pixels of one row per work-item of display_temporal (its float8 lanes; kernels/display.cl says why).
constexpr int kDisplayVec = 8;

std::string display_defines() {
    // Beyond the preprocessing's depth range a pixel is sky (the renderer writes 1e4 m there), as for the ssgi gather.
    return detail::join_defines({detail::frame_plane_defines(), detail::define("DISPLAY_MAX_DEPTH", detail::kMaxSurfaceDepth),
                                 detail::define("DISPLAY_VEC", kDisplayVec), detail::tonemap_defines()});
}

void require(bool ok, const std::string& what) {
    if (!ok) throw InputError(std::string(kOp) + ": " + what);
}

void check_settings(const DisplaySettings& s) {
    auto finite_pos = [](float v) { return std::isfinite(v) && v > 0.0f; };
    require(finite_pos(s.sigma_spatial), "sigma_spatial " + std::to_string(s.sigma_spatial) + " is not finite and > 0");
    require(finite_pos(s.sigma_plane), "sigma_plane " + std::to_string(s.sigma_plane) + " is not finite and > 0");
    require(std::isfinite(s.normal_power) && s.normal_power >= 0.0f && s.normal_power <= 1024.0f,
            "normal_power " + std::to_string(s.normal_power) + " is not in [0, 1024]");
    require(s.radius >= 1 && s.radius <= detail::kJbuMaxRadius,
            "radius " + std::to_string(s.radius) + " is not in [1, " + std::to_string(detail::kJbuMaxRadius) + "]");
    require(std::isfinite(s.blend) && s.blend > 0.0f && s.blend <= 1.0f,
            "blend " + std::to_string(s.blend) + " is not in (0, 1]");
    require(std::isfinite(s.depth_rel) && s.depth_rel >= 0.0f && s.depth_rel <= 1.0f,
            "depth_rel " + std::to_string(s.depth_rel) + " is not in [0, 1]");
    require(std::isfinite(s.depth_abs) && s.depth_abs >= 0.0f && s.depth_abs <= 1000.0f,
            "depth_abs " + std::to_string(s.depth_abs) + " is not in [0, 1000] metres");
    require(std::isfinite(s.clip_margin) && s.clip_margin <= 1e6f,
            "clip_margin " + std::to_string(s.clip_margin) + " is not finite (a negative value turns the clamp off)");
}

void check_display_buffer(const DeviceBuffer& b, const Device& device, std::size_t need, bool write, const std::string& what) {
    const std::string where = std::string(kOp) + ": the " + what + " buffer";
    if (!b) throw InputError(where + " is empty");
    if (detail::shared_context_of(b.device()) != detail::shared_context_of(device))
        throw InputError(where + " belongs to another device than the display view");
    if (b.bytes() < need)
        throw InputError(where + " holds " + std::to_string(b.bytes()) + " bytes, " + std::to_string(need) +
                         " are needed");
    if (write && !b.writable()) throw InputError(where + " was created CL_MEM_READ_ONLY");
}

// The front camera as kernels/display.cl takes it (DISPLAY_CAMERA_ARGS: twelve floats, centre, look, right, up).
struct CameraArgs {
    glm::vec3 centre{0.0f}, look{0.0f}, right{0.0f}, up{0.0f};
    static CameraArgs of(glm::vec3 position, glm::vec3 look, glm::vec3 up) {
        const CameraCluster c = CameraCluster::from_look_up(look, up);  // InputError for a look that is no camera
        return {position, -c.gamma, c.alpha, c.beta};
    }
};

}  // namespace

const char* display_upsampler_name(DisplayUpsampler u) { return u == DisplayUpsampler::Jbu ? "jbu" : "bilinear"; }

DisplayUpsampler display_upsampler_from_name(const std::string& name) {
    if (name == "jbu") return DisplayUpsampler::Jbu;
    if (name == "bilinear") return DisplayUpsampler::Bilinear;
    throw InputError("display upsampler '" + name + "' is not one of jbu, bilinear");
}

struct DisplayView::Impl {
    Device device;
    detail::Context& ctx;
    int size;
    DisplaySettings settings;
    detail::Kernel geometry, low_indirect, clip_box, temporal, compose, resize;
    detail::JointBilateralUpsample jbu;
    detail::Buffer low_normal, low_position, low_light, low_box, normal, position, upsampled, history[2], prev_depth, counters;
    detail::Buffer result, staging, low_planes_buf, low_light_buf, display_planes_buf;
    DeviceBuffer out_handles[3];
    int latest = 0;             // history[latest] holds the last frame's accumulated indirect light
    bool has_history = false;
    CameraArgs prev_camera{};

    Impl(const Device& d, int s, const DisplaySettings& ds)
        : device(d), ctx(detail::context_of(d)), size(s), settings(ds),
          geometry(ctx.kernel("display", "display_geometry", display_defines())),
          low_indirect(ctx.kernel("display", "display_low_indirect", display_defines())),
          clip_box(ctx.kernel("display", "display_clip_box", display_defines())),
          temporal(ctx.kernel("display", "display_temporal", display_defines())),
          compose(ctx.kernel("display", "display_compose", display_defines())),
          resize(ctx.kernel("compose", "resize_bilinear", detail::compose_defines())), jbu(ctx) {
        const std::size_t plane = std::size_t(s) * s * sizeof(float);
        counters = ctx.alloc(2 * sizeof(std::uint32_t), "display view: counters");
        for (detail::Buffer* b : {&normal, &position, &upsampled, &history[0], &history[1]})
            *b = ctx.alloc(3 * plane, "display view: display-resolution planes");
        prev_depth = ctx.alloc(plane, "display view: previous depth");
    }

    void guides(cl_mem planes, int side, const CameraArgs& cam, cl_mem nrm, cl_mem pos) {
        const CameraArgs& k = cam;
        geometry.args(planes, side, k.centre.x, k.centre.y, k.centre.z, k.look.x, k.look.y, k.look.z, k.right.x,
                      k.right.y, k.right.z, k.up.x, k.up.y, k.up.z, nrm, pos);
        const std::size_t g[2] = {(std::size_t(side) + kDisplayVec - 1) / kDisplayVec, std::size_t(side)};
        ctx.launch(geometry, 2, g, detail::kLocal2);
    }
};

DisplayView::DisplayView(const Device& device, int size, const DisplaySettings& settings) {
    require(size >= 2 && size <= kMaxSide,
            "display size " + std::to_string(size) + " is not in [2, " + std::to_string(kMaxSide) + "]");
    check_settings(settings);
    impl_ = std::make_unique<Impl>(device, size, settings);
}

DisplayView::DisplayView(DisplayView&&) noexcept = default;
DisplayView& DisplayView::operator=(DisplayView&&) noexcept = default;
DisplayView::~DisplayView() = default;

int DisplayView::size() const { return impl_->size; }
const DisplaySettings& DisplayView::settings() const { return impl_->settings; }
void DisplayView::reset() { impl_->has_history = false; }

void DisplayView::enqueue(int n, const DeviceBuffer& low_planes, const DeviceBuffer& low_lightmap,
                          const DeviceBuffer& display_planes, const FrameDesc& desc, const glm::vec3& position,
                          const FrameOutputs& outputs, DisplayStats* stats, DisplayTimings* timings) {
    Impl& im = *impl_;
    const int s = im.size;
    require(n >= 2 && n <= s, "the pipeline's face size N = " + std::to_string(n) + " is not in [2, display size " +
                                  std::to_string(s) + "]");
    require(std::isfinite(position.x) && std::isfinite(position.y) && std::isfinite(position.z),
            "the camera position is not finite");
    const CameraArgs cam = CameraArgs::of(position, desc.look, desc.up);
    const std::size_t lo_plane = std::size_t(n) * n, hi_plane = std::size_t(s) * s;
    check_display_buffer(low_planes, im.device, frame_planes_bytes(n, 1), false, "low-resolution planes");
    check_display_buffer(low_lightmap, im.device, 3 * lo_plane * sizeof(float), false, "low-resolution lightmap");
    const int display_planes_used = desc.has_env ? kFramePlanes : desc.has_emission ? frame_plane(Feature::Env)
                                                                                      : frame_plane(Feature::Emission);
    check_display_buffer(display_planes, im.device, display_planes_used * hi_plane * sizeof(float), false, "display planes");
    const DeviceBuffer* outs[3] = {&outputs.lightmap, &outputs.final_image, &outputs.display};
    const char* names[3] = {"lightmap", "final image", "display"};
    for (int i = 0; i < 3; ++i)
        if (*outs[i]) check_display_buffer(*outs[i], im.device, 3 * hi_plane * sizeof(float), true, names[i]);
    if (outputs.display)
        require(std::isfinite(outputs.tonemap.exposure_ev) && std::abs(outputs.tonemap.exposure_ev) <= 64.0f,
                "tone map exposure " + std::to_string(outputs.tonemap.exposure_ev) + " EV is not in [-64, 64]");
    for (const DeviceBuffer* o : outs)
        if (*o && (o->opencl_mem() == low_planes.opencl_mem() || o->opencl_mem() == display_planes.opencl_mem() ||
                   o->opencl_mem() == low_lightmap.opencl_mem()))
            throw InputError(std::string(kOp) + ": an output buffer is also an input");

    detail::StageClock lap(im.ctx, timings);
    // Guides of both resolutions and the N x N indirect light.
    detail::ensure_buffer(im.ctx, im.low_normal, 3 * lo_plane * sizeof(float), "display view: low normal");
    detail::ensure_buffer(im.ctx, im.low_position, 3 * lo_plane * sizeof(float), "display view: low position");
    detail::ensure_buffer(im.ctx, im.low_light, 3 * lo_plane * sizeof(float), "display view: low indirect light");
    im.guides(low_planes.opencl_mem(), n, cam, im.low_normal.get(), im.low_position.get());
    im.guides(display_planes.opencl_mem(), s, cam, im.normal.get(), im.position.get());
    const int lo_count = int(3 * lo_plane);
    im.low_indirect.args(low_lightmap.opencl_mem(), low_planes.opencl_mem(), lo_count, im.low_light);
    const std::size_t gl[1] = {std::size_t(lo_count)};
    im.ctx.launch(im.low_indirect, 1, gl, detail::kLocal1);
    lap(&DisplayTimings::geometry_ms);

    // Upsampling.
    int fallbacks = 0;
    if (im.settings.upsampler == DisplayUpsampler::Jbu) {
        detail::JbuInputs in;
        in.low_width = in.low_height = n;
        in.channels = 3;
        in.low = im.low_light.get();
        in.low_normal = im.low_normal.get();
        in.low_position = im.low_position.get();
        in.width = in.height = s;
        in.normal = im.normal.get();
        in.position = im.position.get();
        detail::JbuParams p;
        p.sigma_spatial = im.settings.sigma_spatial;
        p.normal_power = im.settings.normal_power;
        p.sigma_plane = im.settings.sigma_plane;
        p.radius = im.settings.radius;
        im.jbu.enqueue(im.ctx, in, p, im.upsampled.get(), false);
    } else {
        im.resize.args(im.low_light, n, n, im.upsampled, s, s, 3);
        const std::size_t g[2] = {std::size_t(s), std::size_t(s)};
        im.ctx.launch(im.resize, 2, g, detail::kLocal2);
    }
    lap(&DisplayTimings::upsample_ms);

    // Temporal accumulation into the other history buffer; the display's depth becomes the next frame's.
    cl_mem indirect = im.upsampled.get();
    const bool used_history = im.settings.temporal && im.has_history;
    if (im.settings.temporal) {
        im.ctx.fill_zero(im.counters, 0, im.counters.bytes(), "display view: counters");
        const int next = 1 - im.latest;
        const CameraArgs& pc = im.prev_camera;
        if (used_history && im.settings.clip_margin >= 0.0f) {
            detail::ensure_buffer(im.ctx, im.low_box, 6 * lo_plane * sizeof(float), "display view: clamp ranges");
            im.clip_box.args(im.low_light, im.low_normal, n, im.settings.clip_margin, im.low_box);
            const std::size_t gb[2] = {std::size_t(n), std::size_t(n)};
            im.ctx.launch(im.clip_box, 2, gb, detail::kLocal2);
        }
        // Without a clamp the kernel never reads the box: any buffer stands in for it.
        const detail::Buffer& box = im.low_box ? im.low_box : im.low_light;
        im.temporal.args(im.upsampled, im.history[im.latest], im.prev_depth, im.normal, im.position, box,
                         n, s, pc.centre.x, pc.centre.y, pc.centre.z, pc.look.x, pc.look.y, pc.look.z, pc.right.x,
                         pc.right.y, pc.right.z, pc.up.x, pc.up.y, pc.up.z, int(used_history),
                         im.settings.blend, im.settings.depth_rel, im.settings.depth_abs, im.settings.clip_margin,
                         im.history[next], im.counters);
        const std::size_t g[2] = {(std::size_t(s) + kDisplayVec - 1) / kDisplayVec, std::size_t(s)};
        im.ctx.launch(im.temporal, 2, g, detail::kLocal2);
        im.ctx.copy(display_planes.opencl_mem(), std::size_t(frame_plane(Feature::Depth)) * hi_plane * sizeof(float),
                    im.prev_depth.get(), 0, hi_plane * sizeof(float), "display view: previous depth");
        im.latest = next;
        im.has_history = true;
        im.prev_camera = cam;
        indirect = im.history[next].get();
    }
    lap(&DisplayTimings::temporal_ms);

    // Outputs.
    const int hi_count = int(3 * hi_plane);
    if (outputs.lightmap || outputs.final_image || outputs.display) {
        // One pass writes every output asked for (the display tone-mapped from the final value in registers); an
        // output not asked for is never written, so any of the others stands in for its argument.
        cl_mem any = outputs.display ? outputs.display.opencl_mem()
                     : outputs.final_image ? outputs.final_image.opencl_mem() : outputs.lightmap.opencl_mem();
        auto or_any = [any](const DeviceBuffer& b) { return b ? b.opencl_mem() : any; };
        const ToneMapOptions& tm = outputs.tonemap;
        im.compose.args(display_planes.opencl_mem(), indirect, hi_count, int(desc.has_emission), int(desc.has_env),
                        int(bool(outputs.lightmap)), int(bool(outputs.final_image)), int(bool(outputs.display)),
                        std::exp2(tm.exposure_ev), int(tm.curve), int(tm.srgb), or_any(outputs.lightmap),
                        or_any(outputs.final_image), or_any(outputs.display));
        const std::size_t g[1] = {(std::size_t(hi_count) + kDisplayVec - 1) / kDisplayVec};
        im.ctx.launch(im.compose, 1, g, detail::kLocal1);
    }
    lap(&DisplayTimings::outputs_ms);

    if (stats) {
        *stats = DisplayStats{};
        stats->history_used = used_history;
        if (im.settings.upsampler == DisplayUpsampler::Jbu) fallbacks = im.jbu.fallback_count(im.ctx);
        stats->jbu_fallbacks = fallbacks;
        if (im.settings.temporal) {
            std::uint32_t c[2] = {0, 0};
            im.ctx.read(im.counters, 0, sizeof(c), c, "display view: counters");
            stats->disoccluded = int(c[0]);
            stats->clipped = int(c[1]);
        }
    }
}

FrameImages DisplayView::run(const Frame& low, const Image& low_lightmap, const Frame& display,
                             const glm::vec3& position, bool lightmap, bool final_image, bool display_image,
                             const ToneMapOptions& tonemap, DisplayStats* stats, DisplayTimings* timings) {
    Impl& im = *impl_;
    const int s = im.size, n = low.n;
    require(display.n == s, "the display frame is " + std::to_string(display.n) + "x" + std::to_string(display.n) +
                                ", this view " + std::to_string(s) + "x" + std::to_string(s));
    auto same = [](glm::vec3 a, glm::vec3 b) {
        return glm::length(a - b) <= 1e-5f * std::max(1.0f, std::max(glm::length(a), glm::length(b)));
    };
    auto text = [](glm::vec3 v) {
        return "(" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ")";
    };
    if (!same(low.look, display.look) || !same(low.up, display.up))
        throw InputError(std::string(kOp) + ": the display frame's camera (look " + text(display.look) + ", up " +
                         text(display.up) + ") is not the low-resolution frame's (look " + text(low.look) + ", up " +
                         text(low.up) + ")");
    if (low.position && !same(*low.position, position))
        throw InputError(std::string(kOp) + ": the camera position " + text(position) +
                         " is not the low-resolution frame's " + text(*low.position));
    require(low_lightmap.width == n && low_lightmap.height == n && low_lightmap.channels == 3,
            "the low-resolution lightmap is " + std::to_string(low_lightmap.width) + "x" +
                std::to_string(low_lightmap.height) + "x" + std::to_string(low_lightmap.channels) + ", the frame's " +
                std::to_string(n) + "x" + std::to_string(n) + "x3");
    // One upload: the low front face, its lightmap and the display face, side by side.
    const std::vector<float> lo = pack_frame_planes(low, 1), hi = pack_frame_planes(display, 1);
    const FrameDesc desc = FrameDesc::of(display, 1);
    const std::size_t lo_bytes = lo.size() * sizeof(float), lm_bytes = low_lightmap.data.size() * sizeof(float);
    const std::size_t hi_bytes = hi.size() * sizeof(float);
    std::vector<float> all;
    all.reserve(lo.size() + low_lightmap.data.size() + hi.size());
    all.insert(all.end(), lo.begin(), lo.end());
    all.insert(all.end(), low_lightmap.data.begin(), low_lightmap.data.end());
    all.insert(all.end(), hi.begin(), hi.end());
    detail::ensure_buffer(im.ctx, im.staging, all.size() * sizeof(float), "display view: staging");
    im.ctx.write(im.staging, 0, all.size() * sizeof(float), all.data(), "display view: frame upload");
    auto part = [&](detail::Buffer& b, std::size_t at, std::size_t bytes, const char* what) {
        detail::ensure_buffer(im.ctx, b, bytes, what);
        im.ctx.copy(im.staging.get(), at, b.get(), 0, bytes, what);
        return DeviceBuffer::wrap(im.device, b.get(), 0, bytes);
    };
    const DeviceBuffer lo_buf = part(im.low_planes_buf, 0, lo_bytes, "display view: low planes");
    const DeviceBuffer lm_buf = part(im.low_light_buf, lo_bytes, lm_bytes, "display view: low lightmap");
    const DeviceBuffer hi_buf = part(im.display_planes_buf, lo_bytes + lm_bytes, hi_bytes, "display view: planes");

    const std::size_t out_bytes = 3 * std::size_t(s) * s * sizeof(float);
    FrameOutputs outs;
    outs.tonemap = tonemap;
    const bool wanted[3] = {lightmap, final_image, display_image};
    DeviceBuffer* slots[3] = {&outs.lightmap, &outs.final_image, &outs.display};
    for (int i = 0; i < 3; ++i)
        if (wanted[i]) {
            if (!im.out_handles[i]) im.out_handles[i] = DeviceBuffer::allocate(im.device, out_bytes);
            *slots[i] = im.out_handles[i];
        }
    enqueue(n, lo_buf, lm_buf, hi_buf, desc, position, outs, stats, timings);

    // One download of the outputs asked for, copied side by side on the device first.
    const auto t0 = Clock::now();
    const int count = int(lightmap) + int(final_image) + int(display_image);
    FrameImages r;
    if (count == 0) return r;
    detail::ensure_buffer(im.ctx, im.result, std::size_t(count) * out_bytes, "display view: results");
    Image* targets[3] = {&r.lightmap, &r.final_image, &r.display};
    std::size_t at = 0;
    for (int i = 0; i < 3; ++i)
        if (wanted[i]) {
            im.ctx.copy(slots[i]->opencl_mem(), 0, im.result.get(), at, out_bytes, "display view: results");
            at += out_bytes;
        }
    std::vector<float> host(at / sizeof(float));
    im.ctx.read(im.result, 0, at, host.data(), "display view: results");
    at = 0;
    for (int i = 0; i < 3; ++i)
        if (wanted[i]) {
            *targets[i] = Image(s, s, 3);
            std::copy(host.begin() + std::ptrdiff_t(at), host.begin() + std::ptrdiff_t(at + out_bytes / sizeof(float)),
                      targets[i]->data.begin());
            at += out_bytes / sizeof(float);
        }
    if (timings) timings->outputs_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return r;
}

}  // namespace ngi

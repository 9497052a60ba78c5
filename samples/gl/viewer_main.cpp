// ngi_gl_viewer: an OpenGL 3.3 core-profile application lit by ngi. Each frame it rasterizes the six faces of the
// camera cluster into a G-buffer (gbuffer_pass.hpp), reads the attachments back into pixel buffer objects, hands
// them to ngi as image descriptors (ngi_handoff.hpp), runs the surround pipeline and shows the tone-mapped final
// image with per-stage timings. Interactive (WASD + mouse) or headless along the scene's camera path.
// samples/gl/README.md documents the options, the attachments and the measured agreement with the tracer.
#include <epoxy/gl.h>  // before GLFW: epoxy must come before GL/gl.h
#include <GLFW/glfw3.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <regex>
#include <sstream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <ngi/camera_path.hpp>
#include <ngi/display.hpp>
#include <ngi/error.hpp>
#include <ngi/host_memory.hpp>
#include <ngi/image_io.hpp>
#include <ngi/output_folder.hpp>

#include "gbuffer_pass.hpp"
#include "light_bake.hpp"
#include "ngi_handoff.hpp"
#include "overlay.hpp"
#include "presenter.hpp"
#include "shadow_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

struct Options {
    // The default rung: surround screen-space GI, which beats the networks with the inputs an engine has (issue 45).
    std::string scene = "room:seed=3", model = "ssgi_surround", device, out;
    int n = 64, frames = 30, warmup = 3, shadow = 2048, bake_texels = 0, bake_rays = 256, width = 768, height = 768;
    float time = -1.0f;  // hours; < 0: the scene's default
    unsigned seed = 0;
    bool headless = false, exr = false, display = false, gi = true;
    // The front camera is a square 90-degree view: a W x H window shows its centre W x H crop of a max(W, H) square
    // (a 16:9 window: 90 degrees across, 59 degrees high). The display view computes that whole square.
    int side() const { return std::max(width, height); }
};

// The centre of a square image cropped to the window's aspect (rows for a wide window, columns for a tall one).
ngi::Image crop_to_window(const ngi::Image& img, int window_w, int window_h) {
    const int w = window_w >= window_h ? img.width : std::max(1, int(std::lround(double(img.width) * window_w / window_h)));
    const int h = window_h >= window_w ? img.height : std::max(1, int(std::lround(double(img.height) * window_h / window_w)));
    if (w == img.width && h == img.height) return img;
    const int x0 = (img.width - w) / 2, y0 = (img.height - h) / 2;
    ngi::Image out(w, h, img.channels);
    for (int c = 0; c < img.channels; ++c)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) out.at(c, y, x) = img.at(c, y0 + y, x0 + x);
    return out;
}

struct FrameTiming {
    double raster = 0, readback = 0, gather = 0, input = 0, network = 0, outputs = 0, frame = 0;
    // --display: the front face rasterized again at the window's size and read back, and ngi's display view on it
    // (guides, upsample, temporal, outputs), host repacking of both front faces included in display_ngi.
    double display_raster = 0, display_readback = 0, display_ngi = 0;
    ngi::DisplayTimings display;
    double transfer() const { return readback + gather; }
    double ngi() const { return gather + input + network + outputs + display_ngi; }
};

// Error messages stay on one line (ngi's device error lists the devices on further lines).
std::string one_line(const char* what) {
    std::string s(what);
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    for (std::size_t p; (p = s.find('\n')) != std::string::npos;) s.replace(p, 1, "; ");
    return s;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// A software GL renderer (Mesa's llvmpipe or softpipe, SwiftShader) keeps textures and buffers in host memory: the
// G-buffers' storage is held in ngi's host-memory ledger before GL allocates it, so that with the pipeline's buffers
// on a CPU device it meets NGI_HOST_MEMORY_LIMIT (issue 51: --n 2048 peaked at 7.6 GB under a 4 GiB limit).
ngi::HostMemoryHold hold_gl_memory(const ngi_gl::GlContext& context, const Options& o) {
    const std::string renderer = context.renderer();
    if (renderer.find("llvmpipe") == std::string::npos && renderer.find("softpipe") == std::string::npos &&
        renderer.find("SwiftShader") == std::string::npos)
        return {};
    const std::uint64_t bytes = ngi_gl::GBufferPass::gl_bytes(o.n) + (o.display ? ngi_gl::GBufferPass::gl_bytes(o.side()) : 0);
    return ngi::HostMemoryHold("G-buffers of a software GL renderer (" + renderer + ") for --n " + std::to_string(o.n) +
                                   (o.display ? " and --display" : ""),
                               bytes);
}

// The scene's static light for one time of day: bake, upload, shadow map.
struct Lit {
    ngi::Lighting lighting;
    double bake_ms = 0;
};

class Viewer {
public:
    Viewer(const Options& o, ngi::Device& device, ngi::VoxelScene scene, ngi::Model& model)
        : o_(o), device_(device), scene_(std::move(scene)), model_(model),
          context_(o.width, o.height, !o.headless, "ngi_gl_viewer: " + scene_.name),
          pipeline_(device, o.n), faces_(ngi_gl::exposed_faces(scene_)), shadow_(o.shadow),
          gl_hold_(hold_gl_memory(context_, o)), gbuffer_(o.n) {
        if (o.display) {  // the front face at the window's size: the display's G-buffer and direct light
            display_gbuffer_.emplace(o.side());
            display_view_.emplace(device, o.side());
        }
        hours_ = o.time >= 0 ? o.time : scene_.default_time;
        transfer_ = ngi_gl::choose_transfer_path(device);
        rung_ = std::filesystem::path(o.model).stem().string();
        relight(true);
    }

    void relight(bool first) {
        lighting_ = ngi::lighting_at(hours_, scene_.sun_azimuth);
        ngi_gl::BakeSettings bs;
        bs.texels = o_.bake_texels;
        bs.sky_rays = o_.bake_rays;
        bake_ = ngi_gl::bake_static_light(scene_, faces_, lighting_, bs);
        if (first) {
            const ngi_gl::LightBake& b = bake_;
            gpu_ = std::make_unique<ngi_gl::GpuScene>(
                ngi_gl::build_mesh(scene_, faces_, [&b](std::size_t i) { return b.tile_origin(i); }), bake_);
        } else {
            gpu_->update_bake(bake_);
        }
        shadow_.render(*gpu_, lighting_.sun.direction, scene_.size);
        std::fprintf(stderr, "ngi_gl_viewer: %.1f h: baked %zu faces x %d^2 texels, %d sky rays each (%.0f ms, %.1f Mrays)\n",
                     hours_, faces_.size(), bake_.k, o_.bake_rays, bake_.ms, double(bake_.rays) * 1e-6);
    }

    // One frame: raster, read-back, ngi, present. Returns the stage timings.
    FrameTiming frame(const ngi::CameraPose& pose, ngi_gl::LitFrame* lit_out, bool capture, ngi::Image* window_png) {
        FrameTiming t;
        const auto t0 = Clock::now();
        gbuffer_.render(*gpu_, shadow_, pose, lighting_);
        glFinish();  // llvmpipe runs the draw calls here: the raster time is wall time up to this point
        t.raster = ms_since(t0);
        const auto t1 = Clock::now();
        gbuffer_.read_back();
        t.readback = ms_since(t1);
        ngi_gl::LitFrame lit = ngi_gl::light_frame(pipeline_, model_, gbuffer_, pose, display_view_.has_value(),
                                                   !display_view_.has_value());
        t.gather = lit.timings.gather_ms;
        t.input = lit.timings.input_ms;
        t.network = lit.timings.network_ms;
        t.outputs = lit.timings.outputs_ms;
        if (display_view_) {
            // The N x N lightmap at the window's resolution: the front face rasterized at that size gives the guides
            // and the direct light; the display view upsamples the indirect light and accumulates it over frames.
            const auto t2 = Clock::now();
            display_gbuffer_->render(*gpu_, shadow_, pose, lighting_);
            glFinish();
            t.display_raster = ms_since(t2);
            const auto t3 = Clock::now();
            display_gbuffer_->read_back();
            t.display_readback = ms_since(t3);
            const auto t4 = Clock::now();
            // --gi off: the pipeline's own front direct light as the lightmap -- no indirect light, the same path.
            const ngi::Frame low = gbuffer_.to_frame(pose, 1);
            const ngi::Image& lightmap = o_.gi ? lit.lightmap : low.get(ngi::Feature::Direct, ngi::Face::Front);
            const ngi::FrameImages shown = display_view_->run(low, lightmap, display_gbuffer_->to_frame(pose, 1),
                                                              pose.position, false, false, true, {}, nullptr, &t.display);
            display_gbuffer_->unmap();
            t.display_ngi = ms_since(t4);
            lit.display = shown.display;
        }
        lit.display = crop_to_window(lit.display, o_.width, o_.height);
        int w = 0, h = 0;
        glfwGetFramebufferSize(context_.window(), &w, &h);
        presenter_.draw(lit.display, w, h);
        overlay_.draw(overlay_text(), 8, 8, std::clamp(float(w) / 384.0f, 1.0f, 2.0f), w, h);  // ~46 characters fit
        if (capture && window_png) *window_png = read_window(w, h);
        glfwSwapBuffers(context_.window());
        t.frame = ms_since(t0);
        if (lit_out) *lit_out = std::move(lit);
        last_ = t;
        fps_ = 1000.0 / std::max(t.frame, 1e-3);
        return t;
    }

    std::string overlay_text() const {
        char b[512];
        if (display_view_) {
            const ngi::DisplayTimings& d = last_.display;
            std::snprintf(b, sizeof b,
                          "%s  N=%d -> %dx%d of %d^2  %.1f fps\nraster %.1f + %.1f ms, readback %.1f + %.1f ms\n"
                          "ngi %.1f: merge %.1f %s %.1f\ndisplay %.1f: guides %.1f up %.1f temporal %.1f out %.1f\n"
                          "%.1f h  no area light",
                          o_.gi ? rung_.c_str() : "GI off (direct light only)", o_.n, o_.width, o_.height, o_.side(),
                          fps_, last_.raster, last_.display_raster, last_.readback,
                          last_.display_readback, last_.gather + last_.input + last_.network + last_.outputs,
                          last_.input, model_.config().has_network ? "network" : "ssgi", last_.network,
                          last_.display_ngi, d.geometry_ms, d.upsample_ms, d.temporal_ms, d.outputs_ms, hours_);
            return b;
        }
        std::snprintf(b, sizeof b,
                      "%s  N=%d  %.1f fps\nraster %.1f ms\ntransfer %.1f ms (readback %.1f + gather %.1f)\n"
                      "merge %.1f  %s %.1f  compose %.1f ms\n%s  %.1f h  no area light",
                      rung_.c_str(), o_.n, fps_, last_.raster, last_.transfer(), last_.readback, last_.gather,
                      last_.input, model_.config().has_network ? "network" : "ssgi", last_.network,
                      last_.outputs, transfer_.used.c_str(), hours_);
        return b;
    }

    ngi::Image read_window(int w, int h) {
        std::vector<unsigned char> px(std::size_t(w) * h * 3);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadBuffer(GL_BACK);
        glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, px.data());
        ngi::Image img(w, h, 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) img.at(c, h - 1 - y, x) = px[(std::size_t(y) * w + x) * 3 + c] / 255.0f;
        return img;
    }

    int run_interactive() {
        GLFWwindow* win = context_.window();
        ngi::CameraPath path = ngi::make_camera_path(scene_, ngi::CameraPathKind::Auto, 2, o_.seed);
        ngi::CameraPose pose = path.at(0);
        float yaw = std::atan2(pose.look.x, -pose.look.z), pitch = std::asin(std::clamp(pose.look.y, -1.0f, 1.0f));
        double mx = 0, my = 0;
        glfwGetCursorPos(win, &mx, &my);
        auto last = Clock::now();
        while (!glfwWindowShouldClose(win)) {
            glfwPollEvents();
            const float dt = float(ms_since(last) * 1e-3);
            last = Clock::now();
            if (glfwGetKey(win, GLFW_KEY_ESCAPE) == GLFW_PRESS) break;
            double cx, cy;
            glfwGetCursorPos(win, &cx, &cy);
            if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {  // drag to look
                yaw += float(cx - mx) * 0.005f;
                pitch = std::clamp(pitch - float(cy - my) * 0.005f, -1.5f, 1.5f);
            }
            mx = cx;
            my = cy;
            pose.look = glm::vec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch));
            pose.up = glm::vec3(0, 1, 0);
            const glm::vec3 fwd = glm::normalize(glm::vec3(pose.look.x, 0, pose.look.z));
            const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0)));
            const float speed = 3.0f * dt * (glfwGetKey(win, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ? 3.0f : 1.0f);
            if (glfwGetKey(win, GLFW_KEY_W) == GLFW_PRESS) pose.position += fwd * speed;
            if (glfwGetKey(win, GLFW_KEY_S) == GLFW_PRESS) pose.position -= fwd * speed;
            if (glfwGetKey(win, GLFW_KEY_D) == GLFW_PRESS) pose.position += right * speed;
            if (glfwGetKey(win, GLFW_KEY_A) == GLFW_PRESS) pose.position -= right * speed;
            if (glfwGetKey(win, GLFW_KEY_E) == GLFW_PRESS) pose.position.y += speed;
            if (glfwGetKey(win, GLFW_KEY_Q) == GLFW_PRESS) pose.position.y -= speed;
            const bool later = glfwGetKey(win, GLFW_KEY_T) == GLFW_PRESS, earlier = glfwGetKey(win, GLFW_KEY_G) == GLFW_PRESS;
            if (later || earlier) {  // time of day in half-hour steps: re-bake and re-render the shadow map
                hours_ = std::fmod(hours_ + (later ? 0.5f : -0.5f) + 24.0f, 24.0f);
                relight(false);
            }
            frame(pose, nullptr, false, nullptr);
        }
        return 0;
    }

    // Writes into `out` (staged: nothing is in --out until commit(), and a failed write leaves --out as it was).
    int run_headless(ngi::OutputFolder& out) {
        const int total = o_.warmup + o_.frames;
        ngi::CameraPath path = ngi::make_camera_path(scene_, ngi::CameraPathKind::Auto, std::max(o_.frames, 2), o_.seed);
        std::vector<FrameTiming> times;
        nlohmann::json frames = nlohmann::json::array();
        for (int i = 0; i < total; ++i) {
            const int k = std::max(0, i - o_.warmup);  // warm-up frames repeat the first pose
            const ngi::CameraPose pose = path.at(float(k));
            ngi_gl::LitFrame lit;
            ngi::Image window;
            const bool capture = i == o_.warmup;
            const FrameTiming t = frame(pose, &lit, capture, &window);
            if (i < o_.warmup) continue;
            times.push_back(t);
            char name[64];
            std::snprintf(name, sizeof name, "frame_%04d", k);
            out.write(std::string(name) + ".png", [&](const std::string& f) { ngi::write_png(f, lit.display); });
            if (capture) out.write("capture.png", [&](const std::string& f) { ngi::write_png(f, window); });
            if (o_.exr)
                out.write(std::string(name) + "_raster",
                          [&](const std::string& f) { ngi::write_frame(f, gbuffer_.to_frame(pose)); });
            frames.push_back({{"frame", k}, {"raster_ms", t.raster}, {"readback_ms", t.readback}, {"gather_ms", t.gather},
                              {"transfer_ms", t.transfer()}, {"input_ms", t.input}, {"network_ms", t.network},
                              {"outputs_ms", t.outputs}, {"ngi_ms", t.ngi()}, {"frame_ms", t.frame}});
            if (display_view_)
                frames.back()["display"] = {{"raster_ms", t.display_raster}, {"readback_ms", t.display_readback},
                                            {"ngi_ms", t.display_ngi}, {"guides_ms", t.display.geometry_ms},
                                            {"upsample_ms", t.display.upsample_ms},
                                            {"temporal_ms", t.display.temporal_ms},
                                            {"outputs_ms", t.display.outputs_ms}};
            gbuffer_.unmap();
        }
        auto med = [&](auto f) {
            std::vector<double> v;
            for (const FrameTiming& t : times) v.push_back(f(t));
            return median(v);
        };
        nlohmann::json j;
        j["scene"] = scene_.name;
        j["n"] = o_.n;
        j["display"] = o_.display ? o_.side() : 0;  // the display view's square side (the window shows its crop)
        j["window"] = {o_.width, o_.height};
        j["gi"] = o_.gi;
        j["rung"] = rung_;
        j["model"] = o_.model;
        j["device"] = device_.info().platform_name + " / " + device_.info().name;
        j["gl_renderer"] = context_.renderer();
        j["transfer_path"] = transfer_.used;
        j["cl_khr_gl_sharing_offered"] = transfer_.gl_sharing_offered;
        j["warmup_frames"] = o_.warmup;
        j["bake"] = {{"faces", faces_.size()}, {"texels_per_edge", bake_.k}, {"sky_rays", o_.bake_rays}, {"ms", bake_.ms}};
        j["shadow_map"] = o_.shadow;
        j["frames"] = frames;
        const double frame_med = med([](const FrameTiming& t) { return t.frame; });
        j["median"] = {{"raster_ms", med([](const FrameTiming& t) { return t.raster; })},
                       {"readback_ms", med([](const FrameTiming& t) { return t.readback; })},
                       {"gather_ms", med([](const FrameTiming& t) { return t.gather; })},
                       {"transfer_ms", med([](const FrameTiming& t) { return t.transfer(); })},
                       {"input_ms", med([](const FrameTiming& t) { return t.input; })},
                       {"network_ms", med([](const FrameTiming& t) { return t.network; })},
                       {"outputs_ms", med([](const FrameTiming& t) { return t.outputs; })},
                       {"ngi_ms", med([](const FrameTiming& t) { return t.ngi(); })},
                       {"display_raster_ms", med([](const FrameTiming& t) { return t.display_raster; })},
                       {"display_readback_ms", med([](const FrameTiming& t) { return t.display_readback; })},
                       {"display_ngi_ms", med([](const FrameTiming& t) { return t.display_ngi; })},
                       {"display_upsample_temporal_ms", med([](const FrameTiming& t) {
                            return t.display.geometry_ms + t.display.upsample_ms + t.display.temporal_ms;
                        })},
                       {"frame_ms", frame_med},
                       {"fps", frame_med > 0 ? 1000.0 / frame_med : 0.0}};
        j["not_modelled"] = "area light (lighting_at has none); cl_khr_gl_sharing interop path";
        out.write_text("timings.json", j.dump(2) + "\n");
        out.commit();
        std::printf("%s\n", j["median"].dump().c_str());
        return 0;
    }

private:
    Options o_;
    ngi::Device& device_;
    ngi::VoxelScene scene_;
    ngi::Model& model_;
    ngi_gl::GlContext context_;
    ngi::SurroundPipeline pipeline_;
    std::vector<ngi_gl::ExposedFace> faces_;
    ngi_gl::ShadowMap shadow_;
    ngi::HostMemoryHold gl_hold_;  // the G-buffers' GL storage, when GL is a software renderer (host memory)
    ngi_gl::GBufferPass gbuffer_;
    std::optional<ngi_gl::GBufferPass> display_gbuffer_;  // --display: the front face at the window's size
    std::optional<ngi::DisplayView> display_view_;
    ngi_gl::Presenter presenter_;
    ngi_gl::Overlay overlay_;
    std::unique_ptr<ngi_gl::GpuScene> gpu_;
    ngi_gl::LightBake bake_;
    ngi::Lighting lighting_;
    ngi_gl::TransferPath transfer_;
    std::string rung_;
    float hours_ = 13.0f;
    FrameTiming last_;
    double fps_ = 0;
};

// What a headless run writes: a re-run may replace an --out holding only these; anything else there is someone
// else's, and the viewer refuses to touch it (issue 51: it wrote into a folder of foreign files).
std::string viewer_may_replace(const std::string& dir) {
    static const std::regex own(R"((frame_[0-9]{4,}(\.png|_raster))|capture\.png|timings\.json)");
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
        if (!std::regex_match(e.path().filename().string(), own))
            return "it holds '" + e.path().filename().string() + "', which ngi_gl_viewer does not write";
    return ec ? "cannot list it: " + ec.message() : std::string();
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"ngi_gl_viewer: rasterize the camera cluster's six faces with OpenGL 3.3 and light them with ngi"};
    app.add_option("--scene", o.scene, "room|street|cave|backlit|bleed|sculpture|cornell[:seed=S] or a .vox path")->capture_default_str();
    app.add_option("--model", o.model, "a surround rung: a shipped model's name (ngi::resolve_model) or a .safetensors file")
        ->capture_default_str();
    app.add_option("--n", o.n, "face size N (the model's)")->check(CLI::Range(2, 2048))->capture_default_str();
    app.add_option("--device", o.device, "OpenCL device: cpu, gpu, P:D, pocl, rusticl (default $NGI_DEVICE)");
    // A plain decimal: CLI11 alone read "nan" as NaN (Range passes it) and "0x10" as 16 h (issue 51).
    app.add_option("--time", o.time, "time of day in hours (default: the scene's)")
        ->check(CLI::Validator(
            [](std::string& v) {
                float h = 0;
                const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), h, std::chars_format::fixed);
                return !v.empty() && ec == std::errc() && end == v.data() + v.size() && std::isfinite(h) && h >= 0.0f &&
                               h <= 24.0f
                           ? std::string()
                           : "must be a decimal number of hours in [0, 24], got '" + v + "'";
            },
            "HOURS"));
    app.add_flag("--headless", o.headless, "hidden window: move along the scene's camera path, write PNGs + timings.json");
    app.add_option("--frames", o.frames, "headless: frames to write")->check(CLI::Range(1, 100000))->capture_default_str();
    app.add_option("--warmup", o.warmup, "headless: untimed frames first")->check(CLI::Range(0, 1000))->capture_default_str();
    app.add_option("--out", o.out, "headless: output folder");
    app.add_flag("--exr", o.exr, "headless: also write each frame's raster features as a frame folder of EXRs");
    app.add_option("--shadow-map", o.shadow, "shadow map resolution")->check(CLI::Range(64, 8192))->capture_default_str();
    app.add_option("--bake-texels", o.bake_texels, "baked texels per face edge (0 = automatic)")->check(CLI::Range(0, 16))->capture_default_str();
    app.add_option("--bake-rays", o.bake_rays, "sky rays per baked texel")->check(CLI::Range(1, 65536))->capture_default_str();
    app.add_option("--seed", o.seed, "camera path seed")->capture_default_str();
    std::string window = "768";
    app.add_option("--window", window, "window size in pixels: W (square) or WxH, each in [64, 4096]; a non-square window "
                                       "shows the centre crop of the square front view")
        ->check(CLI::Validator(
            [](std::string& v) {
                static const std::regex size(R"(([0-9]{2,4})(x([0-9]{2,4}))?)");
                std::smatch m;
                if (!std::regex_match(v, m, size)) return "must be W or WxH, got '" + v + "'";
                for (int g : {1, 3})
                    if (m[g].matched && (std::stoi(m[g]) < 64 || std::stoi(m[g]) > 4096))
                        return "each side must be in [64, 4096], got '" + v + "'";
                return std::string();
            },
            "W[xH]"))
        ->capture_default_str();
    std::string gi = "on";
    app.add_option("--gi", gi, "on: ngi's GI; off: direct light only through the same display path (needs --display; "
                               "for before/after comparisons)")
        ->check(CLI::IsMember({"on", "off"}))->capture_default_str();
    app.add_flag("--display", o.display,
                 "show the GI at the window's resolution: the front face rasterized at that size, the N x N lightmap's "
                 "indirect light upsampled by its normals and depth and accumulated over frames (ngi::DisplayView)");
    try {
        app.parse(argc, argv);
        if (o.headless && o.out.empty()) throw CLI::RequiredError("--out (with --headless)");
        if (gi == "off" && !o.display) throw CLI::ValidationError("--gi", "off needs --display");
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    {
        const auto x = window.find('x');
        o.width = std::stoi(window.substr(0, x));
        o.height = x == std::string::npos ? o.width : std::stoi(window.substr(x + 1));
    }
    o.gi = gi == "on";
    // Which stage failed decides the message and the exit code: 1 bad input, 3 device / GL failure.
    std::optional<ngi::OutputFolder> out;  // checked before any work; nothing on disk until the first frame's write
    if (o.headless) {
        try {
            out.emplace(o.out, "ngi_gl_viewer: write", viewer_may_replace);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s\n", one_line(e.what()).c_str());
            return 1;
        }
    }
    ngi::VoxelScene scene;
    try {
        scene = ngi::make_scene(o.scene);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi_gl_viewer: scene %s does not load: %s\n", o.scene.c_str(), one_line(e.what()).c_str());
        return 1;
    }
    std::optional<ngi::Device> device;
    try {
        device = ngi::Device::open(o.device);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi_gl_viewer: no OpenCL device: %s\n", one_line(e.what()).c_str());
        return 3;
    }
    std::optional<ngi::Model> model;
    try {
        model = ngi::Model::load(*device, ngi::resolve_model(o.model));
        const ngi::ModelConfig& c = model->config();
        if (c.input_nc != 12 && c.has_network)  // the viewer renders all six faces: any SSGI rung (no network) runs
            throw ngi::InputError("model " + o.model + " has input_nc " + std::to_string(c.input_nc) +
                                  ": the viewer runs surround models (12 input channels) and ssgi rungs");
    } catch (const ngi::ClError& e) {
        std::fprintf(stderr, "ngi_gl_viewer: device failure loading the model: %s\n", one_line(e.what()).c_str());
        return 3;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi_gl_viewer: model does not load: %s\n", one_line(e.what()).c_str());
        return 1;
    }
    try {
        Viewer viewer(o, *device, std::move(scene), *model);
        const ngi_gl::TransferPath t = ngi_gl::choose_transfer_path(*device);
        std::fprintf(stderr, "ngi_gl_viewer: OpenCL %s; transfer path %s (%s)\n", device->info().name.c_str(),
                     t.used.c_str(), t.note.c_str());
        return o.headless ? viewer.run_headless(*out) : viewer.run_interactive();
    } catch (const ngi_gl::GlError& e) {
        std::fprintf(stderr, "ngi_gl_viewer: %s\n", one_line(e.what()).c_str());
        return 3;
    } catch (const ngi::InputError& e) {
        std::fprintf(stderr, "ngi_gl_viewer: %s\n", one_line(e.what()).c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi_gl_viewer: %s\n", one_line(e.what()).c_str());
        return 3;
    }
}

// ngi lightmap: a frame folder + a trained generator -> the front view's GI lightmap and final image, and, when
// the frame has a path-traced reference, a side-by-side comparison and metrics.
#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "frame_report.hpp"
#include "ngi/display.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/pipeline.hpp"
#include "phase_timer.hpp"
#include "plan_file.hpp"
#include "side_by_side.hpp"

namespace ngi_cli {

namespace {

// The library's JSON form (non-finite values as null with a note, docs/CONVENTIONS.md section 11).
nlohmann::json metrics_json(const ngi::ImageMetrics& m) { return nlohmann::json::parse(ngi::to_json(m)); }

// "WxH" with W and H in 1..16384, or false.
bool parse_size(const std::string& s, int& width, int& height) {
    const auto x = s.find('x');
    return x != std::string::npos && parse_integer(s.substr(0, x), 1, 16384, width) &&
           parse_integer(s.substr(x + 1), 1, 16384, height);
}

// --guard T: the whole string a finite decimal number with 0 < T <= 1 (0 would send every lit frame to direct
// light; above 1 the guard could never act), or false.
bool parse_guard(const std::string& s, double& t) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), t);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size() && std::isfinite(t) && t > 0.0 && t <= 1.0;
}

// A share for the guard's line: three decimals, or three significant digits below 0.001 (a tiny threshold would
// otherwise print as 0.000).
std::string share_text(double v) {
    char b[32];
    std::snprintf(b, sizeof b, v == 0.0 || v >= 0.001 ? "%.3f" : "%.3g", v);
    return b;
}

// final = clamp(albedo, 0, 1) x light + emission + env of a frame's front face, on the host at the frame's size
// (compose_final's rule, kernels/compose.cl: albedo NaN -> 0, light terms NaN / negative -> 0, sums saturating).
// For the display frame, whose size is not the pipeline's.
ngi::Image compose_front(const ngi::Image& light, const ngi::Frame& frame) {
    auto clean = [](float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX); };
    const ngi::Image& albedo = frame.get(ngi::Feature::Albedo, ngi::Face::Front);
    const ngi::Image& emission = frame.get(ngi::Feature::Emission, ngi::Face::Front);
    const ngi::Image& env = frame.get(ngi::Feature::Env, ngi::Face::Front);
    ngi::Image out(light.width, light.height, 3);
    for (std::size_t i = 0; i < out.data.size(); ++i) {
        const float a = std::isnan(albedo.data[i]) ? 0.0f : std::clamp(albedo.data[i], 0.0f, 1.0f);
        float v = a * clean(light.data[i]);
        if (!emission.data.empty()) v = std::min(v + clean(emission.data[i]), FLT_MAX);
        if (!env.data.empty()) v = std::min(v + clean(env.data[i]), FLT_MAX);
        out.data[i] = v;
    }
    return out;
}

struct Options {
    std::string frame_dir, model_path, plan_path, bn_mode, out_dir, size, device, display_dir, upsampler = "jbu";
    double guard = 0.0;  // 0: no --guard (the plan's guard, if any, applies)
    bool timings = false;
};

int run(const Options& o) {
    PhaseTimer timer(o.timings);
    const std::string &frame_dir = o.frame_dir, &model_path = o.model_path, &out_dir = o.out_dir;
    int width = 0, height = 0;  // 0: the frame's face size
    if (!o.size.empty()) parse_size(o.size, width, height);  // checked by the option
    // Checked before the model runs: an output folder this command may not replace is refused up front.
    ngi::OutputFolder out(out_dir, "write", {"lightmap.exr", "final.png", "compare.png", "metrics.json"});
    // A plan (python3 -m ngi.plan) names the rung, its batch-norm mode and face size, and maybe a per-frame switch.
    std::optional<Plan> plan;
    if (!o.plan_path.empty()) plan = Plan::load(o.plan_path);
    ngi::FrameReadStats read_stats;
    const ngi::Frame frame = ngi::read_frame(frame_dir, &read_stats);  // the reference, if any, has the face size
    warn_frame_sanitized("lightmap", frame_dir, read_stats);
    warn_noisy_direct_light("lightmap", frame_dir);
    // --display: the same camera's front view at the display's resolution (ngi render --face S), whose G-buffer and
    // direct light the lightmap is brought to (ngi::DisplayView, docs/CONVENTIONS.md section 20).
    std::optional<ngi::Frame> display;
    if (!o.display_dir.empty()) {
        ngi::FrameReadStats display_stats;
        display = ngi::read_frame(o.display_dir, &display_stats);
        warn_frame_sanitized("lightmap", o.display_dir, display_stats);
        if (display->n < frame.n)
            throw ngi::InputError("--display " + o.display_dir + ": its face size " + std::to_string(display->n) +
                                  " is smaller than the frame's " + std::to_string(frame.n));
        read_stats.sanitized.insert(read_stats.sanitized.end(), display_stats.sanitized.begin(),
                                    display_stats.sanitized.end());
    }
    timer.mark("read_frame");
    double share = -1.0;
    const PlanRung* chosen = plan ? &plan->choose(frame, share) : nullptr;
    ngi::ModelOptions model_options;
    model_options.bn_mode = chosen ? chosen->bn_mode : o.bn_mode;
    ngi::Device device = ngi::Device::open(o.device);
    timer.mark("open_device");
    if (width) {  // checked before the model runs: a presented image is width x height x 3 floats on the device
        const std::size_t image_bytes = std::size_t(width) * std::size_t(height) * 3 * sizeof(float);
        if (image_bytes > device.info().max_alloc_bytes)
            throw ngi::InputError("--size " + o.size + ": an image of that size is " + std::to_string(image_bytes) +
                                  " bytes, beyond the device's largest allocation (" +
                                  std::to_string(device.info().max_alloc_bytes) + " bytes)");
        // And on the host: with a reference, final.png, the three tone-mapped finals of compare.png, compare.png
        // itself (three wide) and the image being upscaled are held at once (8 images); without, 3.
        ngi::check_host_memory("ngi lightmap --size " + o.size, image_bytes * (frame.reference ? 8 : 3));
    }
    // A plan may choose the direct-light rung: no network, the frame's own direct light is the lightmap.
    std::optional<ngi::Model> model;
    if (!chosen || !chosen->model.empty())
        model = ngi::Model::load(device, chosen ? chosen->model : ngi::resolve_model(model_path), model_options);
    if (!width) width = height = frame.n;
    timer.mark("load_model");

    ngi::SurroundPipeline pipeline(device, frame.n);
    ngi::PreprocessStats stats;
    ngi::FrameImages images;
    std::string input_text = "none (direct light only)";
    if (model) {
        // One frame in one call: one upload of the face planes, one download of the lightmap and the final image.
        images = pipeline.run(*model, frame, true, true, false, {}, &stats);
        if (const int replaced = model->sanitized_inputs())  // the pipeline's input is always within range: a bug
            std::fprintf(stderr,
                         "ngi lightmap: warning: the model's input guard replaced %d values of the network input\n",
                         replaced);
        const ngi::ModelConfig& c = model->config();
        const bool surround = c.input_nc == 12;
        if (!c.has_network)  // an SSGI rung: the gather of the faces' light, added to the direct light
            input_text = "none (ssgi, " + c.ssgi.view + " faces, " + std::to_string(c.ssgi.bounces) + " bounce" +
                         (c.ssgi.bounces > 1 ? "s" : "") + ")";
        else
            input_text = ngi::shape_string({1, c.input_nc, surround ? 2 * frame.n : frame.n,
                                            surround ? 4 * frame.n : frame.n}) +
                         ", output " + c.output_mode;  // "indirect": + the frame's direct light
    } else {
        images.lightmap = frame.get(ngi::Feature::Direct, ngi::Face::Front);
        images.final_image = pipeline.compose(images.lightmap, frame);
    }
    timer.mark("pipeline");

    // The per-frame guard (issue 25): when the lightmap's indirect share of the final image exceeds the threshold,
    // the network is unlikely to help this frame and the frame falls back to its own direct light, sanitized as
    // decode_indirect and compose sanitize it. Measured on the network's front lightmap at the frame's face size,
    // before anything is presented or scored, so every output below (lightmap.exr, final.png, compare.png and the
    // "network" metrics) is the fallback's. An explicit --guard overrides the plan's.
    const double guard = o.guard > 0.0 ? o.guard : plan && plan->guard ? plan->guard->max_indirect_share : 0.0;
    double guard_share = 0.0;
    bool fell_back = false;
    if (guard > 0.0) {
        guard_share = ngi::indirect_share(frame, images.lightmap);
        fell_back = guard_share > guard;
        if (fell_back) {
            images.lightmap = frame.get(ngi::Feature::Direct, ngi::Face::Front);
            for (float& v : images.lightmap.data) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX);
            images.final_image = pipeline.compose(images.lightmap, frame);
        }
    }
    // At display resolution: the indirect part of the lightmap (lightmap - direct) upsampled joint-bilaterally (or
    // bilinearly) by the display frame's normals and positions and composed with its own direct light. One frame, no
    // history: both resolutions' positions are taken from the same (arbitrary) camera centre.
    const ngi::Frame& shown = display ? *display : frame;
    if (display) {
        ngi::DisplaySettings ds;
        ds.temporal = false;
        ds.upsampler = ngi::display_upsampler_from_name(o.upsampler);
        ngi::DisplayView view(device, display->n, ds);
        images = view.run(frame, images.lightmap, *display, glm::vec3(0.0f), true, true, false);
        width = height = display->n;
        timer.mark("display");
    }
    auto compose = [&](const ngi::Image& light) {
        return display ? compose_front(light, *display) : pipeline.compose(light, frame);
    };
    const ngi::Image& lightmap = images.lightmap;
    const ngi::Image& final_image = images.final_image;
    auto present = [&](const ngi::Image& im) {
        return width == im.width && height == im.height ? im : pipeline.upscale(im, width, height);
    };

    // Everything is computed before anything is written.
    std::vector<std::pair<std::string, ngi::Image>> pngs = {{"final.png", pipeline.tonemap(present(final_image))}};
    nlohmann::json metrics;
    if (shown.reference) {
        // Direct-only baseline: the direct light alone as the lightmap (what a renderer has without GI).
        const ngi::Image& direct = shown.get(ngi::Feature::Direct, ngi::Face::Front);
        const ngi::Image direct_final = compose(direct), reference_final = compose(*shown.reference);
        const ngi::Image d = pipeline.tonemap(direct_final), n = pipeline.tonemap(final_image),
                         r = pipeline.tonemap(reference_final);
        const ngi::Image dp = pipeline.tonemap(present(direct_final)), np = pipeline.tonemap(present(final_image)),
                         rp = pipeline.tonemap(present(reference_final));
        pngs.emplace_back("compare.png", hconcat({&dp, &np, &rp}));  // at the presentation size
        // Metrics at the frame's own resolution, on the tone-mapped final images (display-referred [0, 1],
        // data_range 1), like the thesis's
        // evaluation of 8-bit renders, and on the linear lightmaps (data_range = the reference's maximum).
        double peak = 0;
        for (float v : shown.reference->data) peak = std::max(peak, double(v));
        metrics = {
            {"convention", "final_ldr: tone-mapped final images, data_range 1; lightmap_linear: HDR lightmaps, "
                           "data_range = max of the reference lightmap"},
            {"network", {{"final_ldr", metrics_json(ngi::compare_images(device, n, r, 1.0))},
                         {"lightmap_linear", metrics_json(ngi::compare_images(device, lightmap, *shown.reference,
                                                                             peak))}}},
            {"direct_only", {{"final_ldr", metrics_json(ngi::compare_images(device, d, r, 1.0))},
                             {"lightmap_linear",
                              metrics_json(ngi::compare_images(device, direct, *shown.reference, peak))}}},
        };
        if (display)
            metrics["display"] = {{"frame", o.display_dir}, {"size", display->n}, {"upsampler", o.upsampler}};
    }
    nlohmann::json plan_json;
    if (plan) {
        plan_json = {{"plan", plan->path}, {"rung", chosen->name},
                     {"model", chosen->model.empty() ? nlohmann::json() : nlohmann::json(chosen->model)},
                     {"switched", chosen != &plan->rung}};
        if (share >= 0.0) plan_json["outside_light_share"] = share;
        if (!metrics.is_null()) metrics["plan"] = plan_json;
    }
    // What the network's output was (docs/MODEL_FORMAT.md): the whole lightmap, or indirect light that the
    // pipeline added to the frame's direct light. None without a model (direct light only).
    if (!metrics.is_null()) metrics["output_mode"] = model ? nlohmann::json(model->config().output_mode) : nlohmann::json();
    if (guard > 0.0 && !metrics.is_null())
        metrics["guard"] = {{"max_indirect_share", guard}, {"indirect_share", guard_share}, {"fell_back", fell_back}};
    mark_scores(metrics, read_stats);  // null scores with a note when the frame's files held NaN/Inf
    timer.mark("present_and_score");

    // All files or none: they are staged and the folder is renamed into place only when every write succeeded.
    const ngi::Image lightmap_out = present(lightmap);
    out.write("lightmap.exr", [&](const std::string& p) { ngi::write_exr(p, lightmap_out, ngi::ExrPixelType::Float); });
    for (const auto& named : pngs)
        out.write(named.first, [&](const std::string& p) { ngi::write_png(p, named.second); });
    if (!metrics.is_null()) out.write_text("metrics.json", metrics.dump(2) + "\n");
    out.commit();
    timer.mark("write");
    if (!metrics.is_null()) std::printf("%s\n", metrics.dump(2).c_str());
    if (plan)
        std::printf("plan       %s: rung %s%s\n", plan->path.c_str(), chosen->name.c_str(),
                    share < 0.0 ? ""
                                : (", outside light share " + std::to_string(share) +
                                   (chosen != &plan->rung ? " < " : " >= ") +
                                   std::to_string(plan->fallback->below))
                                      .c_str());
    if (guard > 0.0)
        std::printf("guard      indirect share %s %s %s: %s\n", share_text(guard_share).c_str(), fell_back ? ">" : "<=",
                    share_text(guard).c_str(), fell_back ? "direct light used" : "network kept");
    std::printf("lightmap   %s/lightmap.exr (%dx%d), final.png%s; input %s; NaN/Inf replaced: %zu in the frame's "
                "files, %d in the network input\n",
                out_dir.c_str(), width, height,
                shown.reference ? ", compare.png (direct only | network | reference), metrics.json" : "",
                input_text.c_str(), read_stats.total_sanitized(), stats.total_nonfinite());
    timer.print();
    return 0;
}

}  // namespace

Run add_lightmap(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(app, "lightmap", "a frame folder + a trained generator -> the front view's GI lightmap",
                                "Writes lightmap.exr and final.png and, when the frame has a reference, compare.png "
                                "(direct only | network | reference) and metrics.json. With a guard (--guard, or the "
                                "plan's), a frame whose lightmap adds more than the threshold's share of the final "
                                "image beyond direct light falls back to direct light alone (docs/CONVENTIONS.md "
                                "section 17).");
    add_path(*cmd, "--frame", o->frame_dir, "DIR", "the frame folder (ngi render)", true);
    CLI::Option* model = add_path(*cmd, "--model", o->model_path, "M",
                                  "the trained generator: a .safetensors file or a shipped model's name (surround)",
                                  false);
    CLI::Option* plan = add_path(*cmd, "--plan", o->plan_path, "PLAN.json",
                                 "run the rung a plan chose (python3 -m ngi.plan), with its per-frame switch if it "
                                 "has one; instead of --model",
                                 false);
    plan->excludes(model);
    CLI::Option* bn = add_choice(*cmd, "--bn-mode", o->bn_mode, {"running", "per_image"},
                                 "override the model file's batch-norm mode", "the file's");
    bn->excludes(plan);
    add_path(*cmd, "--out", o->out_dir, "DIR", "the folder to write", true);
    cmd->add_option("--size", o->size, "the size of the written images, W and H in 1..16384 [default: the face size]")
        ->type_name("WxH")
        ->check(CLI::Validator(
            [](std::string& s) {
                int w = 0, h = 0;
                return parse_size(s, w, h) ? std::string()
                                           : "must be WxH with W and H in 1..16384, e.g. 512x512, got '" + s + "'";
            },
            ""));
    cmd->add_option("--guard", o->guard,
                     "fall back to direct light alone when the indirect share of the frame (ngi::indirect_share: "
                     "what the lightmap adds beyond direct light, as a share of the final image's luminance) "
                     "exceeds T; overrides the plan's guard [0 < T <= 1, default: the plan's, else no guard]")
        ->type_name("T")
        ->check(CLI::Validator(
            [](std::string& s) {
                double t = 0;
                return parse_guard(s, t) ? std::string()
                                         : "needs a finite number with 0 < T <= 1, got '" + s + "'";
            },
            ""));
    CLI::Option* display = add_path(*cmd, "--display", o->display_dir, "DIR",
                                    "the same camera's frame at the display's resolution (ngi render --face S): "
                                    "the lightmap's indirect light is upsampled to it, guided by its normals and "
                                    "depth, and composed with its direct light; outputs and metrics at that size",
                                    false);
    display->excludes("--size");
    add_choice(*cmd, "--upsampler", o->upsampler, {"jbu", "bilinear"},
               "how --display upsamples the indirect light: joint bilateral (guided) or bilinear", "jbu")
        ->needs(display);
    add_device(*cmd, o->device);
    cmd->add_flag("--timings", o->timings,
                  "print the wall time of each phase on stderr (read the frame, open the device, load the model, "
                  "run the pipeline, present and score, write)");
    return [o] {
        if (o->model_path.empty() && o->plan_path.empty()) throw UsageError("lightmap: --model or --plan is required");
        return run(*o);
    };
}

}  // namespace ngi_cli

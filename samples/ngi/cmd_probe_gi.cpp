// ngi probe-gi: lights one rendered view of a voxel scene from per-voxel fields (seed 004) and compares each with
// the path-traced reference: the SH-27 fields of trained voxel_sh models, the path-traced SH ground truth, the LTF
// (as written and physical), optional SH files (baselines), and, for comparison, direct light alone and the
// surround generator. Writes per method lightmap_<m>.exr, final_<m>.png and compare_<m>.png (method | reference |
// |difference|), the per-voxel fields computed here as field_<m>.npy, and metrics.json with every method's quality
// and cost.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/dataset.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/pipeline.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/tensor.hpp"
#include "ngi/voxel_gi.hpp"
#include "side_by_side.hpp"

namespace ngi_cli {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

nlohmann::json metrics_json(const ngi::ImageMetrics& m) { return nlohmann::json::parse(ngi::to_json(m)); }

// A method's name as part of a file name: letters, digits, '-' and '_' only.
bool valid_name(const std::string& s) {
    return !s.empty() && s.size() <= 64 && std::all_of(s.begin(), s.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    });
}

// A .npy of exactly `shape` (a field of this scene's voxels).
std::vector<float> read_field(const std::string& path, const std::vector<int>& shape) {
    const ngi::Tensor t = ngi::read_npy(path);
    if (t.shape != shape)
        throw ngi::InputError(path + ": shape " + ngi::shape_string(t.shape) + ", this scene needs " +
                              ngi::shape_string(shape));
    return t.data;
}

struct Method {
    std::string name, kind;  // kind: what it is, for metrics.json
    ngi::Image lighting;     // front face, irradiance / pi
    ngi::Tensor field;       // the per-voxel field it computed (model SH [V, 27], LTF lighting [V, 3]), if any
    double field_ms = -1;    // computing the per-voxel field (model, LTF); -1: read from a file or not per voxel
    double shade_ms = -1;
    nlohmann::json extra = nlohmann::json::object();
};

struct Options {
    std::string spec, field, out, device, surround_model, write_frame;
    std::vector<std::string> models, sh_files;
    double time = -1.0;
    int frame = 0, frames = 100, ltf_bounces = 8;
    bool noise_floor = false;
    ngi::RenderSettings rs;
};

int run(Options o) {
    // Methods named up front, so a bad name is a usage error before any work.
    std::vector<std::pair<std::string, std::string>> sh_files;  // name, path
    for (const std::string& s : o.sh_files) {
        const auto eq = s.find('=');
        if (eq == std::string::npos || !valid_name(s.substr(0, eq)) || eq + 1 == s.size())
            throw UsageError("--sh needs NAME=FILE.npy with NAME of letters, digits, '-' and '_', got '" + s + "'");
        sh_files.emplace_back(s.substr(0, eq), s.substr(eq + 1));
    }
    if (o.frame > o.frames - 1)
        throw UsageError("--frame needs an integer in 0.." + std::to_string(o.frames - 1) + ", got '" +
                         std::to_string(o.frame) + "'");
    if (o.rs.n % 2) throw UsageError("--face needs an even size (the surround pipeline's), got " + std::to_string(o.rs.n));
    ngi::OutputFolder out(o.out, "write", [](const std::string& dir) -> std::string {
        for (const auto& e : std::filesystem::directory_iterator(dir)) {
            const std::string f = e.path().filename().string();
            const bool ours = f == "metrics.json" || f == "reference.exr" || f == "final_reference.png" ||
                              f.rfind("lightmap_", 0) == 0 || f.rfind("final_", 0) == 0 || f.rfind("field_", 0) == 0 ||
                              f.rfind("compare_", 0) == 0;
            if (!ours) return "it holds " + f + ", which ngi probe-gi does not write";
        }
        return "";
    });
    // --out and --write-frame are written all or none: both are staged and committed together at the end (the frame
    // folder used to be written after --out was committed, so a failing frame write left --out behind with exit 1).
    std::unique_ptr<ngi::OutputFolder> frame_out;
    if (!o.write_frame.empty()) frame_out = ngi::frame_output_folder(o.write_frame);  // its checks, before any work

    ngi::Device device = ngi::Device::open(o.device);
    const ngi::VoxelScene scene = ngi::make_scene(o.spec);
    const float hours = o.time < 0.0 ? scene.default_time : float(o.time);
    const ngi::Lighting lighting = ngi::lighting_at(hours, scene.sun_azimuth);
    const ngi::SurfaceVoxels voxels = ngi::surface_voxels(device, scene, lighting);
    const int V = int(voxels.size());

    // The field folder must be this scene's, at this time: its attributes are compared value for value.
    const std::vector<float> attributes = read_field(o.field + "/attributes.npy", {V, ngi::kVoxelAttributes});
    if (attributes != voxels.attributes)
        throw ngi::InputError(o.field + ": its voxel attributes are not those of " + scene.name + " at " +
                              std::to_string(hours) + " h (another scene, time or grid)");
    const std::vector<float> sh_pt = read_field(o.field + "/sh.npy", {V, 27});
    const std::vector<float> direct = read_field(o.field + "/direct.npy", {V, 3});
    const std::vector<float> voxel_lighting = read_field(o.field + "/lighting.npy", {V, 3});

    // The surround generator, if asked for, is loaded (and its size rule checked) before the long render.
    std::optional<ngi::Model> surround;
    if (!o.surround_model.empty()) {
        surround.emplace(ngi::Model::load(device, ngi::resolve_model(o.surround_model)));
        const int k = surround->config().unet.num_downs;  // global view 2N x 4N: 2N must be divisible by 2^num_downs
        if (k < 1 || k > 12 || (2 * o.rs.n) % (1 << k) != 0)
            throw UsageError("--face " + std::to_string(o.rs.n) + ": the surround model " + o.surround_model +
                             " needs 2N divisible by 2^" + std::to_string(k) + " (N a multiple of " +
                             std::to_string(k >= 1 && k <= 12 ? (1 << k) / 2 : 0) + ")");
    }
    // The view: frame K of the scene's dataset camera path (as ngi render), rendered with its reference.
    const ngi::CameraPath path = ngi::dataset_camera_path(scene, o.frames, 25);
    const ngi::CameraPose pose = path.at(float(o.frame));
    o.rs.seed = ngi::dataset_frame_seed(scene.name, o.frame);
    o.rs.reference = true;
    ngi::Renderer renderer(device, scene);
    auto t0 = Clock::now();
    ngi::RenderStats st;
    const ngi::Frame frame = renderer.render(pose, lighting, o.rs, &st);
    const double render_ms = ms_since(t0);
    std::printf("scene      %s, %d surface voxels; view %d at (%.1f, %.1f, %.1f), %d^2, reference %d spp: %.1f s\n",
                scene.name.c_str(), V, o.frame, pose.position.x, pose.position.y, pose.position.z, o.rs.n,
                o.rs.reference_spp, render_ms * 1e-3);
    std::fflush(stdout);
    nlohmann::json noise_floor = nullptr;

    ngi::SurroundPipeline pipeline(device, frame.n);
    const ngi::Image& reference = *frame.reference;
    const ngi::Image reference_final = pipeline.tonemap(pipeline.compose(reference, frame));
    double peak = 0;
    for (float v : reference.data) peak = std::max(peak, double(v));
    if (o.noise_floor) {  // a second reference with another seed: the best score any method can reach
        ngi::RenderSettings second = o.rs;
        second.seed = o.rs.seed ^ 0x5bd1e995u;
        const ngi::Image r2 = renderer.render_reference(pose, lighting, second);
        const ngi::Image r2_final = pipeline.tonemap(pipeline.compose(r2, frame));
        noise_floor = {{"final_ldr", metrics_json(ngi::compare_images(device, r2_final, reference_final, 1.0))},
                       {"lightmap_linear", metrics_json(ngi::compare_images(device, r2, reference, peak))},
                       {"note", "a second reference of the same view with another seed against the first"}};
    }

    ngi::VoxelGi gi(device, voxels);
    // Warm-ups: the first call of each kernel builds its program (seconds); the times below are per frame.
    gi.shade(frame, pose.position, ngi::Face::Front, voxel_lighting, ngi::VoxelFieldKind::Lighting);
    gi.shade(frame, pose.position, ngi::Face::Front, sh_pt, ngi::VoxelFieldKind::Sh);
    std::vector<Method> methods;
    auto shade = [&](const std::string& name, const std::string& kind, const std::vector<float>& field,
                     ngi::VoxelFieldKind fk, double field_ms) {
        Method m{name, kind, {}, {}, field_ms};
        if (field_ms >= 0 && name != "direct") {  // computed here: written as field_<name>.npy for voxel metrics
            m.field = ngi::Tensor({int(V), fk == ngi::VoxelFieldKind::Sh ? 27 : 3});
            m.field.data = field;
        }
        ngi::ShadeStats ss;
        const auto ts = Clock::now();
        m.lighting = gi.shade(frame, pose.position, ngi::Face::Front, field, fk, &ss);
        m.shade_ms = ms_since(ts);
        m.extra["pixels_without_voxel"] = ss.no_voxel;
        m.extra["pixels_non_finite"] = ss.non_finite;
        methods.push_back(std::move(m));
    };
    methods.push_back({"direct", "the direct-light feature alone (no indirect light): the zero-cost rung",
                       frame.get(ngi::Feature::Direct, ngi::Face::Front), {}, 0.0, 0.0});
    shade("pt_voxel_lighting", "path-traced lighting at each voxel's probe point, one value per voxel",
          voxel_lighting, ngi::VoxelFieldKind::Lighting, -1);
    shade("pt_sh", "path-traced SH-27 of each voxel (the ground truth the networks learn)", sh_pt,
          ngi::VoxelFieldKind::Sh, -1);
    for (const auto& [name, file] : sh_files)
        shade(name, "SH field from " + file, read_field(file, {V, 27}), ngi::VoxelFieldKind::Sh, -1);
    for (const std::string& model_path : o.models) {
        ngi::Model model = ngi::Model::load(device, ngi::resolve_model(model_path));
        const ngi::ModelConfig& c = model.config();
        // A requirement of this command, not a dispatch: it feeds the voxel attributes and reads SH-27 per voxel.
        if (c.family != "voxel_sh")
            throw ngi::InputError("load model " + model_path + ": family " + c.family + ", ngi probe-gi needs voxel_sh");
        try {
            c.voxel_sh.check_grid(scene.size.x, scene.size.y, scene.size.z);  // InputError naming both sizes
        } catch (const ngi::InputError& e) {
            throw ngi::InputError("model " + model_path + " on " + scene.name + ": " + e.what());
        }
        ngi::Tensor in({V, ngi::kVoxelAttributes});
        in.data = voxels.attributes;
        model.run(in);  // the first run builds the programs and the graph: not what a frame costs
        const auto tm = Clock::now();
        const ngi::Tensor sh = model.run(in);
        const double ms = ms_since(tm);
        std::string name = std::filesystem::path(model_path).stem().string();
        if (!valid_name(name)) name = "model" + std::to_string(methods.size());
        shade(name, "voxel_sh model " + model_path + " (" + c.voxel_sh.architecture + ")", sh.data, ngi::VoxelFieldKind::Sh,
              ms);
    }
    if (o.ltf_bounces > 0) {
        const auto tv = Clock::now();
        const std::vector<std::uint32_t> vis = renderer.voxel_visibility(voxels);
        const double vis_ms = ms_since(tv);
        for (const ngi::LtfVariant variant : {ngi::LtfVariant::AsWritten, ngi::LtfVariant::Physical}) {
            const bool phys = variant == ngi::LtfVariant::Physical;
            gi.ltf(direct, 1, variant, phys ? &vis : nullptr);  // warm-up: builds the programs
            std::vector<double> energy;
            const auto tl = Clock::now();
            const std::vector<float> lit =
                gi.ltf(direct, o.ltf_bounces, variant, phys ? &vis : nullptr, &energy);
            const double ms = ms_since(tl);
            shade(phys ? "ltf_physical" : "ltf_as_written",
                  phys ? "radiosity between voxels with visibility from the path-traced direct light"
                       : "seed 004's LTF as written (normalized PDF, no visibility) from the path-traced direct light",
                  lit, ngi::VoxelFieldKind::Lighting, ms);
            methods.back().extra["bounces"] = o.ltf_bounces;
            methods.back().extra["energy_per_iterate"] = energy;
            if (phys) methods.back().extra["visibility_ms"] = vis_ms;
        }
    }
    if (surround) {  // the thesis generator on the same view (its six faces are rendered)
        pipeline.run(*surround, frame, true, false, false);  // warm-up: program builds
        const auto tg = Clock::now();
        ngi::FrameImages im = pipeline.run(*surround, frame, true, false, false);
        const double ms = ms_since(tg);
        methods.push_back({"surround_generator", "the thesis generator " + o.surround_model, std::move(im.lightmap),
                           {}, ms, 0.0});
    }

    // Everything computed; now the files (all or none).
    nlohmann::json per_method = nlohmann::json::object();
    for (const Method& m : methods) {
        const ngi::Image fin = pipeline.tonemap(pipeline.compose(m.lighting, frame));
        ngi::Image diff(fin.width, fin.height, 3);
        for (std::size_t i = 0; i < diff.data.size(); ++i) diff.data[i] = std::abs(fin.data[i] - reference_final.data[i]);
        if (!m.field.data.empty())
            out.write("field_" + m.name + ".npy", [&](const std::string& p) { ngi::write_npy(p, m.field); });
        out.write("lightmap_" + m.name + ".exr",
                  [&](const std::string& p) { ngi::write_exr(p, m.lighting, ngi::ExrPixelType::Float); });
        out.write("final_" + m.name + ".png", [&](const std::string& p) { ngi::write_png(p, fin); });
        out.write("compare_" + m.name + ".png",
                  [&](const std::string& p) { ngi::write_png(p, hconcat({&fin, &reference_final, &diff})); });
        nlohmann::json j = {{"kind", m.kind},
                            {"final_ldr", metrics_json(ngi::compare_images(device, fin, reference_final, 1.0))},
                            {"lightmap_linear", metrics_json(ngi::compare_images(device, m.lighting, reference, peak))},
                            {"field_ms", m.field_ms < 0 ? nlohmann::json(nullptr) : nlohmann::json(m.field_ms)},
                            {"shade_ms", m.shade_ms < 0 ? nlohmann::json(nullptr) : nlohmann::json(m.shade_ms)}};
        j.update(m.extra);
        per_method[m.name] = j;
        std::printf("%-22s final SSIM %.4f PSNR %6.2f dB | lightmap PSNR %6.2f dB | field %8.1f ms\n", m.name.c_str(),
                    j["final_ldr"]["ssim"].is_number() ? j["final_ldr"]["ssim"].get<double>() : NAN,
                    j["final_ldr"]["psnr"].is_number() ? j["final_ldr"]["psnr"].get<double>() : NAN,
                    j["lightmap_linear"]["psnr"].is_number() ? j["lightmap_linear"]["psnr"].get<double>() : NAN,
                    m.field_ms);
    }
    out.write("reference.exr", [&](const std::string& p) { ngi::write_exr(p, reference, ngi::ExrPixelType::Float); });
    out.write("final_reference.png", [&](const std::string& p) { ngi::write_png(p, reference_final); });
    const nlohmann::json metrics = {
        {"scene", scene.name},
        {"time_hours", hours},
        {"frame", o.frame},
        {"face", o.rs.n},
        {"reference_spp", o.rs.reference_spp},
        {"reference_relative_stderr", st.reference_rel_stderr},
        {"voxels", V},
        {"device", device.info().name},
        {"noise_floor", noise_floor},
        {"convention", "final_ldr: tone-mapped final images (albedo x lighting + emission + env), data_range 1; "
                       "lightmap_linear: front-view lighting (irradiance / pi), data_range = max of the reference"},
        {"methods", per_method}};
    out.write_text("metrics.json", metrics.dump(2) + "\n");
    if (frame_out) {
        ngi::write_frame_files(*frame_out, frame);
        ngi::OutputFolder::commit_all({&out, frame_out.get()});
    } else {
        out.commit();
    }
    std::printf("written    %s%s%s\n", o.out.c_str(), frame_out ? " and " : "", o.write_frame.c_str());
    return 0;
}

}  // namespace

Run add_probe_gi(CLI::App& app) {
    auto o = std::make_shared<Options>();
    o->rs.n = 96;
    o->rs.reference_spp = 512;
    CLI::App* cmd = add_command(
        app, "probe-gi", "light a view of a voxel scene from per-voxel fields (seed 004) and compare",
        "Renders view K of the scene with its path-traced reference, lights it from every field given (voxel_sh "
        "models, the field folder's path-traced SH and probe lighting, the LTF as written and physical, --sh files), "
        "and writes lightmap_<m>.exr, final_<m>.png, compare_<m>.png (method | reference | |difference|) and "
        "metrics.json (quality and cost of each).");
    add_path(*cmd, "--scene", o->spec, "SPEC", "the scene (a procedural family[:seed=S] or a .vox file)", true);
    add_path(*cmd, "--field", o->field, "DIR", "the scene's ngi voxel-data folder (same time of day)", true);
    add_path(*cmd, "--out", o->out, "DIR", "the folder to write", true);
    // Repeatable (the app's default refuses a repeated option): every occurrence adds one.
    cmd->add_option("--model", o->models,
                    "a trained voxel_sh model: a file or a shipped model's name (voxel_sh_set; repeatable)")
        ->type_name("M")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    cmd->add_option("--sh", o->sh_files, "another SH field [V,27] to shade, e.g. a baseline (repeatable)")
        ->type_name("NAME=FILE.npy")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    add_nonempty(*cmd, "--surround-model", o->surround_model, "M.safetensors",
                 "also run a thesis generator on the view, for comparison");
    add_integer(*cmd, "--ltf-bounces", o->ltf_bounces, 0, 64, "T", "bounces of both LTF variants (0: no LTF)");
    add_real(*cmd, "--time", o->time, 0.0, 48.0, "HOURS", "time of day (as the field's)", "the scene's");
    add_integer(*cmd, "--frame", o->frame, 0, ngi::kMaxPathFrames - 1, "K", "the view: frame K of the scene's camera path");
    add_integer(*cmd, "--path-frames", o->frames, 1, ngi::kMaxPathFrames, "P", "frames of the scene's camera path");
    add_integer(*cmd, "--face", o->rs.n, 2, 2048, "N", "view size in pixels (even)");
    add_integer(*cmd, "--spp", o->rs.reference_spp, 1, 1 << 20, "S", "samples per pixel of the reference");
    add_integer(*cmd, "--bounces", o->rs.max_bounces, 0, 1000, "B", "indirect bounces of the reference");
    add_switch(*cmd, "--noise-floor", o->noise_floor,
               "also render a second reference with another seed and report its score (the noise floor)");
    add_nonempty(*cmd, "--write-frame", o->write_frame, "DIR", "also write the rendered frame folder (ngi lightmap)");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli

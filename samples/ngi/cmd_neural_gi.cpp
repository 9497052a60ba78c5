// ngi neural-gi: a frame folder lit by an area light + a per-scene Neural GI model (seed 002) -> the front view's
// indirect light and final image, optionally with the network at 1/K resolution and joint bilateral upsampling,
// and, when the frame has a path-traced reference, a side-by-side comparison and metrics.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "frame_report.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/neural_gi.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/pipeline.hpp"
#include "side_by_side.hpp"

namespace ngi_cli {

namespace {

nlohmann::json metrics_json(const ngi::ImageMetrics& m) { return nlohmann::json::parse(ngi::to_json(m)); }

struct Options {
    std::string frame_dir, model_path, out_dir, device;
    int upsample = 1;
    double sigma_spatial = 0.75, normal_power = 32.0, sigma_plane = 0.1;
};

int run(const Options& o) {
    const char* const kFiles[] = {"indirect.exr", "lighting.exr", "final.png", "compare.png", "metrics.json"};
    ngi::OutputFolder out(o.out_dir, "write", {std::begin(kFiles), std::end(kFiles)});
    ngi::FrameReadStats read_stats;
    const ngi::Frame frame = ngi::read_frame(o.frame_dir, &read_stats);
    warn_frame_sanitized("neural-gi", o.frame_dir, read_stats);
    ngi::Device device = ngi::Device::open(o.device);
    ngi::Model model = ngi::Model::load(device, ngi::resolve_model(o.model_path));
    ngi::NeuralGiOptions options;
    options.upsample = o.upsample;
    options.jbu_sigma_spatial = float(o.sigma_spatial);
    options.jbu_normal_power = float(o.normal_power);
    options.jbu_sigma_plane = float(o.sigma_plane);
    ngi::NeuralGiRenderer renderer(device);
    const ngi::NeuralGiImages images = renderer.run(model, frame, options);
    if (images.sanitized_inputs)  // the assembled input is always within range: a bug if this prints
        std::fprintf(stderr, "ngi neural-gi: warning: the model's input guard replaced %d values\n",
                     images.sanitized_inputs);

    // Everything is computed before anything is written.
    ngi::SurroundPipeline pipeline(device, frame.n);  // compose and tone map, as `ngi lightmap` does
    const ngi::Image final_image = pipeline.compose(images.lighting, frame);
    std::vector<std::pair<std::string, ngi::Image>> pngs = {{"final.png", pipeline.tonemap(final_image)}};
    nlohmann::json metrics;
    if (frame.reference) {
        const ngi::Image& direct = frame.get(ngi::Feature::Direct, ngi::Face::Front);
        const ngi::Image d = pipeline.tonemap(pipeline.compose(direct, frame)), n = pipeline.tonemap(final_image),
                         r = pipeline.tonemap(pipeline.compose(*frame.reference, frame));
        pngs.emplace_back("compare.png", hconcat({&d, &n, &r}));
        double peak = 0;
        for (float v : frame.reference->data) peak = std::max(peak, double(v));
        metrics = {
            {"convention", "final_ldr: tone-mapped final images, data_range 1; lighting_linear: direct + indirect "
                           "lighting without albedo, data_range = max of the reference"},
            {"network", {{"final_ldr", metrics_json(ngi::compare_images(device, n, r, 1.0))},
                         {"lighting_linear",
                          metrics_json(ngi::compare_images(device, images.lighting, *frame.reference, peak))}}},
            {"direct_only", {{"final_ldr", metrics_json(ngi::compare_images(device, d, r, 1.0))},
                             {"lighting_linear", metrics_json(ngi::compare_images(device, direct, *frame.reference,
                                                                                  peak))}}},
            {"network_size", images.network_size},
            {"upsample", o.upsample},
            {"jbu_fallback_pixels", images.jbu_fallbacks},
        };
    }
    mark_scores(metrics, read_stats);  // null scores with a note when the frame's files held NaN/Inf

    out.write("indirect.exr", [&](const std::string& p) { ngi::write_exr(p, images.indirect, ngi::ExrPixelType::Float); });
    out.write("lighting.exr", [&](const std::string& p) { ngi::write_exr(p, images.lighting, ngi::ExrPixelType::Float); });
    for (const auto& named : pngs) out.write(named.first, [&](const std::string& p) { ngi::write_png(p, named.second); });
    if (!metrics.is_null()) out.write_text("metrics.json", metrics.dump(2) + "\n");
    out.commit();
    if (!metrics.is_null()) std::printf("%s\n", metrics.dump(2).c_str());
    std::printf("neural-gi  %s/indirect.exr, lighting.exr, final.png%s (%dx%d; network at %dx%d%s)\n",
                o.out_dir.c_str(), frame.reference ? ", compare.png (direct only | network | reference), metrics.json" : "",
                frame.n, frame.n, images.network_size, images.network_size,
                o.upsample > 1 ? (", joint bilateral upsampling x" + std::to_string(o.upsample) + ", " +
                                  std::to_string(images.jbu_fallbacks) + " bilinear fallback pixels")
                                     .c_str()
                               : "");
    return 0;
}

}  // namespace

Run add_neural_gi(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "neural-gi", "a frame lit by an area light + a Neural GI model (seed 002) -> indirect light, final image",
        "Writes indirect.exr, lighting.exr (direct + indirect) and final.png and, when the frame has a reference, "
        "compare.png (direct only | network | reference) and metrics.json. The model is trained per scene "
        "(docs/MODEL_FORMAT.md \"neural_gi\").");
    add_path(*cmd, "--frame", o->frame_dir, "DIR", "the frame folder (ngi render --area-light)", true);
    add_path(*cmd, "--model", o->model_path, "M",
             "the scene's neural_gi model: a .safetensors file or a shipped model's name (neural_gi_room)", true);
    add_path(*cmd, "--out", o->out_dir, "DIR", "the folder to write", true);
    add_integer(*cmd, "--upsample", o->upsample, 1, 64, "K",
                "run the network at 1/K of the face size and upsample its indirect light (joint bilateral)");
    add_real(*cmd, "--jbu-sigma-spatial", o->sigma_spatial, 1e-3, 100.0, "PX",
             "spatial standard deviation of the upsampling, in low-resolution pixels");
    add_real(*cmd, "--jbu-normal-power", o->normal_power, 0.0, 1024.0, "K", "exponent of the normal weight");
    add_real(*cmd, "--jbu-sigma-plane", o->sigma_plane, 1e-6, 1e6, "M",
             "standard deviation of the tangent-plane distance, in metres");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli

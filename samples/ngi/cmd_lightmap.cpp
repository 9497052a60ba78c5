// ngi lightmap: a frame folder + a trained generator -> the front view's GI lightmap and final image, and, when
// the frame has a path-traced reference, a side-by-side comparison and metrics.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"

namespace ngi_cli {

namespace {

// Images side by side (same height and channel count), left to right.
ngi::Image hconcat(const std::vector<const ngi::Image*>& images) {
    ngi::Image out(0, images[0]->height, images[0]->channels);
    for (const auto* im : images) out.width += im->width;
    out.data.assign(std::size_t(out.width) * out.height * out.channels, 0.0f);
    int x0 = 0;
    for (const auto* im : images) {
        for (int c = 0; c < out.channels; ++c)
            for (int y = 0; y < out.height; ++y)
                for (int x = 0; x < im->width; ++x) out.at(c, y, x0 + x) = im->at(c, y, x);
        x0 += im->width;
    }
    return out;
}

nlohmann::json metrics_json(const ngi::ImageMetrics& m) {
    return {{"mse", m.mse}, {"psnr", std::isfinite(m.psnr) ? nlohmann::json(m.psnr) : nlohmann::json()},
            {"ssim", m.ssim}};
}

}  // namespace

int cmd_lightmap(int argc, char** argv) {
    Args args(argc, argv, 2, {});
    const std::string frame_dir = args.require("frame"), model_path = args.require("model"),
                      out_dir = args.require("out");
    ngi::Device device = ngi::Device::open(args.get("device"));
    ngi::Model model = ngi::Model::load(device, model_path);
    const ngi::Frame frame = ngi::read_frame(frame_dir);
    int width = frame.n, height = frame.n;
    if (args.has("size") && std::sscanf(args.get("size").c_str(), "%dx%d", &width, &height) != 2)
        throw UsageError("--size must be WxH, e.g. 512x512");
    if (width < 1 || height < 1 || width > 16384 || height > 16384) throw UsageError("--size out of range");

    ngi::SurroundPipeline pipeline(device, frame.n);
    ngi::PreprocessStats stats;
    const ngi::Tensor input = pipeline.network_input(frame, model.config(), &stats);
    ngi::RunInfo info;
    const ngi::Tensor output = model.run(input, &info);
    const ngi::Image lightmap = pipeline.front_lightmap(output, model.config());
    const ngi::Image final_image = pipeline.compose(lightmap, frame);
    auto present = [&](const ngi::Image& im) {
        return width == im.width && height == im.height ? im : pipeline.upscale(im, width, height);
    };

    // Everything is computed before anything is written.
    std::vector<std::pair<std::string, ngi::Image>> pngs = {{"final.png", pipeline.tonemap(present(final_image))}};
    nlohmann::json metrics;
    if (frame.reference) {
        if (frame.reference->width != frame.n || frame.reference->height != frame.n)
            throw ngi::InputError("lightmap: " + frame_dir + "/reference.exr is " +
                                  std::to_string(frame.reference->width) + "x" +
                                  std::to_string(frame.reference->height) + ", expected the face size " +
                                  std::to_string(frame.n) + "x" + std::to_string(frame.n));
        // Direct-only baseline: the direct light alone as the lightmap (what a renderer has without GI).
        const ngi::Image direct_final = pipeline.compose(frame.get(ngi::Feature::Direct, ngi::Face::Front), frame);
        const ngi::Image reference_final = pipeline.compose(*frame.reference, frame);
        const ngi::Image d = pipeline.tonemap(direct_final), n = pipeline.tonemap(final_image),
                         r = pipeline.tonemap(reference_final);
        const ngi::Image dp = pipeline.tonemap(present(direct_final)), np = pipeline.tonemap(present(final_image)),
                         rp = pipeline.tonemap(present(reference_final));
        pngs.emplace_back("compare.png", hconcat({&dp, &np, &rp}));  // at the presentation size
        // Metrics at the frame's own resolution, on the tone-mapped final images (display-referred [0, 1],
        // data_range 1), like the thesis's
        // evaluation of 8-bit renders, and on the linear lightmaps (data_range = the reference's maximum).
        double peak = 0;
        for (float v : frame.reference->data) peak = std::max(peak, double(v));
        metrics = {
            {"convention", "final_ldr: tone-mapped final images, data_range 1; lightmap_linear: HDR lightmaps, "
                           "data_range = max of the reference lightmap"},
            {"network", {{"final_ldr", metrics_json(ngi::compare_images(device, n, r, 1.0))},
                         {"lightmap_linear", metrics_json(ngi::compare_images(device, lightmap, *frame.reference,
                                                                             std::max(peak, 1e-6)))}}},
            {"direct_only", {{"final_ldr", metrics_json(ngi::compare_images(device, d, r, 1.0))},
                             {"lightmap_linear",
                              metrics_json(ngi::compare_images(device, frame.get(ngi::Feature::Direct, ngi::Face::Front),
                                                               *frame.reference, std::max(peak, 1e-6)))}}},
        };
    }

    std::filesystem::create_directories(out_dir);
    ngi::write_exr(out_dir + "/lightmap.exr", present(lightmap), ngi::ExrPixelType::Float);
    for (const auto& [name, image] : pngs) ngi::write_png(out_dir + "/" + name, image);
    if (!metrics.is_null()) {
        std::ofstream(out_dir + "/metrics.json") << metrics.dump(2) << "\n";
        std::printf("%s\n", metrics.dump(2).c_str());
    }
    std::printf("lightmap   %s/lightmap.exr (%dx%d), final.png%s; input %s, %d NaN/Inf sanitized\n", out_dir.c_str(),
                width, height, frame.reference ? ", compare.png (direct only | network | reference), metrics.json" : "",
                ngi::shape_string(input.shape).c_str(), stats.total_nonfinite());
    return 0;
}

}  // namespace ngi_cli

// ngi merge: a frame folder -> the global view of every feature, the coordinate map and the network input.
#include <cstdio>
#include <filesystem>

#include "commands.hpp"
#include "ngi/image_io.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"

namespace ngi_cli {

int cmd_merge(int argc, char** argv) {
    Args args(argc, argv, 2, {});
    const std::string frame_dir = args.require("frame"), out_dir = args.require("out");
    ngi::Device device = ngi::Device::open(args.get("device"));
    ngi::FrameReadStats read_stats;
    const ngi::Frame frame = ngi::read_frame(frame_dir, &read_stats);
    const auto mode = ngi::global_view_mode_from_name(args.get("mode", "thesis"));
    ngi::SurroundPipeline pipeline(device, frame.n, mode);

    // The network input follows a model's config when one is given, else the default surround layout.
    ngi::ModelConfig config;
    if (args.has("model")) {
        config = ngi::Model::load(device, args.get("model")).config();
    } else {
        config.input_nc = 12;
        config.input_layout = ngi::surround_input_channels();
    }
    // Compute everything before writing anything: a bad frame leaves no partial output.
    std::vector<std::pair<std::string, ngi::Image>> views;
    for (int f = 0; f < ngi::kFeatureCount; ++f) {
        const auto feature = ngi::Feature(f);
        if (frame.get(feature, ngi::Face::Front).data.empty()) continue;  // optional emission / env absent
        views.emplace_back(std::string("globalview_") + ngi::feature_name(feature) + ".exr",
                           pipeline.global_view(frame, feature));
    }
    ngi::PreprocessStats stats;
    const ngi::Tensor input = pipeline.network_input(frame, config, &stats);

    std::filesystem::create_directories(out_dir);
    for (const auto& [name, image] : views) ngi::write_exr(out_dir + "/" + name, image, ngi::ExrPixelType::Float);
    ngi::write_exr(out_dir + "/coord.exr", pipeline.coord_map(), ngi::ExrPixelType::Float);
    ngi::write_npy(out_dir + "/input.npy", input);

    std::printf("frame      %s: N = %d, %zu NaN/Inf values sanitized on read\n", frame_dir.c_str(), frame.n,
                read_stats.total_sanitized());
    std::printf("global     %d x %d (%s layout): %zu features + coord.exr -> %s\n", pipeline.width(),
                pipeline.height(), ngi::global_view_mode_name(mode), views.size(), out_dir.c_str());
    std::printf("input.npy  %s, channels:", ngi::shape_string(input.shape).c_str());
    for (const auto& c : config.input_layout) std::printf(" %s", c.c_str());
    std::printf("\n");
    return 0;
}

}  // namespace ngi_cli

// ngi merge: a frame folder -> the global view of every feature, the coordinate map and the network input; with
// a reference, the training target (the reference encoded as the generator should output it).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/model.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/pipeline.hpp"

namespace ngi_cli {

namespace {

struct Options {
    std::string frame_dir, out_dir, mode = "thesis", model, device;
    const CLI::Option* model_given = nullptr;
    bool single_view = false, npy_only = false;
};

int run(const Options& o) {
    const std::string &frame_dir = o.frame_dir, &out_dir = o.out_dir;
    const ngi::GlobalViewMode mode = ngi::global_view_mode_from_name(o.mode);  // checked by the option
    // Checked before any work: an output folder this command may not replace is refused up front.
    std::vector<std::string> owned = {"coord.exr", "input.npy", "target.npy"};
    for (int f = 0; f < ngi::kFeatureCount; ++f)
        owned.push_back(std::string("globalview_") + ngi::feature_name(ngi::Feature(f)) + ".exr");
    ngi::OutputFolder out(out_dir, "write", owned);
    ngi::Device device = ngi::Device::open(o.device);
    ngi::FrameReadStats read_stats;
    const ngi::Frame frame = ngi::read_frame(frame_dir, &read_stats);
    ngi::SurroundPipeline pipeline(device, frame.n, mode);

    // The network input follows a model's config when one is given, else the default surround layout (or the
    // front view only with --single-view).
    ngi::ModelConfig config;
    if (o.model_given->count()) {
        config = ngi::Model::load(device, ngi::resolve_model(o.model)).config();
    } else if (o.single_view) {
        config.input_nc = 10;
        config.input_layout = ngi::single_view_input_channels();
    } else {
        config.input_nc = 12;
        config.input_layout = ngi::surround_input_channels();
    }
    const bool views_wanted = !o.npy_only;
    // Compute everything before writing anything: a bad frame leaves no partial output.
    std::vector<std::pair<std::string, ngi::Image>> views;
    for (int f = 0; views_wanted && f < ngi::kFeatureCount; ++f) {
        const auto feature = ngi::Feature(f);
        if (frame.get(feature, ngi::Face::Front).data.empty()) continue;  // optional emission / env absent
        views.emplace_back(std::string("globalview_") + ngi::feature_name(feature) + ".exr",
                           pipeline.global_view(frame, feature));
    }
    ngi::PreprocessStats stats;
    const ngi::Tensor input = pipeline.network_input(frame, config, &stats);
    // The target: the front view's reference lightmap, [1, 3, N, N], encoded as the inverse of front_lightmap.
    ngi::Tensor target;
    if (frame.reference) target = pipeline.encode_lightmap(*frame.reference, config);

    // All files or none: they are staged and the folder is renamed into place only when every write succeeded.
    auto exr = [&](const std::string& name, const ngi::Image& image) {
        out.write(name, [&](const std::string& p) { ngi::write_exr(p, image, ngi::ExrPixelType::Float); });
    };
    for (const auto& [name, image] : views) exr(name, image);
    if (views_wanted) exr("coord.exr", pipeline.coord_map());
    out.write("input.npy", [&](const std::string& p) { ngi::write_npy(p, input); });
    if (frame.reference) out.write("target.npy", [&](const std::string& p) { ngi::write_npy(p, target); });
    out.commit();

    std::printf("frame      %s: N = %d, %zu NaN/Inf values sanitized on read\n", frame_dir.c_str(), frame.n,
                read_stats.total_sanitized());
    if (views_wanted)
        std::printf("global     %d x %d (%s layout): %zu features + coord.exr -> %s\n", pipeline.width(),
                    pipeline.height(), ngi::global_view_mode_name(mode), views.size(), out_dir.c_str());
    std::printf("input.npy  %s, channels:", ngi::shape_string(input.shape).c_str());
    for (const auto& c : config.input_layout) std::printf(" %s", c.c_str());
    std::printf("\n");
    if (frame.reference)
        std::printf("target.npy %s: reference.exr through the %s transfer into [%g, %g]\n",
                    ngi::shape_string(target.shape).c_str(), ngi::lumination_transfer_name(pipeline.transfer()),
                    config.output_range[0], config.output_range[1]);
    return 0;
}

}  // namespace

Run add_merge(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "merge", "a frame folder -> the global view of every feature, coord.exr and the network input",
        "Writes globalview_<feature>.exr, coord.exr, the network input input.npy and, when the frame has a reference, "
        "the training target target.npy (--npy-only: only the .npy files).");
    add_path(*cmd, "--frame", o->frame_dir, "DIR", "the frame folder (ngi render)", true);
    add_path(*cmd, "--out", o->out_dir, "DIR", "the folder to write", true);
    add_choice(*cmd, "--mode", o->mode, {"thesis", "equirect"}, "the global view's layout");
    CLI::Option* model = add_path(*cmd, "--model", o->model, "M.safetensors",
                                  "lay the network input out as this model's config says [default: the surround "
                                  "layout, 12 channels]",
                                  false);
    CLI::Option* single = add_switch(*cmd, "--single-view", o->single_view,
                                     "the network input of the front view only (10 channels); not with --model");
    single->excludes(model);
    add_switch(*cmd, "--npy-only", o->npy_only, "write only input.npy (and target.npy), no .exr");
    add_device(*cmd, o->device);
    o->model_given = model;
    return [o] { return run(*o); };
}

}  // namespace ngi_cli

// Families "pix2pix_unet" and "deepillumination" (docs/MODEL_FORMAT.md): the U-Net generators' front-end. Their
// config (the network fields every generator has, its channel counts, and ModelConfig::unet), the tensors checked and
// the ops built by models/unet.cpp, run as graphs (models/graph_runner.hpp).
#include "models/family.hpp"
#include "models/graph_runner.hpp"
#include "models/network_config.hpp"
#include "models/unet.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi::detail {

namespace {

class UNetRunner : public GraphRunner {
public:
    explicit UNetRunner(UNetOps ops) : ops_(std::move(ops)) {}

protected:
    std::unique_ptr<Graph> build_graph(const ModelConfig&, int height, int width) const override {
        return build_unet_graph(ops_, height, width);
    }
    std::size_t weight_bytes() const override { return ops_.weight_bytes; }

private:
    UNetOps ops_;
};

// num_downs: pix2pix's UnetGenerator takes 5..12; DeepIllumination's G has exactly 8. Only pix2pix generators have
// output modes other than "lightmap".
FamilyConfig parse_unet_generator(const nlohmann::json& j, const std::string& path, std::string_view family,
                                  int min_downs, int max_downs, bool other_output_modes) {
    const ConfigFields f(j, path);
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = family;
    parsed.traits = {.input = ModelInput::image, .has_network = true, .output_keeps_size = true};
    network_config_start(f, c);
    c.output_nc = int(f.integer("output_nc", 1, kMaxChannels, 0, true));
    c.unet.ngf = int(f.integer("ngf", 1, kMaxChannels / 8, 0, true));  // the deepest levels have 8 * ngf channels
    c.unet.num_downs = int(f.integer("num_downs", min_downs, max_downs, 0, true));
    network_config_fields(f, c, c.unet, other_output_modes);
    network_config_end(f);
    return parsed;
}

FamilyConfig parse_pix2pix_unet(const nlohmann::json& j, const std::string& path) {
    return parse_unet_generator(j, path, "pix2pix_unet", 5, 12, true);
}

FamilyConfig parse_deepillumination(const nlohmann::json& j, const std::string& path) {
    return parse_unet_generator(j, path, "deepillumination", 8, 8, false);
}

std::unique_ptr<FamilyRunner> load_unet_generator(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                                  const std::string& path, const ModelOptions& options) {
    apply_network_options(cfg, options);
    refuse_mlp_path(options, path, cfg);
    return naming_file(path, [&] {
        const GemmSelection& gemm = gemm_selection(ctx);
        return std::make_unique<UNetRunner>(build_unet_ops(ctx, cfg, file, gemm.params, gemm.conv_params));
    });
}

}  // namespace

extern constinit const ModelFamily kPix2pixUnetFamily{"pix2pix_unet", &parse_pix2pix_unet, &load_unet_generator};
extern constinit const ModelFamily kDeepIlluminationFamily{"deepillumination", &parse_deepillumination, &load_unet_generator};

}  // namespace ngi::detail

// Family "neural_gi" (seed 002, docs/MODEL_FORMAT.md "neural_gi"): its config (the network fields of a pix2pix U-Net
// with a linear output, the encoding and the "neural_gi" object), the tensors checked and the graph built by
// models/neural_gi_model.cpp, run by models/graph_runner.hpp.
#include <cmath>

#include "models/family.hpp"
#include "models/float_field.hpp"
#include "models/graph_runner.hpp"
#include "models/mlp_model.hpp"
#include "models/network_config.hpp"
#include "models/neural_gi_model.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi::detail {

namespace {

constexpr int kMaxBufferChannels = 4096, kMaxNeuralGiMlpWidth = 4096, kMaxMlpDepth = 64;

// c.neural_gi and c.encoding from the metadata (c.unet, the buffer network's, is read: ngf, num_downs, bn_mode, ...).
void parse_neural_gi_fields(const nlohmann::json& j, ModelConfig& c, const std::string& what) {
    auto fail = [&](const std::string& key, const std::string& rule) {
        return InputError(what + "field '" + key + "' must be " + rule);
    };
    if (c.output_nc != 3) throw fail("output_nc", "3 (RGB indirect light) for family neural_gi");
    if (c.unet.dropout != "off") throw fail("dropout", "\"off\" for family neural_gi (its U-Net has no dropout)");
    parse_encoding_fields(j, c.encoding, what);
    if (!j.contains("neural_gi") || !j["neural_gi"].is_object())
        throw fail("neural_gi", "an object {buffer_channels, mlp_width, mlp_depth, skip_layer, decode}");
    const nlohmann::json& n = j["neural_gi"];
    auto integer = [&](const char* k, long long lo, long long hi) {
        if (!n.contains(k) || !n[k].is_number_integer() ||
            (n[k].is_number_unsigned() && n[k].get<std::uint64_t>() > std::uint64_t(hi)) || n[k].get<long long>() < lo ||
            n[k].get<long long>() > hi)
            throw fail(std::string("neural_gi.") + k, "an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
        return int(n[k].get<long long>());
    };
    ModelConfig::NeuralGi& g = c.neural_gi;
    g.buffer_channels = integer("buffer_channels", 1, kMaxBufferChannels);
    g.mlp_width = integer("mlp_width", 1, kMaxNeuralGiMlpWidth);
    g.mlp_depth = integer("mlp_depth", 1, kMaxMlpDepth);
    // 0: no re-injection (layer 0 takes the input anyway).
    g.skip_layer = integer("skip_layer", 0, g.mlp_depth - 1);
    if (n.contains("scene_box")) {
        const nlohmann::json& b = n["scene_box"];
        const std::string rule = std::string("{\"min\": [x, y, z], \"max\": [x, y, z]}, finite (|v| <= 1e30), ") +
                                 kFloat32Rule + ", min <= max";
        auto vec3 = [&](const char* k, float* out) {
            if (!b.is_object() || !b.contains(k) || !b[k].is_array() || b[k].size() != 3) throw fail("neural_gi.scene_box", rule);
            for (int i = 0; i < 3; ++i) {
                if (!b[k][i].is_number()) throw fail("neural_gi.scene_box", rule);
                const double v = b[k][i].get<double>();
                if (!std::isfinite(v) || std::abs(v) > 1e30 || !float32_representable(v))
                    throw fail("neural_gi.scene_box", rule);
                out[i] = float(v);
            }
        };
        vec3("min", g.scene_min);
        vec3("max", g.scene_max);
        for (int i = 0; i < 3; ++i)
            if (g.scene_min[i] > g.scene_max[i]) throw fail("neural_gi.scene_box", rule);
        g.has_scene_box = true;
    }
    if (!n.contains("decode") || n["decode"] != "exp")
        throw fail("neural_gi.decode", "\"exp\" (indirect = exp(min(x, 88)), never negative)");
}

FamilyConfig parse_neural_gi(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "neural_gi";
    parsed.traits = {.input = ModelInput::image, .has_network = true, .output_keeps_size = true};
    network_config_start(f, c);
    c.output_nc = int(f.integer("output_nc", 1, kMaxChannels, 0, true));
    c.unet.ngf = int(f.integer("ngf", 1, kMaxChannels / 8, 0, true));  // the deepest levels have 8 * ngf channels
    c.unet.num_downs = int(f.integer("num_downs", 5, 12, 0, true));
    network_config_fields(f, c, c.unet, false);
    parse_neural_gi_fields(j, c, f.what());  // after dropout: it must be off
    network_config_end(f);
    return parsed;
}

class NeuralGiRunner : public GraphRunner {
public:
    explicit NeuralGiRunner(NeuralGiOps ops) : ops_(std::move(ops)) {}

protected:
    std::unique_ptr<Graph> build_graph(const ModelConfig& cfg, int height, int width) const override {
        return build_neural_gi_graph(ops_, cfg.input_nc, height, width);
    }
    std::size_t weight_bytes() const override { return ops_.weight_bytes; }

private:
    NeuralGiOps ops_;
};

std::unique_ptr<FamilyRunner> load_neural_gi(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                             const std::string& path, const ModelOptions& options) {
    apply_network_options(cfg, options);
    refuse_mlp_path(options, path, cfg);
    return naming_file(path, [&] {
        const GemmSelection& gemm = gemm_selection(ctx);
        return std::make_unique<NeuralGiRunner>(build_neural_gi_ops(ctx, cfg, file, gemm.params, gemm.conv_params));
    });
}

}  // namespace

extern constinit const ModelFamily kNeuralGiFamily{"neural_gi", &parse_neural_gi, &load_neural_gi};

}  // namespace ngi::detail

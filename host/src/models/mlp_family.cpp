// Family "mlp" (docs/MODEL_FORMAT.md "mlp"): a network evaluated per item (pixel of an NCHW image, or row of an [N, C]
// point list). Its config (the network fields, its layers and frequency encoding, an AO network's "ao" object kept
// for ModelAccess::ao), and the runner over MlpRunner (models/mlp_model.hpp: fused kernel or dense GEMMs).
#include <cmath>
#include <set>

#include "models/family.hpp"
#include "models/float_field.hpp"
#include "models/mlp_model.hpp"
#include "models/network_config.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi::detail {

namespace {

constexpr int kMaxMlpLayers = 64;
constexpr int kMaxMlpWidth = 65536;

// c.mlp.layers, c.encoding and c.output_nc from the metadata `j`; `what` prefixes errors.
void parse_mlp_fields(const nlohmann::json& j, ModelConfig& c, const std::string& what) {
    auto fail = [&](const std::string& key, const std::string& rule) {
        return InputError(what + "field '" + key + "' must be " + rule);
    };
    if (!j.contains("layers") || !j["layers"].is_array() || j["layers"].empty() || j["layers"].size() > kMaxMlpLayers)
        throw fail("layers", "a list of 1.." + std::to_string(kMaxMlpLayers) + " layers {\"out\": n, \"activation\": a}");
    static const std::set<std::string> kActs = {"none", "relu", "leaky_relu", "tanh", "sigmoid", "exp"};
    for (std::size_t i = 0; i < j["layers"].size(); ++i) {
        const nlohmann::json& l = j["layers"][i];
        const std::string key = "layers[" + std::to_string(i) + "]";
        if (!l.is_object()) throw fail(key, "an object {\"out\": n, \"activation\": a}");
        ModelConfig::Mlp::Layer layer;
        if (!l.contains("out") || !l["out"].is_number_integer() || l["out"].get<long long>() < 1 ||
            l["out"].get<long long>() > kMaxMlpWidth)
            throw fail(key + ".out", "an integer in 1.." + std::to_string(kMaxMlpWidth));
        layer.out = l["out"].get<int>();
        if (l.contains("activation")) {
            if (!l["activation"].is_string() || !kActs.count(l["activation"].get<std::string>()))
                throw fail(key + ".activation", "one of none, relu, leaky_relu, tanh, sigmoid, exp");
            layer.activation = l["activation"].get<std::string>();
        }
        if (l.contains("slope")) {
            if (!l["slope"].is_number() || !std::isfinite(l["slope"].get<double>()) ||
                std::abs(l["slope"].get<double>()) > 1.0 || !float32_representable(l["slope"].get<double>()))
                throw fail(key + ".slope", std::string("a number in [-1, 1] ") + kFloat32Rule + ", got " +
                                               l["slope"].dump().substr(0, 40));
            layer.slope = l["slope"].get<float>();
        }
        c.mlp.layers.push_back(layer);
    }
    c.output_nc = c.mlp.layers.back().out;
    // An MLP's inputs (normals, positions, radiance) have no common range: unless the file says otherwise, the
    // guard replaces only NaN (-> 0) and +-Inf (-> +-FLT_MAX).
    c.input_range[0] = -3.402823466e38f;
    c.input_range[1] = 3.402823466e38f;
    parse_encoding_fields(j, c.encoding, what);
}

FamilyConfig parse_mlp(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "mlp";
    parsed.traits = {.input = ModelInput::items, .has_network = true, .output_keeps_size = true};
    network_config_start(f, c);
    parse_mlp_fields(j, c, f.what());  // layers, encoding; output_nc = the last layer's width
    if (j.contains("ao")) parsed.internal["ao"] = j["ao"];  // seed 001's AO network (ModelAccess::ao)
    if (j.contains("output_nc") && f.integer("output_nc", 1, kMaxChannels, 0, true) != c.output_nc)
        throw f.fail("output_nc", "the last layer's width (" + std::to_string(c.output_nc) + ")");
    // The U-Net's norm and dropout keys, accepted since the four families shared one parser: checked, then dropped
    // (an mlp has no U-Net: ModelConfig::unet stays empty).
    ModelConfig::UNet no_unet;
    network_config_fields(f, c, no_unet, false);
    network_config_end(f);
    return parsed;
}

// Per-item runner: the fused kernel or the dense GEMMs, over planar [C, n] items.
class MlpFamilyRunner : public FamilyRunner {
public:
    MlpFamilyRunner(Context& ctx, const MlpSpec& spec, const GemmParams& gemm, const std::string& path, float lo,
                    float hi)
        : mlp_(ctx, spec, gemm, path, lo, hi) {}
    Tensor run(Context& ctx, const ModelConfig&, const Tensor& input, RunInfo* info) override {
        enqueued_ = false;
        return mlp_.run(ctx, input, info);
    }
    void enqueue(const Device& device, const ModelConfig& c, const DeviceBuffer& input, const DeviceBuffer& output,
                 int height, int width) override {
        check_enqueue_items(height, width, "items");
        const std::size_t items = std::size_t(height) * std::size_t(width) * sizeof(float);
        check_enqueue_buffer(input, device, items * std::size_t(c.input_nc), false, "input");
        check_enqueue_buffer(output, device, items * std::size_t(c.output_nc), true, "output");
        mlp_.enqueue(context_of(device), input.opencl_mem(), output.opencl_mem(), height * width);
        enqueued_ = true;
    }
    void enqueue_frame(Context&, const ModelConfig&, cl_mem, std::size_t, cl_mem, std::size_t, int, int) override {
        throw InputError("the surround pipeline runs image generators; this model is an mlp");
    }
    int sanitized_inputs(Context& ctx) override { return enqueued_ ? mlp_.sanitized_count(ctx) : 0; }

private:
    MlpRunner mlp_;
    bool enqueued_ = false;  // the last call was enqueue (run's guard is counted in RunInfo)
};

std::unique_ptr<FamilyRunner> load_mlp(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                       const std::string& path, const ModelOptions& options) {
    // options.bn_mode and options.dropout are accepted and have nothing to act on (no U-Net).
    return std::make_unique<MlpFamilyRunner>(ctx, mlp_spec(cfg, file, path), gemm_selection(ctx).params,
                                             options.mlp_path, cfg.input_range[0], cfg.input_range[1]);
}

}  // namespace

extern constinit const ModelFamily kMlpFamily{"mlp", &parse_mlp, &load_mlp};

}  // namespace ngi::detail

// Family "pixel_cnn" (docs/MODEL_FORMAT.md "pixel_cnn"): a plain image-to-image CNN, a stack of k x k convolutions
// (k odd, stride 1, zero padding (k - 1) / 2, so every layer keeps the image's size), each with a bias and an
// activation, over [1, input_nc, H, W]. Its config is the layer list (kept private: the public ModelConfig has no
// section for it, and ModelConfig::json holds the metadata), its tensors "layers.<i>.weight" [out, in, k, k] and
// "layers.<i>.bias" [out] (optional), and its network a graph of conv2d nodes run by models/graph_runner.hpp.
#include <cfloat>
#include <cmath>
#include <set>
#include <vector>

#include "graph/nodes.hpp"
#include "models/config_fields.hpp"
#include "models/family.hpp"
#include "models/float_field.hpp"
#include "models/graph_runner.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi::detail {

namespace {

constexpr int kPixelCnnMaxLayers = 64, kPixelCnnMaxWidth = 4096, kPixelCnnMaxKernel = 31;

struct PixelCnnLayer {
    int out = 0, kernel = 1;
    Act act;
};

// The "layers" list: 1..64 objects {"out": 1..4096, "kernel": odd 1..31 (default 1), "activation": none | relu |
// leaky_relu | tanh | sigmoid (default none), "slope": leaky_relu's, [-1, 1] (default 0.01)}.
std::vector<PixelCnnLayer> read_pixel_cnn_layers(const ConfigFields& f) {
    const std::string rule = "a list of 1.." + std::to_string(kPixelCnnMaxLayers) +
                             " layers {\"out\": n, \"kernel\": k, \"activation\": a}";
    if (!f.has("layers") || !f.at("layers").is_array() || f.at("layers").empty() ||
        f.at("layers").size() > std::size_t(kPixelCnnMaxLayers))
        throw f.fail("layers", rule);
    std::vector<PixelCnnLayer> layers;
    for (std::size_t i = 0; i < f.at("layers").size(); ++i) {
        const nlohmann::json& l = f.at("layers")[i];
        const std::string key = "layers[" + std::to_string(i) + "]";
        auto bad = [&](const std::string& field, const std::string& what) {
            return InputError(f.what() + "field '" + key + field + "' must be " + what);
        };
        if (!l.is_object()) throw bad("", "an object {\"out\": n, \"kernel\": k, \"activation\": a}");
        for (const auto& item : l.items())
            if (item.key() != "out" && item.key() != "kernel" && item.key() != "activation" && item.key() != "slope")
                throw bad("", "an object of out, kernel, activation and slope; '" + item.key().substr(0, 80) +
                                  "' is none of them");
        PixelCnnLayer layer;
        if (!l.contains("out") || !is_integer_in(l["out"], 1, kPixelCnnMaxWidth))
            throw bad(".out", "an integer in 1.." + std::to_string(kPixelCnnMaxWidth));
        layer.out = l["out"].get<int>();
        if (l.contains("kernel")) {
            if (!is_integer_in(l["kernel"], 1, kPixelCnnMaxKernel) || l["kernel"].get<int>() % 2 == 0)
                throw bad(".kernel", "an odd integer in 1.." + std::to_string(kPixelCnnMaxKernel) +
                                         " (the padding (k - 1) / 2 keeps the image's size)");
            layer.kernel = l["kernel"].get<int>();
        }
        float slope = 0.01f;
        if (l.contains("slope")) {
            const nlohmann::json& s = l["slope"];
            if (!s.is_number() || !std::isfinite(s.get<double>()) || std::abs(s.get<double>()) > 1.0 ||
                !float32_representable(s.get<double>()))
                throw bad(".slope", std::string("a number in [-1, 1] ") + kFloat32Rule);
            slope = s.get<float>();
        }
        if (l.contains("activation") && !l["activation"].is_string())
            throw bad(".activation", "one of none, relu, leaky_relu, tanh, sigmoid");
        const std::string a = l.contains("activation") ? l["activation"].get<std::string>() : "none";
        if (a == "none") layer.act = Act::none();
        else if (a == "relu") layer.act = Act::relu();
        else if (a == "leaky_relu") layer.act = Act::leaky(slope);
        else if (a == "tanh") layer.act = Act::tanh();
        else if (a == "sigmoid") layer.act = Act::sigmoid();
        else throw bad(".activation", "one of none, relu, leaky_relu, tanh, sigmoid");
        layers.push_back(layer);
    }
    return layers;
}

FamilyConfig parse_pixel_cnn(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "pixel_cnn";
    parsed.traits = {.input = ModelInput::image, .has_network = true, .output_keeps_size = true};  // same padding
    f.format_version();
    c.input_nc = int(f.integer("input_nc", 1, kPixelCnnMaxWidth, 0, true));
    c.output_nc = read_pixel_cnn_layers(f).back().out;
    if (f.has("output_nc") && f.integer("output_nc", 1, kPixelCnnMaxWidth, 0, true) != c.output_nc)
        throw f.fail("output_nc", "the last layer's width (" + std::to_string(c.output_nc) + ")");
    // No known input range unless the file gives one: the guard replaces only NaN (-> 0) and +-Inf.
    c.input_range[0] = -FLT_MAX;
    c.input_range[1] = FLT_MAX;
    f.range("input_range", c.input_range);
    f.range("output_range", c.output_range);
    if (f.has("input_layout") && !read_input_layout(f.at("input_layout"), c.input_nc, c.input_layout))
        throw f.fail("input_layout", input_layout_rule(c.input_nc));
    c.source = f.string("source", {}, c.source, false);
    c.output_mode = f.string("output_mode", {"lightmap"}, c.output_mode, false);
    if (f.has("training") && !f.at("training").is_object()) throw f.fail("training", "an object");
    check_fields(f, {"format_version", "family", "input_nc", "output_nc", "layers", "input_range", "output_range",
                     "input_layout", "source", "output_mode", "training", "required"});
    return parsed;
}

class PixelCnnRunner : public GraphRunner {
public:
    PixelCnnRunner(std::vector<std::shared_ptr<Op>> convs, std::size_t weight_bytes)
        : convs_(std::move(convs)), weight_bytes_(weight_bytes) {}

protected:
    std::unique_ptr<Graph> build_graph(const ModelConfig& cfg, int height, int width) const override {
        auto g = std::make_unique<Graph>();
        TensorId x = g->input({cfg.input_nc, height, width}, "input");
        for (std::size_t i = 0; i < convs_.size(); ++i) x = g->add(convs_[i], {x}, "layers." + std::to_string(i));
        g->set_output(x);
        return g;
    }
    std::size_t weight_bytes() const override { return weight_bytes_; }

private:
    std::vector<std::shared_ptr<Op>> convs_;
    std::size_t weight_bytes_;
};

std::unique_ptr<FamilyRunner> load_pixel_cnn(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                             const std::string& path, const ModelOptions& options) {
    if (!options.bn_mode.empty() || !options.dropout.empty() || !options.mlp_path.empty())
        throw InputError("load model " + path + ": bn_mode, dropout and mlp_path do not apply to family pixel_cnn (no "
                         "batch norm, no dropout, not an mlp)");
    const nlohmann::json metadata = nlohmann::json::parse(cfg.json);  // the parser accepted it
    const std::vector<PixelCnnLayer> layers = read_pixel_cnn_layers(ConfigFields(metadata, path));
    // Every tensor present with its shape before anything touches the device, and no other tensor.
    const std::string where = "load model " + path + ": ";
    std::set<std::string> used;
    auto tensor = [&](const std::string& name, const std::vector<int>& shape, bool required) -> const StoredTensor* {
        const auto it = file.tensors.find(name);
        if (it == file.tensors.end()) {
            if (required) throw InputError(where + "tensor '" + name + "' is missing");
            return nullptr;
        }
        if (it->second.shape != shape)
            throw InputError(where + "tensor '" + name + "' is " + shape_string(it->second.shape) + ", expected " +
                             shape_string(shape));
        used.insert(name);
        return &it->second;
    };
    std::vector<const StoredTensor*> weights, biases;
    int in = cfg.input_nc;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        const std::string p = "layers." + std::to_string(i);
        const int k = layers[i].kernel;
        weights.push_back(tensor(p + ".weight", {layers[i].out, in, k, k}, true));
        biases.push_back(tensor(p + ".bias", {layers[i].out}, false));
        in = layers[i].out;
    }
    for (const auto& [name, t] : file.tensors)
        if (!used.count(name))
            throw InputError(where + "tensor '" + name + "' is not part of this pixel_cnn (" +
                             std::to_string(layers.size()) + " layers)");
    const GemmSelection& gemm = gemm_selection(ctx);
    const ConvPath conv_path = gemm.conv_params ? ConvPath::automatic : ConvPath::im2col;
    std::vector<std::shared_ptr<Op>> convs;
    std::size_t weight_bytes = 0;
    in = cfg.input_nc;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        const int k = layers[i].kernel;
        ChannelAffine affine;
        if (biases[i]) affine.shift = biases[i]->data;
        convs.push_back(std::make_shared<ConvNode>(
            ctx, gemm.params, ConvSpec{in, layers[i].out, {k, k, 1, (k - 1) / 2}, Act::none(), layers[i].act},
            weights[i]->data.data(), affine, conv_path, gemm.conv_params));
        weight_bytes += (weights[i]->data.size() + affine.shift.size()) * sizeof(float);
        in = layers[i].out;
    }
    return std::make_unique<PixelCnnRunner>(std::move(convs), weight_bytes);
}

}  // namespace

extern constinit const ModelFamily kPixelCnnFamily{"pixel_cnn", &parse_pixel_cnn, &load_pixel_cnn};

}  // namespace ngi::detail

#include "models/neural_gi_model.hpp"

#include <algorithm>
#include <set>

#include "graph/nodes.hpp"
#include "models/mlp_model.hpp"

namespace ngi::detail {

namespace {

const std::string kBufferPrefix = "buffer.";

// The U-Net part of the config: a pix2pix generator whose output is the neural buffer (dropout never applies).
ModelConfig buffer_config(const ModelConfig& cfg) {
    ModelConfig b = cfg;
    b.family = "pix2pix_unet";
    b.output_nc = cfg.neural_gi.buffer_channels;
    b.unet.dropout = "off";
    return b;
}

// The file's "buffer.*" tensors under their UnetGenerator names.
SafetensorsFile buffer_tensors(const SafetensorsFile& file) {
    SafetensorsFile b;
    for (const auto& [name, t] : file.tensors)
        if (name.rfind(kBufferPrefix, 0) == 0) b.tensors.emplace(name.substr(kBufferPrefix.size()), t);
    return b;
}

int encoded_width(const ModelConfig& cfg) { return frequency_encoding(cfg.encoding).width(cfg.input_nc); }

// Input width of hidden layer i.
int hidden_in(const ModelConfig& cfg, int i) {
    const ModelConfig::NeuralGi& n = cfg.neural_gi;
    const int z = encoded_width(cfg) + n.buffer_channels;
    if (i == 0) return z;
    return n.mlp_width + (i == n.skip_layer ? z : 0);
}

// name -> shape of every MLP tensor.
std::vector<std::pair<std::string, std::vector<int>>> mlp_tensors(const ModelConfig& cfg) {
    const ModelConfig::NeuralGi& n = cfg.neural_gi;
    std::vector<std::pair<std::string, std::vector<int>>> t;
    for (int i = 0; i < n.mlp_depth; ++i) {
        const std::string p = "mlp.layers." + std::to_string(i);
        t.push_back({p + ".weight", {n.mlp_width, hidden_in(cfg, i), 1, 1}});
        t.push_back({p + ".bias", {n.mlp_width}});
    }
    t.push_back({"mlp.output.weight", {cfg.output_nc, n.mlp_width, 1, 1}});
    t.push_back({"mlp.output.bias", {cfg.output_nc}});
    return t;
}

}  // namespace

void validate_neural_gi_tensors(const ModelConfig& cfg, const SafetensorsFile& file) {
    validate_unet_tensors(buffer_config(cfg), buffer_tensors(file));  // names the U-Net's own problems
    const std::string problems = tensor_mismatches(
        mlp_tensors(cfg), file, [](const std::string& name) { return name.rfind(kBufferPrefix, 0) == 0; });
    const ModelConfig::NeuralGi& n = cfg.neural_gi;
    if (!problems.empty())
        throw InputError("load model: the tensors do not match a neural_gi network with input_nc " +
                         std::to_string(cfg.input_nc) + ", encoded width " + std::to_string(encoded_width(cfg)) +
                         ", buffer_channels " + std::to_string(n.buffer_channels) + ", mlp " +
                         std::to_string(n.mlp_depth) + " x " + std::to_string(n.mlp_width) + ", skip_layer " +
                         std::to_string(n.skip_layer) + ":" + problems);
}

NeuralGiOps build_neural_gi_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file,
                                const GemmParams& gemm, const std::optional<GemmParams>& conv_gemm) {
    validate_neural_gi_tensors(cfg, file);
    const ConvPath conv_path = conv_gemm ? ConvPath::automatic : ConvPath::im2col;
    const ModelConfig::NeuralGi& n = cfg.neural_gi;
    NeuralGiOps ops;
    ops.buffer = build_unet_ops(ctx, buffer_config(cfg), buffer_tensors(file), gemm, conv_gemm, Act::none());
    ops.encode = std::make_shared<FrequencyEncodeNode>(ctx, cfg.input_nc, frequency_encoding(cfg.encoding));
    ops.skip_copy = std::make_shared<CopyNode>();
    ops.skip_layer = n.skip_layer;
    ops.weight_bytes = ops.buffer.weight_bytes;
    auto dense = [&](const std::string& prefix, int in, int out, Act act) {
        const StoredTensor& w = file.tensors.at(prefix + ".weight");
        ChannelAffine affine;
        affine.shift = file.tensors.at(prefix + ".bias").data;
        ops.weight_bytes += (w.data.size() + affine.shift.size()) * sizeof(float);
        return std::make_shared<ConvNode>(ctx, gemm, ConvSpec{in, out, {1, 1, 1, 0}, Act::none(), act}, w.data.data(),
                                          affine, conv_path, conv_gemm);
    };
    for (int i = 0; i < n.mlp_depth; ++i)
        ops.hidden.push_back(dense("mlp.layers." + std::to_string(i), hidden_in(cfg, i), n.mlp_width, Act::relu()));
    ops.output = dense("mlp.output", n.mlp_width, cfg.output_nc, Act::exp());
    return ops;
}

std::unique_ptr<Graph> build_neural_gi_graph(const NeuralGiOps& ops, int input_nc, int height, int width) {
    auto g = std::make_unique<Graph>();
    const TensorId x = g->input({input_nc, height, width}, "input");
    const TensorId encoded = g->add(ops.encode, {x}, "encode");
    const TensorId buffer = add_unet(*g, ops.buffer, x, "buffer.");
    const TensorId z = g->concat({encoded, buffer}, "mlp.input");
    TensorId h = z;
    for (std::size_t i = 0; i < ops.hidden.size(); ++i) {
        const std::string name = "mlp.layers." + std::to_string(i);
        if (ops.skip_layer > 0 && int(i) == ops.skip_layer)
            h = g->concat({h, g->add(ops.skip_copy, {z}, name + ".reinjected")}, name + ".input");
        h = g->add(ops.hidden[i], {h}, name);
    }
    g->set_output(g->add(ops.output, {h}, "mlp.output"));
    return g;
}

}  // namespace ngi::detail

// The "graph" family's weights and graph: check_graph_weights, the ops of every node (graph/nodes.hpp) with their
// weights uploaded, and the graph built per input size. graph_config.cpp parses the config and the node list.
#include "models/graph_model.hpp"

#include <algorithm>
#include <set>

#include "graph/nodes.hpp"
#include "models/graph_fuse.hpp"
#include "models/mlp_model.hpp"

namespace ngi::detail {

namespace {

// The activation of key `key` ("activation" or "input_activation") of node n; absent: none.
Act node_activation(const nlohmann::json& n, const char* key) {
    if (!n.contains(key)) return Act::none();
    const std::string a = n[key].get<std::string>();
    if (a == "relu") return Act::relu();
    if (a == "leaky_relu") return Act::leaky(n.contains("slope") ? n["slope"].get<float>() : 0.01f);
    if (a == "tanh") return Act::tanh();
    if (a == "sigmoid") return Act::sigmoid();
    if (a == "exp") return Act::exp();
    if (a == "softplus") return Act::softplus();
    if (a == "erf") return Act::erf();
    return Act::none();
}

// The op of node n (nullptr for a concat: Graph::concat places its inputs inside it, no op) with its weights
// uploaded; their bytes are added to weight_bytes.
std::shared_ptr<Op> make_node_op(Context& ctx, const GraphNodeDesc& n, const GraphNodeWeights& w, int cin,
                                 const GemmParams& gemm, const std::optional<GemmParams>& conv_gemm,
                                 std::size_t& weight_bytes) {
    const int cout = n.out_channels;
    const nlohmann::json& f = n.fields;
    switch (n.kind) {
        case NodeKind::conv2d:
        case NodeKind::conv_transpose2d:
        case NodeKind::dense: {
            const ConvPath conv_path = conv_gemm ? ConvPath::automatic : ConvPath::im2col;
            ChannelAffine affine;
            if (w.b) affine.shift = w.b->data;
            ConvSpec spec{cin, cout, {1, 1, 1, 0}, node_activation(f, "input_activation"),
                          node_activation(f, "activation")};
            if (n.kind != NodeKind::dense)
                spec.geom = {f["kernel"][0].get<int>(), f["kernel"][1].get<int>(), f["stride"].get<int>(),
                             f["pad"].get<int>()};
            std::shared_ptr<Op> op;
            if (n.kind == NodeKind::conv_transpose2d)
                op = std::make_shared<ConvTransposeNode>(ctx, gemm, spec, w.w->data.data(), affine, conv_path,
                                                         conv_gemm);
            else
                op = std::make_shared<ConvNode>(ctx, gemm, spec, w.w->data.data(), affine, conv_path, conv_gemm);
            weight_bytes += (w.w->data.size() + (w.b ? w.b->data.size() : 0)) * sizeof(float);
            return op;
        }
        case NodeKind::concat:
            return nullptr;
        case NodeKind::activation:
            return std::make_shared<ActivationNode>(ctx, node_activation(f, "activation"));
        case NodeKind::affine: {
            auto op = std::make_shared<AffineNode>(ctx, w.scale ? w.scale->data : std::vector<float>(cin, 1.0f),
                                                   w.shift ? w.shift->data : std::vector<float>(cin, 0.0f));
            weight_bytes += 2 * std::size_t(cin) * sizeof(float);
            return op;
        }
        case NodeKind::add:
        case NodeKind::mul:
            if (f.value("broadcast", false)) return std::make_shared<BroadcastNode>(ctx, n.kind == NodeKind::mul, cin);
            return std::make_shared<BinaryNode>(ctx, n.kind == NodeKind::mul);
        case NodeKind::frequency_encode: {
            ModelConfig::Encoding e;
            parse_encoding_fields(f, e, "");
            return std::make_shared<FrequencyEncodeNode>(ctx, cin, frequency_encoding(e));
        }
        case NodeKind::nan_to_num:
            return std::make_shared<NanToNumNode>(ctx);
        case NodeKind::max_pool2d:
            return std::make_shared<MaxPoolNode>(
                ctx, MaxPoolGeometry{f["kernel"][0].get<int>(), f["kernel"][1].get<int>(), f["stride"][0].get<int>(),
                                     f["stride"][1].get<int>(), f["pads"][0].get<int>(), f["pads"][1].get<int>(),
                                     f["pads"][2].get<int>(), f["pads"][3].get<int>()});
        case NodeKind::global_avg_pool:
            return std::make_shared<GlobalAvgPoolNode>(ctx);
        case NodeKind::instance_norm: {
            auto op = std::make_shared<BatchNormNode>(ctx, cin, w.scale->data, w.shift->data, f["eps"].get<float>(),
                                                      Act::none());
            weight_bytes += 2 * std::size_t(cin) * sizeof(float);
            return op;
        }
        case NodeKind::group_norm: {
            const int groups = f["groups"].get<int>();
            auto op = std::make_shared<GroupNormNode>(ctx, cin, groups, w.scale->data, w.shift->data,
                                                      f["eps"].get<float>());
            weight_bytes += 2 * std::size_t(groups) * sizeof(float);
            return op;
        }
        case NodeKind::pad2d: {
            const std::string mode = f["mode"].get<std::string>();
            return std::make_shared<PadNode>(
                ctx, PadGeometry{f["pads"][0].get<int>(), f["pads"][1].get<int>(), f["pads"][2].get<int>(),
                                 f["pads"][3].get<int>(),
                                 mode == "reflect" ? PadMode::Reflect
                                 : mode == "edge"  ? PadMode::Edge
                                                   : PadMode::Constant,
                                 f.value("value", 0.0f)});
        }
        case NodeKind::resize_bilinear: {
            const std::string c = f["coordinate"].get<std::string>();
            const ResizeCoord mode = c == "half_pixel"           ? ResizeCoord::HalfPixel
                                     : c == "pytorch_half_pixel" ? ResizeCoord::PytorchHalfPixel
                                     : c == "align_corners"      ? ResizeCoord::AlignCorners
                                                                 : ResizeCoord::Asymmetric;
            if (f.contains("sizes"))
                return std::make_shared<ResizeNode>(ctx, f["sizes"][0].get<int>(), f["sizes"][1].get<int>(), mode);
            return std::make_shared<ResizeNode>(ctx, f["scales"][0].get<float>(), f["scales"][1].get<float>(), mode);
        }
    }
    throw Error("graph model: node '" + n.name + "' has no node kind");  // unreachable: every kind is a case
}

}  // namespace

std::vector<GraphNodeWeights> check_graph_weights(const GraphDesc& d, const SafetensorsFile& file) {
    std::vector<int> channels = {d.input_nc};
    for (const GraphNodeDesc& n : d.nodes) channels.push_back(n.out_channels);
    // Every tensor a node names, present and of the shape the node implies; nothing else in the file.
    std::set<std::string> used;
    auto weight = [&](const GraphNodeDesc& n, const char* key, const std::vector<int>& shape) -> const StoredTensor* {
        if (!n.fields.contains(key)) return nullptr;
        const std::string name = n.fields[key].get<std::string>();
        auto it = file.tensors.find(name);
        if (it == file.tensors.end())
            throw InputError("load model: node '" + n.name + "' (" + n.op + "): tensor '" + name + "' (" + key +
                             ") is not in the file");
        if (it->second.shape != shape)
            throw InputError("load model: node '" + n.name + "' (" + n.op + "): tensor '" + name + "' (" + key +
                             ") is " + shape_string(it->second.shape) + ", expected " + shape_string(shape));
        used.insert(name);
        return &it->second;
    };
    std::vector<GraphNodeWeights> weights(d.nodes.size());
    for (std::size_t k = 0; k < d.nodes.size(); ++k) {
        const GraphNodeDesc& n = d.nodes[k];
        const int cin = channels[n.inputs[0]], cout = n.out_channels;
        GraphNodeWeights& w = weights[k];
        switch (n.kind) {
            case NodeKind::conv2d:
            case NodeKind::conv_transpose2d: {
                const int kh = n.fields["kernel"][0].get<int>(), kw = n.fields["kernel"][1].get<int>();
                w.w = weight(n, "weight", n.kind == NodeKind::conv2d ? std::vector<int>{cout, cin, kh, kw}
                                                                     : std::vector<int>{cin, cout, kh, kw});
                w.b = weight(n, "bias", {cout});
                break;
            }
            case NodeKind::dense:
                w.w = weight(n, "weight", {cout, cin});
                w.b = weight(n, "bias", {cout});
                break;
            case NodeKind::affine:
            case NodeKind::instance_norm:
                w.scale = weight(n, "scale", {cin});
                w.shift = weight(n, "shift", {cin});
                break;
            case NodeKind::group_norm: {
                const int groups = n.fields["groups"].get<int>();
                w.scale = weight(n, "scale", {groups});
                w.shift = weight(n, "shift", {groups});
                break;
            }
            case NodeKind::concat:
            case NodeKind::activation:
            case NodeKind::add:
            case NodeKind::mul:
            case NodeKind::frequency_encode:
            case NodeKind::nan_to_num:
            case NodeKind::max_pool2d:
            case NodeKind::global_avg_pool:
            case NodeKind::pad2d:
            case NodeKind::resize_bilinear:
                break;  // no weights
        }
    }
    for (const auto& [name, t] : file.tensors)
        if (!used.count(name))
            throw InputError("load model: tensor '" + name + "' is not used by any node of the graph");
    return weights;
}

GraphModelOps build_graph_model_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file,
                                    const GemmParams& gemm, const std::optional<GemmParams>& conv_gemm) {
    GraphModelOps m;
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(cfg.json);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(std::string("load model: metadata 'ngi': malformed JSON: ") + e.what());
    }
    const GraphDesc file_desc = parse_graph_desc(j, "load model: metadata 'ngi': ");
    // Pass 1: the weights of the list as written, checked before anything touches the device.
    const std::vector<GraphNodeWeights> file_weights = check_graph_weights(file_desc, file);
    // Pass 2: affines and activations folded into the layers before them where exact (graph_fuse.hpp).
    const FusedGraph fused = fuse_graph(file_desc, file_weights);
    m.desc = fused.desc;
    const GraphDesc& d = m.desc;
    std::vector<int> channels = {d.input_nc};
    for (const GraphNodeDesc& n : d.nodes) channels.push_back(n.out_channels);

    // Pass 3: the ops (weights uploaded).
    m.copy = std::make_shared<CopyNode>();
    for (std::size_t k = 0; k < d.nodes.size(); ++k) {
        const GraphNodeDesc& n = d.nodes[k];
        std::shared_ptr<Op> op;
        try {
            op = make_node_op(ctx, n, fused.weights[k], channels[n.inputs[0]], gemm, conv_gemm, m.weight_bytes);
        } catch (const InputError& e) {
            throw InputError("load model: node '" + graph_node_label(n) + "' (" + n.op + "): " + e.what());
        }
        m.ops.push_back(std::move(op));
    }
    return m;
}

std::unique_ptr<Graph> build_graph_model_graph(const GraphModelOps& m, int height, int width) {
    const GraphDesc& d = m.desc;
    auto g = std::make_unique<Graph>();
    std::vector<TensorId> t(d.nodes.size() + 1, -1);
    t[0] = g->input({d.input_nc, height, width}, d.input_name);
    // Readers of every tensor (a concat counts: its members live inside it); the graph output is read at the end.
    std::vector<int> readers(d.nodes.size() + 1, 0);
    for (const GraphNodeDesc& n : d.nodes)
        for (int i : n.inputs) ++readers[i];
    ++readers[d.output];
    // Tensors whose memory is a concat's (the concat itself, or an in-place result of it): its members live there
    // and may have readers of their own.
    std::vector<char> concat_memory(d.nodes.size() + 1, 0);
    for (std::size_t k = 0; k < d.nodes.size(); ++k) {
        const GraphNodeDesc& n = d.nodes[k];
        std::vector<TensorId> in;
        for (int i : n.inputs) in.push_back(t[i]);
        if (n.kind == NodeKind::concat) {
            for (std::size_t s = 0; s < in.size(); ++s)  // a tensor twice in one concat: the second is a copy
                if (!g->placeable(in[s]) || std::find(in.begin(), in.begin() + long(s), in[s]) != in.begin() + long(s))
                    in[s] = g->add(m.copy, {in[s]}, n.name + ".copy" + std::to_string(s));
            t[k + 1] = g->concat(in, n.name);
            concat_memory[k + 1] = 1;
            continue;
        }
        // An in-place op would change what the other readers of its input (or of a concat's members) see.
        if (m.ops[k]->in_place()) {
            if (readers[n.inputs[0]] > 1 || concat_memory[n.inputs[0]])
                in[0] = g->add(m.copy, {in[0]}, n.name + ".copy");
            else
                concat_memory[k + 1] = concat_memory[n.inputs[0]];
        }
        t[k + 1] = g->add(m.ops[k], in, graph_node_label(n));  // errors and profiles name what was folded in
    }
    g->set_output(t[d.output]);
    return g;
}

}  // namespace ngi::detail

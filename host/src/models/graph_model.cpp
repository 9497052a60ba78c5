#include "models/graph_model.hpp"

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <map>
#include <set>

#include "graph/nodes.hpp"
#include "ops/max_pool.hpp"
#include "ops/pad2d.hpp"
#include "ops/resize.hpp"
#include "ops/set_pool.hpp"
#include "models/float_field.hpp"
#include "models/mlp_model.hpp"
#include "models/unet.hpp"

namespace ngi::detail {

namespace {

constexpr int kMaxKernel = kMaxGraphKernel, kMaxStride = kMaxGraphStride, kMaxPad = kMaxGraphPad,
              kMaxNameLength = kMaxGraphNameLength;

// y = act(x), in place.
class ActivationNode : public Op {
public:
    ActivationNode(Context& ctx, Act act) : ew_(ctx), act_(act) {}
    std::string kind() const override { return "activation"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = ew_.activate(ctx, in[0], act_, ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    Act act_;
};

// torch.nan_to_num(x) with its defaults: NaN -> 0, +-Inf -> +-FLT_MAX, in place. The sanitize kernel with the
// float range as limits (its own counter, so the graph input's count is not touched).
class NanToNumNode : public Op {
public:
    explicit NanToNumNode(Context& ctx) : ew_(ctx) {}
    std::string kind() const override { return "nan_to_num"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>*) override {
        ew_.sanitize(ctx, in[0], -FLT_MAX, FLT_MAX);
    }

private:
    Elementwise ew_;
};

// x += y or x *= y (same shape), in place on input 0.
class BinaryNode : public Op {
public:
    BinaryNode(Context& ctx, bool mul) : ew_(ctx), mul_(mul) {}
    std::string kind() const override { return mul_ ? "mul" : "add"; }
    Shape infer(const std::vector<Shape>& in) const override {
        if (in.size() != 2) throw InputError(kind() + " takes two inputs");
        if (!(in[0] == in[1]))
            throw InputError(kind() + ": the inputs are " + to_string(in[0]) + " and " + to_string(in[1]) +
                             " (no broadcasting between computed tensors)");
        return in[0];
    }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = mul_ ? ew_.mul(ctx, in[0], in[1], ev != nullptr) : ew_.add(ctx, in[0], in[1], ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    bool mul_;
};

// y = x * s or x + s with s of shape C x 1 x 1 (a squeeze-excitation's channel weights): s is copied into the
// scale (or shift) of a per-channel affine. Not in place (the affine kernel's input and output are restrict).
class BroadcastNode : public Op {
public:
    BroadcastNode(Context& ctx, bool mul, int channels) : ew_(ctx), mul_(mul), channels_(channels) {
        const std::vector<float> ones(std::size_t(channels), 1.0f), zeros(std::size_t(channels), 0.0f);
        operand_ = ctx.alloc(std::size_t(channels) * sizeof(float), "graph broadcast operand");
        fixed_ = ctx.alloc(std::size_t(channels) * sizeof(float), "graph broadcast identity");
        ctx.write(fixed_, 0, std::size_t(channels) * sizeof(float), mul ? zeros.data() : ones.data(),
                  "graph broadcast identity");
    }
    std::string kind() const override { return mul_ ? "mul (broadcast)" : "add (broadcast)"; }
    Shape infer(const std::vector<Shape>& in) const override {
        if (in.size() != 2) throw InputError(kind() + " takes two inputs");
        if (in[0].c != channels_ || !(in[1] == Shape{channels_, 1, 1}))
            throw InputError(kind() + ": the inputs are " + to_string(in[0]) + " and " + to_string(in[1]) +
                             "; the second must be " + std::to_string(channels_) + "x1x1 (one value a channel)");
        return in[0];
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        ctx.copy(in[1].mem, in[1].offset * sizeof(float), operand_.get(), 0, std::size_t(channels_) * sizeof(float),
                 "graph broadcast operand");
        const int n = in[0].shape.h * in[0].shape.w;
        cl_event e = ew_.channel_affine(ctx, in[0].mem, in[0].offset, 1, n, channels_, n,
                                        mul_ ? operand_.get() : fixed_.get(), mul_ ? fixed_.get() : operand_.get(),
                                        out.mem, out.offset, ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    bool mul_;
    int channels_;
    Buffer operand_, fixed_;
};

// ONNX MaxPool (ops/max_pool.hpp): padded cells never win.
class MaxPoolNode : public Op {
public:
    MaxPoolNode(Context& ctx, const MaxPoolGeometry& g) : pool_(ctx, g) {}
    std::string kind() const override { return "max_pool2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return pool_.output_shape(ConvNode::one(in)); }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        pool_.enqueue(ctx, in[0], out, ev);
    }

private:
    MaxPool2d pool_;
};

// GroupNorm's normalization (ONNX's export: Reshape [0, G, -1], InstanceNormalization, Reshape back): each of G
// groups of C / G channels normalized over its channels and pixels together (mean and biased variance), then
// scale[g], shift[g]. A group's channels are contiguous in C x H x W, so this is the per-image batch norm over the
// same memory viewed as G x 1 x (C / G) H W; in place.
class GroupNormNode : public Op {
public:
    GroupNormNode(Context& ctx, int channels, int groups, const std::vector<float>& scale,
                  const std::vector<float>& shift, float eps)
        : bn_(ctx, groups, scale, shift, eps, Act::none()), channels_(channels), groups_(groups) {}
    std::string kind() const override { return "group_norm"; }
    Shape infer(const std::vector<Shape>& in) const override {
        const Shape& s = ConvNode::one(in);
        if (s.c != channels_)
            throw InputError("group_norm: the input has " + std::to_string(s.c) + " channels, the node " +
                             std::to_string(channels_));
        return s;
    }
    std::size_t scratch_floats(const std::vector<Shape>&) const override {
        return bn_.scratch_floats(Shape{groups_, 1, 1});
    }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem scratch,
                 std::vector<cl_event>* ev) override {
        const Shape& s = in[0].shape;
        bn_.enqueue(ctx, View{in[0].mem, in[0].offset, {groups_, 1, channels_ / groups_ * s.h * s.w}}, scratch, 0, ev);
    }

private:
    BatchNormPerImage bn_;
    int channels_, groups_;
};

// ONNX Pad over H and W (ops/pad2d.hpp): constant, reflect or edge.
class PadNode : public Op {
public:
    PadNode(Context& ctx, const PadGeometry& g) : pad_(ctx, g) {}
    std::string kind() const override { return "pad2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return pad_.output_shape(ConvNode::one(in)); }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        pad_.enqueue(ctx, in[0], out, ev);
    }

private:
    Pad2d pad_;
};

// ONNX Resize, mode linear, by constant scales (ops/resize.hpp): the output is floor(in * scale) a side with the
// product taken in float32, as onnxruntime does (PyTorch's exporter declares floor(10 * 0.7) = 7 for scale_factor
// 0.7, whose float32 scale 0.699999988 times 10 is 6.99999988 in double: 6), so the op is made per output size (a
// graph is built per input size).
class ResizeNode : public Op {
public:
    ResizeNode(Context& ctx, float scale_h, float scale_w, ResizeCoord mode)
        : ctx_(ctx), scale_h_(scale_h), scale_w_(scale_w), mode_(mode) {}
    // A fixed output size (ONNX 'sizes'): the scales of the coordinates are out / in, exactly.
    ResizeNode(Context& ctx, int out_h, int out_w, ResizeCoord mode)
        : ctx_(ctx), scale_h_(0.0f), scale_w_(0.0f), mode_(mode), out_h_(out_h), out_w_(out_w) {}
    std::string kind() const override { return "resize_bilinear"; }
    Shape infer(const std::vector<Shape>& in) const override {
        const Shape& s = ConvNode::one(in);
        if (out_h_ > 0) return op(out_h_, out_w_).output_shape(s);
        const float ph = float(s.h) * scale_h_, pw = float(s.w) * scale_w_;  // a float32 product (FLT_EVAL_METHOD 0)
        const double oh = std::floor(double(ph)), ow = std::floor(double(pw));
        if (!(oh >= 1 && ow >= 1 && oh <= kMaxDim && ow <= kMaxDim))
            throw InputError("resize_bilinear: scales " + std::to_string(scale_h_) + " x " + std::to_string(scale_w_) +
                             " make " + to_string(s) + " an output of " + std::to_string(oh) + " x " +
                             std::to_string(ow) + " (each side 1.." + std::to_string(kMaxDim) + ")");
        return op(int(oh), int(ow)).output_shape(s);
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        op(out.shape.h, out.shape.w).enqueue(ctx, in[0], out, ev);
    }

private:
    static constexpr int kMaxDim = 1 << 16;
    ResizeBilinear& op(int oh, int ow) const {
        auto& r = ops_[{oh, ow}];
        if (!r) r = std::make_unique<ResizeBilinear>(ctx_, ResizeGeometry{oh, ow, scale_h_, scale_w_, mode_});
        return *r;
    }
    Context& ctx_;
    float scale_h_, scale_w_;
    ResizeCoord mode_;
    int out_h_ = 0, out_w_ = 0;  // > 0: a fixed output size
    mutable std::map<std::pair<int, int>, std::unique_ptr<ResizeBilinear>> ops_;
};

// The mean of every channel over H x W: C x H x W -> C x 1 x 1 (ONNX GlobalAveragePool, ReduceMean over H and W).
class GlobalAvgPoolNode : public Op {
public:
    explicit GlobalAvgPoolNode(Context& ctx) : pool_(ctx) {}
    std::string kind() const override { return "global_avg_pool"; }
    Shape infer(const std::vector<Shape>& in) const override { return {ConvNode::one(in).c, 1, 1}; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>*) override {
        const int n = in[0].shape.h * in[0].shape.w;
        pool_.pool_planar(ctx, in[0].mem, in[0].offset, in[0].shape.c, n, 0, n, PoolMode::Mean, out.mem, out.offset);
    }

private:
    SetPool pool_;
};

// y[c] = scale[c] x[c] + shift[c] (a batch norm that follows no convolution, a Mul or Add by a constant).
class AffineNode : public Op {
public:
    AffineNode(Context& ctx, const std::vector<float>& scale, const std::vector<float>& shift)
        : ew_(ctx), channels_(int(scale.size())) {
        scale_ = ctx.alloc(scale.size() * sizeof(float), "graph affine scale");
        shift_ = ctx.alloc(shift.size() * sizeof(float), "graph affine shift");
        ctx.write(scale_, 0, scale.size() * sizeof(float), scale.data(), "graph affine scale");
        ctx.write(shift_, 0, shift.size() * sizeof(float), shift.data(), "graph affine shift");
    }
    std::string kind() const override { return "affine"; }
    Shape infer(const std::vector<Shape>& in) const override {
        const Shape& s = ConvNode::one(in);
        if (s.c != channels_)
            throw InputError("affine: the input has " + std::to_string(s.c) + " channels, the node " +
                             std::to_string(channels_));
        return s;
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        const int n = in[0].shape.h * in[0].shape.w;
        cl_event e = ew_.channel_affine(ctx, in[0].mem, in[0].offset, 1, n, channels_, n, scale_.get(), shift_.get(),
                                        out.mem, out.offset, ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    int channels_;
    Buffer scale_, shift_;
};

const std::set<std::string> kOps = {"conv2d", "conv_transpose2d", "dense", "concat", "activation",
                                    "affine", "add", "mul", "frequency_encode", "nan_to_num",
                                    "max_pool2d", "global_avg_pool", "instance_norm", "group_norm", "pad2d",
                                    "resize_bilinear"};
const std::set<std::string> kActivations = {"none", "relu", "leaky_relu", "tanh", "sigmoid", "exp", "softplus", "erf"};

bool is_int_in(const nlohmann::json& v, long long lo, long long hi) {
    if (!v.is_number_integer()) return false;
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(LLONG_MAX)) return false;
    const long long x = v.get<long long>();
    return x >= lo && x <= hi;
}

bool is_name(const nlohmann::json& v) {
    return v.is_string() && !v.get<std::string>().empty() && v.get<std::string>().size() <= kMaxNameLength;
}

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

}  // namespace

GraphDesc parse_graph_desc(const nlohmann::json& j, const std::string& what) {
    auto fail = [&](const std::string& key, const std::string& rule) {
        return InputError(what + "field '" + key + "' must be " + rule);
    };
    if (!j.contains("graph") || !j["graph"].is_object())
        throw fail("graph", "an object {\"layout\", \"input\", \"output\", \"nodes\"}");
    const nlohmann::json& g = j["graph"];
    GraphDesc d;
    if (g.contains("layout")) {
        if (!g["layout"].is_string() || (g["layout"] != "nchw" && g["layout"] != "nc"))
            throw fail("graph.layout", "\"nchw\" | \"nc\"");
        d.layout = g["layout"].get<std::string>();
    }
    if (!g.contains("input") || !is_name(g["input"])) throw fail("graph.input", "a tensor name (1..512 characters)");
    if (!g.contains("output") || !is_name(g["output"])) throw fail("graph.output", "a tensor name (1..512 characters)");
    if (!j.contains("input_nc") || !is_int_in(j["input_nc"], 1, kMaxChannels))
        throw fail("input_nc", "an integer in 1.." + std::to_string(kMaxChannels));
    d.input_name = g["input"].get<std::string>();
    d.input_nc = j["input_nc"].get<int>();
    if (!g.contains("nodes") || !g["nodes"].is_array() || g["nodes"].empty() || g["nodes"].size() > kMaxGraphNodes)
        throw fail("graph.nodes", "a list of 1.." + std::to_string(kMaxGraphNodes) + " node objects");

    std::map<std::string, int> tensor = {{d.input_name, 0}};  // name -> index
    std::vector<int> channels = {d.input_nc};
    std::set<std::string> node_names;
    const bool nc = d.layout == "nc";
    for (std::size_t k = 0; k < g["nodes"].size(); ++k) {
        const nlohmann::json& n = g["nodes"][k];
        std::string label = "graph.nodes[" + std::to_string(k) + "]";
        if (!n.is_object()) throw InputError(what + label + " is not an object");
        if (!n.contains("name") || !is_name(n["name"]))
            throw InputError(what + label + ": 'name' must be a string of 1..512 characters");
        GraphNodeDesc node;
        node.name = n["name"].get<std::string>();
        label = "node '" + node.name + "'";
        auto bad = [&](const std::string& msg) { return InputError(what + label + ": " + msg); };
        if (!node_names.insert(node.name).second) throw bad("a second node of this name");
        if (!n.contains("op") || !n["op"].is_string()) throw bad("'op' must be a string");
        node.op = n["op"].get<std::string>();
        label = "node '" + node.name + "' (" + node.op.substr(0, 80) + ")";
        if (!kOps.count(node.op))
            throw bad("op '" + node.op.substr(0, 80) + "' is not one of conv2d, conv_transpose2d, dense, concat, "
                      "activation, affine, add, mul, frequency_encode, nan_to_num, max_pool2d, global_avg_pool, "
                      "instance_norm, group_norm, pad2d, resize_bilinear");
        static const std::map<std::string, std::set<std::string>> kFields = {
            {"conv2d", {"in", "out", "kernel", "stride", "pad", "weight", "bias", "activation", "input_activation", "slope"}},
            {"conv_transpose2d", {"in", "out", "kernel", "stride", "pad", "weight", "bias", "activation", "input_activation", "slope"}},
            {"dense", {"in", "out", "weight", "bias", "activation", "slope"}},
            {"concat", {}},
            {"activation", {"activation", "slope"}},
            {"affine", {"scale", "shift"}},
            {"add", {"broadcast"}},
            {"mul", {"broadcast"}},
            {"frequency_encode", {"encoding"}},
            {"nan_to_num", {}},
            {"max_pool2d", {"kernel", "stride", "pads"}},
            {"global_avg_pool", {}},
            {"instance_norm", {"scale", "shift", "eps"}},
            {"group_norm", {"groups", "scale", "shift", "eps"}},
            {"pad2d", {"pads", "mode", "value"}},
            {"resize_bilinear", {"scales", "sizes", "coordinate"}}};
        const std::set<std::string>& allowed = kFields.at(node.op);
        for (auto it = n.begin(); it != n.end(); ++it) {
            const std::string& key = it.key();
            if (key != "name" && key != "op" && key != "inputs" && key != "output" && key != "source" &&
                !allowed.count(key))
                throw bad("unknown field '" + key.substr(0, 80) + "'");
        }
        // Inputs: each one the graph input or an earlier node's output (so no cycle, nothing dangling).
        if (!n.contains("inputs") || !n["inputs"].is_array() || n["inputs"].empty() ||
            n["inputs"].size() > std::size_t(kMaxGraphNodeInputs))
            throw bad("'inputs' must be a list of 1.." + std::to_string(kMaxGraphNodeInputs) + " tensor names");
        for (const auto& in : n["inputs"]) {
            if (!is_name(in)) throw bad("'inputs' must be a list of tensor names");
            auto it = tensor.find(in.get<std::string>());
            if (it == tensor.end())
                throw bad("input '" + in.get<std::string>().substr(0, 120) + "' is neither the graph input nor the "
                          "output of an earlier node (dangling, or a cycle)");
            node.inputs.push_back(it->second);
        }
        const std::size_t arity = node.op == "concat" ? 0 : (node.op == "add" || node.op == "mul") ? 2 : 1;
        if (arity && node.inputs.size() != arity)
            throw bad("takes " + std::to_string(arity) + " input" + (arity > 1 ? "s" : "") + ", the list has " +
                      std::to_string(node.inputs.size()));
        if (!n.contains("output") || !is_name(n["output"])) throw bad("'output' must be a tensor name");
        node.output = n["output"].get<std::string>();
        if (tensor.count(node.output)) throw bad("output '" + node.output.substr(0, 120) + "' is made a second time");
        const int cin = channels[node.inputs[0]];

        // Activation fields.
        for (const char* key : {"activation", "input_activation"}) {
            if (!n.contains(key)) continue;
            if (!n[key].is_string() || !kActivations.count(n[key].get<std::string>()))
                throw bad(std::string("'") + key + "' must be one of none, relu, leaky_relu, tanh, sigmoid, exp, "
                          "softplus, erf");
        }
        if (node.op == "activation" && !n.contains("activation")) throw bad("'activation' is missing");
        if (n.contains("slope")) {
            const nlohmann::json& s = n["slope"];
            if (!s.is_number() || !std::isfinite(s.get<double>()) || std::abs(s.get<double>()) > 1.0 ||
                !float32_representable(s.get<double>()))
                throw bad(std::string("'slope' must be a number in [-1, 1] ") + kFloat32Rule);
        }
        auto tensor_field = [&](const char* key, bool required) {
            if (!n.contains(key)) {
                if (required) throw bad(std::string("'") + key + "' (a tensor name) is missing");
                return;
            }
            if (!is_name(n[key])) throw bad(std::string("'") + key + "' must be a tensor name");
        };
        auto int_field = [&](const char* key, long long lo, long long hi) {
            if (!n.contains(key) || !is_int_in(n[key], lo, hi))
                throw bad(std::string("'") + key + "' must be an integer in " + std::to_string(lo) + ".." +
                          std::to_string(hi));
            return int(n[key].get<long long>());
        };

        if (node.op == "conv2d" || node.op == "conv_transpose2d" || node.op == "dense") {
            const int in = int_field("in", 1, kMaxChannels);
            node.out_channels = int_field("out", 1, kMaxChannels);
            if (in != cin)
                throw bad("'in' is " + std::to_string(in) + ", its input has " + std::to_string(cin) + " channels");
            tensor_field("weight", true);
            tensor_field("bias", false);
            if (node.op != "dense") {
                const std::string rule = "[kh, kw], integers in 1.." + std::to_string(kMaxKernel);
                if (!n.contains("kernel") || !n["kernel"].is_array() || n["kernel"].size() != 2 ||
                    !is_int_in(n["kernel"][0], 1, kMaxKernel) || !is_int_in(n["kernel"][1], 1, kMaxKernel))
                    throw bad("'kernel' must be " + rule);
                const int stride = int_field("stride", 1, kMaxStride), pad = int_field("pad", 0, kMaxPad);
                if (nc && (n["kernel"][0] != 1 || n["kernel"][1] != 1 || stride != 1 || pad != 0))
                    throw bad("layout \"nc\" has no spatial axes: only 1 x 1 kernels, stride 1, pad 0");
            }
        } else if (node.op == "concat") {
            long long c = 0;
            for (int i : node.inputs) c += channels[i];
            if (c > kMaxChannels) throw bad("concatenates " + std::to_string(c) + " channels (at most " +
                                            std::to_string(kMaxChannels) + ")");
            node.out_channels = int(c);
        } else if (node.op == "add" || node.op == "mul") {
            if (n.contains("broadcast") && !n["broadcast"].is_boolean()) throw bad("'broadcast' must be true or false");
            if (channels[node.inputs[1]] != cin)
                throw bad("combines " + std::to_string(cin) + " and " + std::to_string(channels[node.inputs[1]]) +
                          " channels (the second input may be one value a channel, 'broadcast', not fewer channels)");
            if (nc && n.value("broadcast", false)) throw bad("layout \"nc\" has no spatial axes to broadcast over");
            node.out_channels = cin;
        } else if (node.op == "max_pool2d") {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pool");
            auto pair = [&](const char* key, int lo, int hi) {
                const std::string rule = std::string("'") + key + "' must be [h, w], integers in " + std::to_string(lo) +
                                         ".." + std::to_string(hi);
                if (!n.contains(key) || !n[key].is_array() || n[key].size() != 2 || !is_int_in(n[key][0], lo, hi) ||
                    !is_int_in(n[key][1], lo, hi))
                    throw bad(rule);
                return std::pair<int, int>{n[key][0].get<int>(), n[key][1].get<int>()};
            };
            const auto [kh, kw] = pair("kernel", 1, kMaxKernel);
            pair("stride", 1, kMaxStride);
            const std::string rule = "'pads' must be [top, left, bottom, right], integers in 0.." +
                                     std::to_string(kMaxPad) + ", each below its kernel side";
            if (!n.contains("pads") || !n["pads"].is_array() || n["pads"].size() != 4) throw bad(rule);
            for (int s = 0; s < 4; ++s)
                if (!is_int_in(n["pads"][s], 0, kMaxPad) || n["pads"][s].get<int>() >= (s % 2 ? kw : kh)) throw bad(rule);
            node.out_channels = cin;
        } else if (node.op == "pad2d") {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pad");
            const std::string rule = "'pads' must be [top, left, bottom, right], integers in -" +
                                     std::to_string(kMaxPad) + ".." + std::to_string(kMaxPad) + " (negative: a crop)";
            if (!n.contains("pads") || !n["pads"].is_array() || n["pads"].size() != 4) throw bad(rule);
            for (const auto& p : n["pads"])
                if (!is_int_in(p, -kMaxPad, kMaxPad)) throw bad(rule);
            if (!n.contains("mode") || !n["mode"].is_string() ||
                (n["mode"] != "constant" && n["mode"] != "reflect" && n["mode"] != "edge"))
                throw bad("'mode' must be \"constant\", \"reflect\" or \"edge\"");
            if (n.contains("value") && (!n["value"].is_number() || !float32_representable(n["value"].get<double>())))
                throw bad(std::string("'value' must be a number ") + kFloat32Rule);
            node.out_channels = cin;
        } else if (node.op == "resize_bilinear") {
            if (nc) throw bad("layout \"nc\" has no spatial axes to resize");
            if (n.contains("scales") == n.contains("sizes"))
                throw bad("exactly one of 'scales' ([h, w] factors) and 'sizes' ([h, w] output pixels) is needed");
            if (n.contains("scales")) {
                const std::string rule = "'scales' must be [h, w], numbers in [1/64, 64]";
                if (!n["scales"].is_array() || n["scales"].size() != 2) throw bad(rule);
                for (const auto& s : n["scales"])
                    if (!s.is_number() || !(s.get<double>() >= 1.0 / 64) || !(s.get<double>() <= 64)) throw bad(rule);
            } else {
                const std::string rule = "'sizes' must be [h, w], integers in 1..65536";
                if (!n["sizes"].is_array() || n["sizes"].size() != 2 || !is_int_in(n["sizes"][0], 1, 65536) ||
                    !is_int_in(n["sizes"][1], 1, 65536))
                    throw bad(rule);
            }
            static const std::set<std::string> kCoords = {"half_pixel", "pytorch_half_pixel", "align_corners",
                                                          "asymmetric"};
            if (!n.contains("coordinate") || !n["coordinate"].is_string() || !kCoords.count(n["coordinate"].get<std::string>()))
                throw bad("'coordinate' must be \"half_pixel\", \"pytorch_half_pixel\", \"align_corners\" or "
                          "\"asymmetric\"");
            node.out_channels = cin;
        } else if (node.op == "global_avg_pool") {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pool");
            node.out_channels = cin;
        } else if (node.op == "instance_norm" || node.op == "group_norm") {
            if (nc) throw bad("layout \"nc\" has no spatial axes to normalize over");
            if (node.op == "group_norm" && cin % int_field("groups", 1, kMaxChannels) != 0)
                throw bad("'groups' (" + n["groups"].dump() + ") must divide the input's " + std::to_string(cin) +
                          " channels");
            tensor_field("scale", true);
            tensor_field("shift", true);
            const nlohmann::json* eps = n.contains("eps") ? &n["eps"] : nullptr;
            if (!eps || !eps->is_number() || !(eps->get<double>() > 0) || !(eps->get<double>() <= 1.0) ||
                !float32_representable(eps->get<double>()) || !(float(eps->get<double>()) > 0.0f))
                throw bad(std::string("'eps' must be a number in (0, 1] ") + kFloat32Rule);
            node.out_channels = cin;
        } else if (node.op == "affine") {
            tensor_field("scale", false);
            tensor_field("shift", false);
            if (!n.contains("scale") && !n.contains("shift")) throw bad("neither 'scale' nor 'shift' is given");
            node.out_channels = cin;
        } else if (node.op == "frequency_encode") {
            if (!n.contains("encoding") || !n["encoding"].is_object()) throw bad("'encoding' must be an object");
            ModelConfig e;
            parse_encoding_fields(n, e, what + label + ": ");
            if (e.encoding_bands < 1) throw bad("'encoding.bands' must be at least 1");
            node.out_channels = frequency_encoding(e).width(cin);
            if (node.out_channels > kMaxChannels) throw bad("encodes to more than " + std::to_string(kMaxChannels) + " channels");
        } else {  // activation, nan_to_num
            node.out_channels = cin;
        }
        node.fields = n;
        tensor[node.output] = int(d.nodes.size()) + 1;
        channels.push_back(node.out_channels);
        d.nodes.push_back(std::move(node));
    }
    auto out = tensor.find(g["output"].get<std::string>());
    if (out == tensor.end())
        throw fail("graph.output", "the output of a node; no node makes '" + g["output"].get<std::string>().substr(0, 120) + "'");
    if (out->second == 0) throw fail("graph.output", "a node's output, not the graph input itself");
    d.output = out->second;
    return d;
}

ModelConfig parse_graph_config(const nlohmann::json& j, const std::string& path) {
    const std::string what = "load model " + path + ": metadata 'ngi': ";
    auto fail = [&](const std::string& key, const std::string& rule) {
        const std::string got = j.contains(key) ? ", got " + j[key].dump() : " (missing)";
        return InputError(what + "field '" + key + "' must be " + rule + got.substr(0, 120));
    };
    ModelConfig c;
    c.family = "graph";
    if (j.contains("format_version")) {
        if (j["format_version"].is_number_integer() && j["format_version"].get<long long>() > kModelFormatVersion)
            throw InputError(what + "field 'format_version' is " + j["format_version"].dump() +
                             ", newer than the newest this reader knows (" + std::to_string(kModelFormatVersion) +
                             "): update ngi");
        if (!is_int_in(j["format_version"], 1, kModelFormatVersion))
            throw fail("format_version", "an integer in 1.." + std::to_string(kModelFormatVersion));
    }
    const GraphDesc d = parse_graph_desc(j, what);
    c.input_nc = d.input_nc;
    c.output_nc = d.nodes[d.output - 1].out_channels;
    c.graph.layout = d.layout;
    if (j.contains("output_nc") && !(is_int_in(j["output_nc"], 1, kMaxChannels) && j["output_nc"] == c.output_nc))
        throw fail("output_nc", "the graph output's channel count (" + std::to_string(c.output_nc) + ")");
    // An imported network's inputs have no known range: the guard replaces only NaN (-> 0) and +-Inf.
    c.input_range[0] = -FLT_MAX;
    c.input_range[1] = FLT_MAX;
    for (const char* key : {"input_range", "output_range"}) {
        if (!j.contains(key)) continue;
        const nlohmann::json& v = j[key];
        const std::string rule = std::string("[lo, hi], two numbers with lo < hi, both ") + kFloat32Rule;
        if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) throw fail(key, rule);
        const double lo = v[0].get<double>(), hi = v[1].get<double>();
        if (!float32_representable(lo) || !float32_representable(hi) || !(float(lo) < float(hi))) throw fail(key, rule);
        float* out = std::string(key) == "input_range" ? c.input_range : c.output_range;
        out[0] = float(lo);
        out[1] = float(hi);
    }
    if (j.contains("input_layout") && !read_input_layout(j["input_layout"], c.input_nc, c.input_layout))
        throw fail("input_layout", input_layout_rule(c.input_nc));
    if (j.contains("source")) {
        if (!j["source"].is_string()) throw fail("source", "a string");
        c.source = j["source"].get<std::string>();
    }
    if (j.contains("output_mode") && j["output_mode"] != "lightmap")
        throw fail("output_mode", "\"lightmap\" (only family pix2pix_unet has another output mode)");
    if (j.contains("training") && !j["training"].is_object()) throw fail("training", "an object");
    static const std::set<std::string> kKnown = {"format_version", "family", "input_nc", "output_nc", "graph",
                                                 "input_range", "output_range", "input_layout", "source",
                                                 "training", "required", "onnx", "output_mode"};
    if (j.contains("required")) {
        if (!j["required"].is_array()) throw fail("required", "a list of field names");
        for (const auto& name : j["required"]) {
            if (!name.is_string()) throw fail("required", "a list of field names");
            if (!kKnown.count(name.get<std::string>()))
                throw InputError(what + "field 'required' lists '" + name.get<std::string>().substr(0, 80) +
                                 "', which this reader does not know: the file needs a newer ngi");
        }
    }
    return c;
}

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
        if (n.op == "conv2d" || n.op == "conv_transpose2d") {
            const int kh = n.fields["kernel"][0].get<int>(), kw = n.fields["kernel"][1].get<int>();
            w.w = weight(n, "weight", n.op == "conv2d" ? std::vector<int>{cout, cin, kh, kw}
                                                        : std::vector<int>{cin, cout, kh, kw});
            w.b = weight(n, "bias", {cout});
        } else if (n.op == "dense") {
            w.w = weight(n, "weight", {cout, cin});
            w.b = weight(n, "bias", {cout});
        } else if (n.op == "affine" || n.op == "instance_norm") {
            w.scale = weight(n, "scale", {cin});
            w.shift = weight(n, "shift", {cin});
        } else if (n.op == "group_norm") {
            const int groups = n.fields["groups"].get<int>();
            w.scale = weight(n, "scale", {groups});
            w.shift = weight(n, "shift", {groups});
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
    m.desc = parse_graph_desc(j, "load model: metadata 'ngi': ");
    const GraphDesc& d = m.desc;
    std::vector<int> channels = {d.input_nc};
    for (const GraphNodeDesc& n : d.nodes) channels.push_back(n.out_channels);
    // Pass 1: the weights, checked before anything touches the device.
    const std::vector<GraphNodeWeights> weights = check_graph_weights(d, file);

    // Pass 2: the ops (weights uploaded).
    const ConvPath conv_path = conv_gemm ? ConvPath::automatic : ConvPath::im2col;
    m.copy = std::make_shared<CopyNode>();
    for (std::size_t k = 0; k < d.nodes.size(); ++k) {
        const GraphNodeDesc& n = d.nodes[k];
        const GraphNodeWeights& w = weights[k];
        const int cin = channels[n.inputs[0]], cout = n.out_channels;
        std::shared_ptr<Op> op;
        try {
            if (n.op == "conv2d" || n.op == "conv_transpose2d" || n.op == "dense") {
                ChannelAffine affine;
                if (w.b) affine.shift = w.b->data;
                ConvSpec spec{cin, cout, {1, 1, 1, 0}, node_activation(n.fields, "input_activation"),
                              node_activation(n.fields, "activation")};
                if (n.op != "dense")
                    spec.geom = {n.fields["kernel"][0].get<int>(), n.fields["kernel"][1].get<int>(),
                                 n.fields["stride"].get<int>(), n.fields["pad"].get<int>()};
                if (n.op == "conv_transpose2d")
                    op = std::make_shared<ConvTransposeNode>(ctx, gemm, spec, w.w->data.data(), affine, conv_path, conv_gemm);
                else
                    op = std::make_shared<ConvNode>(ctx, gemm, spec, w.w->data.data(), affine, conv_path, conv_gemm);
                m.weight_bytes += (w.w->data.size() + (w.b ? w.b->data.size() : 0)) * sizeof(float);
            } else if (n.op == "activation") {
                op = std::make_shared<ActivationNode>(ctx, node_activation(n.fields, "activation"));
            } else if (n.op == "affine") {
                op = std::make_shared<AffineNode>(ctx, w.scale ? w.scale->data : std::vector<float>(cin, 1.0f),
                                                  w.shift ? w.shift->data : std::vector<float>(cin, 0.0f));
                m.weight_bytes += 2 * std::size_t(cin) * sizeof(float);
            } else if (n.op == "add" || n.op == "mul") {
                if (n.fields.value("broadcast", false))
                    op = std::make_shared<BroadcastNode>(ctx, n.op == "mul", cin);
                else
                    op = std::make_shared<BinaryNode>(ctx, n.op == "mul");
            } else if (n.op == "max_pool2d") {
                const nlohmann::json& f = n.fields;
                op = std::make_shared<MaxPoolNode>(
                    ctx, MaxPoolGeometry{f["kernel"][0].get<int>(), f["kernel"][1].get<int>(), f["stride"][0].get<int>(),
                                         f["stride"][1].get<int>(), f["pads"][0].get<int>(), f["pads"][1].get<int>(),
                                         f["pads"][2].get<int>(), f["pads"][3].get<int>()});
            } else if (n.op == "global_avg_pool") {
                op = std::make_shared<GlobalAvgPoolNode>(ctx);
            } else if (n.op == "pad2d") {
                const nlohmann::json& f = n.fields;
                const std::string mode = f["mode"].get<std::string>();
                op = std::make_shared<PadNode>(
                    ctx, PadGeometry{f["pads"][0].get<int>(), f["pads"][1].get<int>(), f["pads"][2].get<int>(),
                                     f["pads"][3].get<int>(),
                                     mode == "reflect" ? PadMode::Reflect : mode == "edge" ? PadMode::Edge : PadMode::Constant,
                                     f.value("value", 0.0f)});
            } else if (n.op == "resize_bilinear") {
                const nlohmann::json& f = n.fields;
                const std::string c = f["coordinate"].get<std::string>();
                const ResizeCoord mode = c == "half_pixel"           ? ResizeCoord::HalfPixel
                                         : c == "pytorch_half_pixel" ? ResizeCoord::PytorchHalfPixel
                                         : c == "align_corners"      ? ResizeCoord::AlignCorners
                                                                     : ResizeCoord::Asymmetric;
                if (f.contains("sizes"))
                    op = std::make_shared<ResizeNode>(ctx, f["sizes"][0].get<int>(), f["sizes"][1].get<int>(), mode);
                else
                    op = std::make_shared<ResizeNode>(ctx, f["scales"][0].get<float>(), f["scales"][1].get<float>(),
                                                      mode);
            } else if (n.op == "group_norm") {
                const int groups = n.fields["groups"].get<int>();
                op = std::make_shared<GroupNormNode>(ctx, cin, groups, w.scale->data, w.shift->data,
                                                     n.fields["eps"].get<float>());
                m.weight_bytes += 2 * std::size_t(groups) * sizeof(float);
            } else if (n.op == "instance_norm") {
                op = std::make_shared<BatchNormNode>(ctx, cin, w.scale->data, w.shift->data,
                                                     n.fields["eps"].get<float>(), Act::none());
                m.weight_bytes += 2 * std::size_t(cin) * sizeof(float);
            } else if (n.op == "frequency_encode") {
                ModelConfig e;
                parse_encoding_fields(n.fields, e, "");
                op = std::make_shared<FrequencyEncodeNode>(ctx, cin, frequency_encoding(e));
            } else if (n.op == "nan_to_num") {
                op = std::make_shared<NanToNumNode>(ctx);
            }  // concat: no op
        } catch (const InputError& e) {
            throw InputError("load model: node '" + n.name + "' (" + n.op + "): " + e.what());
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
        if (n.op == "concat") {
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
        t[k + 1] = g->add(m.ops[k], in, n.name);
    }
    g->set_output(t[d.output]);
    return g;
}

}  // namespace ngi::detail

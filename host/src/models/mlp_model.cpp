#include "models/mlp_model.hpp"

#include <set>

namespace ngi::detail {

namespace {

Act activation_of(const ModelConfig::Mlp::Layer& l) {
    if (l.activation == "none") return Act::none();
    if (l.activation == "relu") return Act::relu();
    if (l.activation == "leaky_relu") return Act::leaky(l.slope);
    if (l.activation == "tanh") return Act::tanh();
    if (l.activation == "sigmoid") return Act::sigmoid();
    if (l.activation == "exp") return Act::exp();
    throw InputError("mlp: unknown activation '" + l.activation + "'");  // the front-end's parser already refused it
}

}  // namespace

void parse_encoding_fields(const nlohmann::json& j, ModelConfig::Encoding& c, const std::string& what) {
    auto fail = [&](const std::string& key, const std::string& rule) {
        return InputError(what + "field '" + key + "' must be " + rule);
    };
    if (j.contains("encoding")) {
        const nlohmann::json& e = j["encoding"];
        if (!e.is_object()) throw fail("encoding", "an object");
        auto integer = [&](const char* k, int lo, int hi, int fallback) {
            if (!e.contains(k)) return fallback;
            if (!e[k].is_number_integer() || e[k].get<long long>() < lo || e[k].get<long long>() > hi)
                throw fail(std::string("encoding.") + k, "an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
            return e[k].get<int>();
        };
        auto boolean = [&](const char* k, bool fallback) {
            if (!e.contains(k)) return fallback;
            if (!e[k].is_boolean()) throw fail(std::string("encoding.") + k, "true or false");
            return e[k].get<bool>();
        };
        c.bands = integer("bands", 0, 24, 0);
        c.first_exponent = integer("first_exponent", -32, 31, 0);
        if (c.first_exponent + c.bands > 32)
            throw fail("encoding.first_exponent", "such that the last band's exponent is at most 31");
        c.pi = boolean("pi", true);
        c.include_input = boolean("include_input", true);
        if (e.contains("order")) {
            if (!e["order"].is_string() || (e["order"] != "band" && e["order"] != "component"))
                throw fail("encoding.order", "\"band\" | \"component\"");
            c.order = e["order"].get<std::string>();
        }
    }
}

FrequencyEncoding frequency_encoding(const ModelConfig::Encoding& c) {
    FrequencyEncoding e;
    e.bands = c.bands;
    e.first_exponent = c.first_exponent;
    e.pi = c.pi;
    e.include_input = c.include_input;
    e.order = c.order == "component" ? FrequencyEncoding::Order::ComponentMajor
                                               : FrequencyEncoding::Order::BandMajor;
    return e;
}

MlpSpec mlp_spec(const ModelConfig& c, const SafetensorsFile& file, const std::string& path) {
    MlpSpec s;
    s.inputs = c.input_nc;
    s.encoding = frequency_encoding(c.encoding);
    int in = s.encoding.width(s.inputs);
    std::set<std::string> used;
    const std::vector<ModelConfig::Mlp::Layer>& layers = c.mlp.layers;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        DenseSpec d;
        d.in = in;
        d.out = layers[i].out;
        d.act = activation_of(layers[i]);
        const std::string wname = "layers." + std::to_string(i) + ".weight", bname = "layers." + std::to_string(i) + ".bias";
        auto w = file.tensors.find(wname);
        if (w == file.tensors.end()) throw InputError("load model " + path + ": tensor '" + wname + "' is missing");
        if (w->second.shape != std::vector<int>{d.out, d.in})
            throw InputError("load model " + path + ": tensor '" + wname + "' is " + shape_string(w->second.shape) +
                             ", expected [" + std::to_string(d.out) + ", " + std::to_string(d.in) + "]");
        d.weight = w->second.data;
        used.insert(wname);
        if (auto b = file.tensors.find(bname); b != file.tensors.end()) {
            if (b->second.shape != std::vector<int>{d.out})
                throw InputError("load model " + path + ": tensor '" + bname + "' is " + shape_string(b->second.shape) +
                                 ", expected [" + std::to_string(d.out) + "]");
            d.bias = b->second.data;
            used.insert(bname);
        }
        s.layers.push_back(std::move(d));
        in = layers[i].out;
    }
    for (const auto& [name, t] : file.tensors)
        if (!used.count(name))
            throw InputError("load model " + path + ": tensor '" + name + "' is not part of this mlp (" +
                             std::to_string(layers.size()) + " layers)");
    s.validate(("load model " + path).c_str());
    return s;
}

MlpRunner::MlpRunner(Context& ctx, const MlpSpec& spec, const GemmParams& gemm, const std::string& path, float lo,
                     float hi)
    : spec_(spec), guard_(ctx), lo_(lo), hi_(hi) {
    if (path != "" && path != "fused" && path != "dense")
        throw InputError("mlp: path '" + path + "' is not one of fused, dense");
    int widest = spec.encoding.width(spec.inputs);
    for (const DenseSpec& d : spec.layers) widest = std::max(widest, d.out);
    bool slopes_agree = true;
    float slope = 0;
    bool seen = false;
    for (const DenseSpec& d : spec.layers)
        if (d.act.kind == Activation::LeakyReLU) {
            if (seen && d.act.alpha != slope) slopes_agree = false;
            slope = d.act.alpha;
            seen = true;
        }
    const bool fits = widest <= kFusedMlpMaxWidth && slopes_agree && FusedMlp::fits_device(ctx, spec);
    if (path == "fused" && !fits)
        throw InputError("mlp: the fused path was asked for, but the network (" + std::to_string(widest) +
                         " wide) does not fit it on this device");
    if (path != "dense" && fits) fused_ = std::make_unique<FusedMlp>(ctx, spec);
    else dense_ = std::make_unique<DenseMlp>(ctx, gemm, spec);
    for (const DenseSpec& d : spec.layers) weight_bytes_ += (d.weight.size() + d.bias.size()) * sizeof(float);
}

void MlpRunner::enqueue(Context& ctx, cl_mem in, cl_mem out, int n) {
    const std::size_t in_bytes = std::size_t(spec_.inputs) * n * sizeof(float);
    ensure_buffer(ctx, in_, in_bytes, "mlp input");
    ctx.copy(in, 0, in_.get(), 0, in_bytes, "mlp input");
    guard_.sanitize(ctx, View{in_.get(), 0, Shape{spec_.inputs, 1, n}}, lo_, hi_);
    const int out_c = spec_.layers.back().out;
    if (fused_) {
        fused_->enqueue(ctx, in_.get(), 0, ItemLayout::planar(n), n, out, 0, ItemLayout::planar(n));
    } else {
        ensure_buffer(ctx, scratch_, dense_->scratch_floats(n) * sizeof(float), "mlp scratch");
        dense_->enqueue(ctx, View{in_.get(), 0, Shape{spec_.inputs, 1, n}}, View{out, 0, Shape{out_c, 1, n}},
                        scratch_.get());
    }
}

Tensor MlpRunner::run(Context& ctx, const Tensor& x, RunInfo* info) {
    const auto& s = x.shape;
    const bool image = s.size() == 4 && s[0] == 1 && s[1] == spec_.inputs;
    const bool points = s.size() == 2 && s[1] == spec_.inputs;
    if (!image && !points)
        throw InputError("run model: input tensor is " + shape_string(s) + ", an mlp takes [1, " +
                         std::to_string(spec_.inputs) + ", H, W] (per pixel) or [N, " + std::to_string(spec_.inputs) +
                         "] (points)");
    if (x.data.size() != Tensor::element_count(s))
        throw InputError("run model: input tensor has " + std::to_string(x.data.size()) + " values for shape " +
                         shape_string(s));
    const std::size_t items = image ? std::size_t(s[2]) * s[3] : std::size_t(s[0]);
    if (items == 0 || items > std::size_t(1) << 30)
        throw InputError("run model: " + std::to_string(items) + " items (1 .. 2^30)");
    const int n = int(items), out_c = spec_.layers.back().out;
    Tensor y(image ? std::vector<int>{1, out_c, s[2], s[3]} : std::vector<int>{n, out_c});
    // Planar on the device ([C, n]); a point list is transposed on the host on the way in and out.
    std::vector<float> planar;
    const float* src = x.data.data();
    if (points) {
        planar.resize(x.data.size());
        for (int i = 0; i < n; ++i)
            for (int c = 0; c < spec_.inputs; ++c) planar[std::size_t(c) * n + i] = x.data[std::size_t(i) * spec_.inputs + c];
        src = planar.data();
    }
    const std::size_t in_bytes = std::size_t(spec_.inputs) * n * sizeof(float), out_bytes = std::size_t(out_c) * n * sizeof(float);
    ensure_buffer(ctx, in_, in_bytes, "mlp input");
    ensure_buffer(ctx, out_, out_bytes, "mlp output");
    ctx.write(in_, 0, in_bytes, src, "mlp input");
    guard_.sanitize(ctx, View{in_.get(), 0, Shape{spec_.inputs, 1, n}}, lo_, hi_);
    if (fused_) {
        fused_->enqueue(ctx, in_.get(), 0, ItemLayout::planar(n), n, out_.get(), 0, ItemLayout::planar(n));
    } else {
        ensure_buffer(ctx, scratch_, dense_->scratch_floats(n) * sizeof(float), "mlp scratch");
        dense_->enqueue(ctx, View{in_.get(), 0, Shape{spec_.inputs, 1, n}}, View{out_.get(), 0, Shape{out_c, 1, n}},
                        scratch_.get());
    }
    if (points) {
        std::vector<float> p(y.data.size());
        ctx.read(out_, 0, out_bytes, p.data(), "mlp output");
        for (int i = 0; i < n; ++i)
            for (int c = 0; c < out_c; ++c) y.data[std::size_t(i) * out_c + c] = p[std::size_t(c) * n + i];
    } else {
        ctx.read(out_, 0, out_bytes, y.data.data(), "mlp output");
    }
    if (info) {
        info->sanitized_inputs = guard_.sanitized_count(ctx);
        info->layers.clear();
        info->weight_bytes = weight_bytes_;
        info->scratch_bytes = scratch_.bytes();
        info->arena_bytes = in_.bytes() + out_.bytes();
        info->naive_bytes = info->arena_bytes;
    }
    return y;
}

}  // namespace ngi::detail

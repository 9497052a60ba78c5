#include "models/unet.hpp"

#include <algorithm>
#include <cmath>

#include "graph/nodes.hpp"

namespace ngi::detail {

namespace {

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

// junyanz UnetGenerator: level i's nn.Sequential is model.model, then .1.model, then .3.model for each deeper level.
std::string pix2pix_seq(int level) {
    std::string s = "model.model";
    if (level >= 1) s += ".1.model";
    for (int i = 2; i <= level; ++i) s += ".3.model";
    return s;
}

UNetSpec pix2pix_spec(const ModelConfig& c) {
    const int D = c.unet.num_downs;
    UNetSpec spec;
    spec.levels.resize(D);
    for (int i = 0; i < D; ++i) {
        LevelSpec& l = spec.levels[i];
        l.in_c = i == 0 ? c.input_nc : spec.levels[i - 1].inner_c;
        l.inner_c = c.unet.ngf * std::min(1 << std::min(i, 3), 8);
        const std::string s = pix2pix_seq(i) + ".";
        if (i == 0) {  // outermost: [downconv, submodule, uprelu, upconv(bias), tanh]
            l.down_w = s + "0.weight";
            l.up_w = s + "3.weight";
            l.up_b = s + "3.bias";
            l.up_in = 2 * l.inner_c;
            l.up_out = c.output_nc;
        } else if (i == D - 1) {  // innermost: [downrelu, downconv, uprelu, upconv, upnorm]
            l.down_w = s + "1.weight";
            l.up_w = s + "3.weight";
            l.up_bn = s + "4";
            l.up_in = l.inner_c;
            l.up_out = l.in_c;
        } else {  // middle: [downrelu, downconv, downnorm, submodule, uprelu, upconv, upnorm, (dropout)]
            l.down_w = s + "1.weight";
            l.down_bn = s + "2";
            l.up_w = s + "5.weight";
            l.up_bn = s + "6";
            l.up_in = 2 * l.inner_c;
            l.up_out = l.in_c;
            l.dropout = i >= 4;  // the num_downs-5 blocks built in UnetGenerator's loop
        }
    }
    return spec;
}

UNetSpec deepillumination_spec(const ModelConfig& c) {
    // conv{i+1} / deconv{8-i} at level i; batch_norm{,2,4,8} modules shared by several layers.
    const char* down_bn[8] = {"", "batch_norm2", "batch_norm4", "batch_norm8", "batch_norm8", "batch_norm8", "batch_norm8", ""};
    const char* up_bn[8] = {"", "batch_norm", "batch_norm2", "batch_norm4", "batch_norm8", "batch_norm8", "batch_norm8", "batch_norm8"};
    UNetSpec spec;
    spec.decoder_first = true;
    spec.levels.resize(8);
    for (int i = 0; i < 8; ++i) {
        LevelSpec& l = spec.levels[i];
        l.in_c = i == 0 ? c.input_nc : spec.levels[i - 1].inner_c;
        l.inner_c = c.unet.ngf * std::min(1 << std::min(i, 3), 8);
        l.down_w = "conv" + std::to_string(i + 1) + ".weight";
        l.down_b = "conv" + std::to_string(i + 1) + ".bias";
        l.down_bn = down_bn[i];
        l.up_w = "deconv" + std::to_string(8 - i) + ".weight";
        l.up_b = "deconv" + std::to_string(8 - i) + ".bias";
        l.up_bn = up_bn[i];
        l.up_in = i == 7 ? l.inner_c : 2 * l.inner_c;
        l.up_out = i == 0 ? c.output_nc : l.in_c;
        l.dropout = i >= 5;  // decoders 1-3
    }
    return spec;
}

const StoredTensor& get(const SafetensorsFile& f, const std::string& key) { return f.tensors.at(key); }

// Running-statistics batch norm (+ conv bias) folded into the epilogue's per-channel affine.
ChannelAffine fold(const SafetensorsFile& f, const std::string& bias, const std::string& bn, int channels,
                   float eps, bool use_bn_stats) {
    ChannelAffine a{std::vector<float>(channels, 1.0f), std::vector<float>(channels, 0.0f)};
    if (!bias.empty()) a.shift = get(f, bias).data;
    if (!bn.empty() && use_bn_stats) {
        const auto& g = get(f, bn + ".weight").data;
        const auto& b = get(f, bn + ".bias").data;
        const auto& m = get(f, bn + ".running_mean").data;
        const auto& v = get(f, bn + ".running_var").data;
        for (int c = 0; c < channels; ++c) {
            const float s = float(double(g[c]) / std::sqrt(double(v[c]) + eps));
            a.shift[c] = float(double(b[c]) + (double(a.shift[c]) - m[c]) * s);
            a.scale[c] = s;
            // A negative running variance gives sqrt(< 0) = NaN, a tiny one a scale beyond float: either would
            // turn every output of the layer into NaN or Inf without a word.
            if (!(double(v[c]) + eps > 0.0) || !std::isfinite(a.scale[c]) || !std::isfinite(a.shift[c]))
                throw InputError("load model: tensor '" + bn + ".running_var' channel " + std::to_string(c) + " is " +
                                 std::to_string(v[c]) + ": batch norm's folded scale " + bn + ".weight / sqrt(var + " +
                                 "bn_eps) and shift are not finite in float32");
        }
    }
    return a;
}

}  // namespace

UNetSpec unet_spec(const ModelConfig& cfg) {
    return cfg.family == "deepillumination" ? deepillumination_spec(cfg) : pix2pix_spec(cfg);
}

std::vector<std::pair<std::string, std::vector<int>>> expected_tensors(const UNetSpec& spec) {
    std::vector<std::pair<std::string, std::vector<int>>> out;
    auto add = [&](const std::string& k, std::vector<int> s) {
        for (const auto& [name, shape] : out) if (name == k) return;  // shared BN modules appear once
        out.emplace_back(k, std::move(s));
    };
    auto bn = [&](const std::string& p, int c) {
        for (const char* f : {".weight", ".bias", ".running_mean", ".running_var"}) add(p + f, {c});
    };
    for (const LevelSpec& l : spec.levels) {
        add(l.down_w, {l.inner_c, l.in_c, 4, 4});
        if (!l.down_b.empty()) add(l.down_b, {l.inner_c});
        if (!l.down_bn.empty()) bn(l.down_bn, l.inner_c);
        add(l.up_w, {l.up_in, l.up_out, 4, 4});
        if (!l.up_b.empty()) add(l.up_b, {l.up_out});
        if (!l.up_bn.empty()) bn(l.up_bn, l.up_out);
    }
    return out;
}

std::string tensor_mismatches(const std::vector<std::pair<std::string, std::vector<int>>>& expected,
                              const SafetensorsFile& file, const std::function<bool(const std::string&)>& other) {
    std::vector<std::string> missing, unexpected, misshaped;
    for (const auto& [name, shape] : expected) {
        auto it = file.tensors.find(name);
        if (it == file.tensors.end()) missing.push_back(name);
        else if (it->second.shape != shape)
            misshaped.push_back(name + " is " + shape_string(it->second.shape) + ", expected " + shape_string(shape));
    }
    for (const auto& [name, t] : file.tensors) {
        bool known = other && other(name);
        for (const auto& e : expected) known = known || e.first == name;
        if (!known) unexpected.push_back(name);
    }
    std::string problems;
    if (!missing.empty()) problems += "\n  missing tensors: " + join(missing);
    if (!unexpected.empty()) problems += "\n  unexpected tensors: " + join(unexpected);
    if (!misshaped.empty()) problems += "\n  shape mismatch: " + join(misshaped);
    return problems;
}

void validate_unet_tensors(const ModelConfig& cfg, const SafetensorsFile& file) {
    const std::string problems = tensor_mismatches(expected_tensors(unet_spec(cfg)), file);
    if (!problems.empty())
        throw InputError("load model: the tensors do not match a " + cfg.family + " generator with input_nc " +
                         std::to_string(cfg.input_nc) + ", output_nc " + std::to_string(cfg.output_nc) + ", ngf " +
                         std::to_string(cfg.unet.ngf) + ", num_downs " + std::to_string(cfg.unet.num_downs) + ":" +
                         problems);
    if (cfg.unet.bn_mode != "running" && cfg.unet.bn_mode != "per_image")
        throw InputError("load model: bn_mode '" + cfg.unet.bn_mode + "' is not running or per_image");
    if (cfg.unet.dropout != "off" && cfg.unet.dropout != "seeded")
        throw InputError("load model: dropout '" + cfg.unet.dropout + "' is not off or seeded");
}

UNetOps build_unet_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file, const GemmParams& gemm,
                       const std::optional<GemmParams>& conv_gemm, Act outer_act) {
    const ConvPath conv_path = conv_gemm ? ConvPath::automatic : ConvPath::im2col;
    validate_unet_tensors(cfg, file);  // names, shapes and modes, before touching the device
    const UNetSpec spec = unet_spec(cfg);
    const bool running = cfg.unet.bn_mode == "running";
    const int D = int(spec.levels.size());
    const Act leaky = Act::leaky(cfg.unet.leaky_slope);
    UNetOps ops;
    ops.decoder_first = spec.decoder_first;
    ops.input_nc = cfg.input_nc;
    ops.levels.resize(D);
    std::uint32_t dropout_site = 0;
    auto per_image_bn = [&](const std::string& bn, int channels, Act act) -> std::shared_ptr<Op> {
        if (bn.empty() || running) return nullptr;
        return std::make_shared<BatchNormNode>(ctx, channels, get(file, bn + ".weight").data,
                                               get(file, bn + ".bias").data, cfg.unet.bn_eps, act);
    };
    for (int i = 0; i < D; ++i) {
        const LevelSpec& l = spec.levels[i];
        UNetOps::Level& o = ops.levels[i];
        // Every consumer of a down output applies LeakyReLU in place first (innermost: ReLU), so the producer
        // writes the activated value; that is also what the skip carries (pix2pix's in-place quirk).
        const Act down_act = i < D - 1 ? leaky : Act::relu();
        const bool down_has_bn = !l.down_bn.empty() && !running;
        o.down = std::make_shared<ConvNode>(
            ctx, gemm, ConvSpec{l.in_c, l.inner_c, {4, 4, 2, 1}, Act::none(), down_has_bn ? Act::none() : down_act},
            get(file, l.down_w).data.data(), fold(file, l.down_b, l.down_bn, l.inner_c, cfg.unet.bn_eps, running),
            conv_path, conv_gemm);
        o.down_bn = per_image_bn(l.down_bn, l.inner_c, down_act);
        const Act up_in = i == D - 1 ? Act::none() : Act::relu();  // innermost input is already ReLU'd
        const Act up_act = i == 0 ? outer_act : Act::none();
        o.up = std::make_shared<ConvTransposeNode>(
            ctx, gemm, ConvSpec{l.up_in, l.up_out, {4, 4, 2, 1}, up_in, up_act}, get(file, l.up_w).data.data(),
            fold(file, l.up_b, l.up_bn, l.up_out, cfg.unet.bn_eps, running), conv_path, conv_gemm);
        o.up_bn = per_image_bn(l.up_bn, l.up_out, Act::none());
        ops.weight_bytes += (get(file, l.down_w).data.size() + get(file, l.up_w).data.size()) * sizeof(float);
    }
    // Dropout sites are numbered in execution order: the up path runs from the innermost level outwards.
    for (int i = D - 1; i >= 0; --i)
        if (spec.levels[i].dropout && cfg.unet.dropout == "seeded")
            ops.levels[i].dropout =
                std::make_shared<DropoutNode>(ctx, cfg.unet.dropout_seed, dropout_site++, cfg.unet.dropout_p);
    return ops;
}

TensorId add_unet(Graph& g, const UNetOps& ops, TensorId x, const std::string& prefix) {
    const int D = int(ops.levels.size());
    const Shape in = g.shape(x);
    if (in.h % (1 << D) != 0 || in.w % (1 << D) != 0)
        throw InputError("run model: input " + std::to_string(in.h) + "x" + std::to_string(in.w) +
                         " (HxW) must be a multiple of 2^num_downs = " + std::to_string(1 << D) +
                         " in both dimensions so the skip connections line up");
    std::vector<TensorId> down(D);
    for (int i = 0; i < D; ++i) {
        const std::string n = prefix + "level" + std::to_string(i) + ".down";
        down[i] = g.add(ops.levels[i].down, {i == 0 ? x : down[i - 1]}, n + ".conv");
        if (ops.levels[i].down_bn) down[i] = g.add(ops.levels[i].down_bn, {down[i]}, n + ".bn");
    }
    TensorId up_input = down[D - 1];
    for (int i = D - 1; i >= 0; --i) {
        const std::string n = prefix + "level" + std::to_string(i) + ".up";
        TensorId u = g.add(ops.levels[i].up, {up_input}, n + ".convT");
        if (ops.levels[i].up_bn) u = g.add(ops.levels[i].up_bn, {u}, n + ".bn");
        if (ops.levels[i].dropout) u = g.add(ops.levels[i].dropout, {u}, n + ".dropout");
        if (i == 0) return u;
        up_input = ops.decoder_first ? g.concat({u, down[i - 1]}, n + ".cat") : g.concat({down[i - 1], u}, n + ".cat");
    }
    return up_input;  // not reached: level 0 returns
}

std::unique_ptr<Graph> build_unet_graph(const UNetOps& ops, int height, int width) {
    auto g = std::make_unique<Graph>();
    const TensorId x = g->input({ops.input_nc, height, width}, "input");
    g->set_output(add_unet(*g, ops, x));
    return g;
}

}  // namespace ngi::detail

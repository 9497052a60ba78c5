// Model configs (__metadata__["ngi"], docs/MODEL_FORMAT.md) of every family, and what each family's loader does
// with an accepted config before it needs an OpenCL device. The first input byte picks the family (modulo 7:
// pix2pix_unet, deepillumination, mlp, neural_gi, voxel_sh, graph, or 6 = the "family" key as written, which is how
// family ssgi is reached: its seeds are the shipped ssgi models' configs); the rest is
// the config's JSON text. For a family other than "as written", a text that parses as a JSON object gets that
// family as its "family" key (re-serialized; a text whose "family" already matches is passed unchanged, so the
// duplicate-key and number-format paths stay reachable), so that mutations explore one family's fields instead of
// the family check. fuzz_safetensors covers the container and the pix2pix tensors; this target covers configs.
//
// After parse_model_config accepts a config, the target runs the family's device-free next step and checks what
// the loader relies on:
//   pix2pix_unet, deepillumination: the tensors the config implies (unet_spec, expected_tensors): every shape
//       positive; a file holding exactly those shapes passes validate_unet_tensors;
//   neural_gi: validate_neural_gi_tensors refuses a file without tensors (InputError);
//   mlp: a file with the layer shapes docs/MODEL_FORMAT.md gives ([out, in], the first `in` the encoded width)
//       passes mlp_spec, and its layers chain;
//   voxel_sh: the widths and grid within their ranges;
//   graph: the node list as build_graph_model_ops re-reads it (parse_graph_desc) agrees with the config (output
//       channels, inputs made before use); a file with the weight shapes of docs/MODEL_FORMAT.md's op table passes
//       check_graph_weights, unless two nodes name one tensor with different shapes (then an InputError); the
//       loader's fusion of it throws nothing and leaves a list of nodes reading only earlier tensors;
//   any other family (reached "as written"): the registry knows it (models/family.hpp).
// Only ngi::Error may come out for bad input (fuzz_common.hpp); a failed check is a crash.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fuzz_common.hpp"
#include "models/config_fields.hpp"
#include "models/family.hpp"
#include "models/graph_fuse.hpp"
#include "models/graph_model.hpp"
#include "models/mlp_model.hpp"
#include "models/neural_gi_model.hpp"
#include "models/safetensors.hpp"
#include "models/ssgi_config.hpp"
#include "models/unet.hpp"
#include "models/voxel_sh_model.hpp"

namespace {

const char* const kFamilies[] = {"pix2pix_unet", "deepillumination", "mlp", "neural_gi", "voxel_sh", "graph"};

ngi::detail::StoredTensor shaped(std::vector<int> shape) {  // shape only: the checks below read no values
    ngi::detail::StoredTensor t;
    t.shape = std::move(shape);
    t.dtype = "F32";
    return t;
}

bool finite_range(const float r[2]) { return std::isfinite(r[0]) && std::isfinite(r[1]) && r[0] < r[1]; }

void check_graph(const ngi::ModelConfig& cfg) {
    using namespace ngi::detail;
    const GraphDesc d = parse_graph_desc(nlohmann::json::parse(cfg.json), "fuzz: ");
    if (d.nodes.empty() || d.output < 1 || std::size_t(d.output) > d.nodes.size()) __builtin_trap();
    if (d.nodes[std::size_t(d.output) - 1].out_channels != cfg.output_nc || d.input_nc != cfg.input_nc) __builtin_trap();
    std::vector<int> channels = {d.input_nc};
    for (std::size_t k = 0; k < d.nodes.size(); ++k) {
        const GraphNodeDesc& n = d.nodes[k];
        if (n.inputs.empty() || n.out_channels < 1 || n.out_channels > kMaxChannels) __builtin_trap();
        for (int i : n.inputs)
            if (i < 0 || std::size_t(i) > k) __builtin_trap();  // made before it is read: no cycle
        channels.push_back(n.out_channels);
    }
    // The weights docs/MODEL_FORMAT.md's op table gives each node.
    SafetensorsFile file;
    bool clash = false;
    auto want = [&](const GraphNodeDesc& n, const char* key, std::vector<int> shape) {
        if (!n.fields.contains(key)) return;
        const std::string name = n.fields[key].get<std::string>();
        const auto it = file.tensors.find(name);
        if (it != file.tensors.end()) clash |= it->second.shape != shape;
        else file.tensors[name] = shaped(std::move(shape));
    };
    for (const GraphNodeDesc& n : d.nodes) {
        const int cin = channels[std::size_t(n.inputs[0])], cout = n.out_channels;
        if (n.op == "conv2d" || n.op == "conv_transpose2d") {
            const int kh = n.fields["kernel"][0].get<int>(), kw = n.fields["kernel"][1].get<int>();
            want(n, "weight", n.op == "conv2d" ? std::vector<int>{cout, cin, kh, kw} : std::vector<int>{cin, cout, kh, kw});
            want(n, "bias", {cout});
        } else if (n.op == "dense") {
            want(n, "weight", {cout, cin});
            want(n, "bias", {cout});
        } else if (n.op == "affine" || n.op == "instance_norm") {
            want(n, "scale", {cin});
            want(n, "shift", {cin});
        } else if (n.op == "group_norm") {
            want(n, "scale", {n.fields["groups"].get<int>()});
            want(n, "shift", {n.fields["groups"].get<int>()});
        }
    }
    std::vector<GraphNodeWeights> w;
    try {
        w = check_graph_weights(d, file);
        if (clash || w.size() != d.nodes.size()) __builtin_trap();
    } catch (const ngi::Error&) {
        if (!clash) __builtin_trap();  // the documented shapes were refused
        return;
    }
    // The loader's fusion (graph_fuse.hpp) on weights of value 1 (bounded: a few million values in all): it throws
    // nothing, removes one node a fold, and leaves a list every node of which reads only earlier tensors, ending in
    // the output's channels.
    std::size_t values = 0;
    for (const auto& [name, t] : file.tensors) {
        std::size_t n = 1;
        for (int s : t.shape) n *= std::size_t(s);
        values += n;
        if (values > (std::size_t(1) << 22)) return;
    }
    for (auto& [name, t] : file.tensors) {
        std::size_t n = 1;
        for (int s : t.shape) n *= std::size_t(s);
        t.data.assign(n, 1.0f);
    }
    FusedGraph f;
    try {
        f = fuse_graph(d, check_graph_weights(d, file));
    } catch (...) {
        __builtin_trap();  // a checked list and its weights: nothing to refuse
    }
    if (f.desc.nodes.size() + std::size_t(f.affines + f.activations + f.input_activations) != d.nodes.size())
        __builtin_trap();
    if (f.desc.output < 1 || std::size_t(f.desc.output) > f.desc.nodes.size() ||
        f.desc.nodes[std::size_t(f.desc.output) - 1].out_channels != cfg.output_nc)
        __builtin_trap();
    for (std::size_t k = 0; k < f.desc.nodes.size(); ++k)
        for (int i : f.desc.nodes[k].inputs)
            if (i < 0 || std::size_t(i) > k) __builtin_trap();
}

void check_mlp(const ngi::ModelConfig& cfg) {
    using namespace ngi::detail;
    if (cfg.mlp.layers.empty() || cfg.output_nc != cfg.mlp.layers.back().out) __builtin_trap();
    SafetensorsFile file;
    int in = frequency_encoding(cfg.encoding).width(cfg.input_nc);
    if (in < 1) __builtin_trap();
    for (std::size_t i = 0; i < cfg.mlp.layers.size(); ++i) {
        file.tensors["layers." + std::to_string(i) + ".weight"] = shaped({cfg.mlp.layers[i].out, in});
        file.tensors["layers." + std::to_string(i) + ".bias"] = shaped({cfg.mlp.layers[i].out});
        in = cfg.mlp.layers[i].out;
    }
    const MlpSpec s = mlp_spec(cfg, file, "fuzz.safetensors");  // must accept the documented shapes
    if (s.layers.size() != cfg.mlp.layers.size()) __builtin_trap();
    for (std::size_t i = 1; i < s.layers.size(); ++i)
        if (s.layers[i].in != s.layers[i - 1].out) __builtin_trap();
}

void check_unet(const ngi::ModelConfig& cfg) {
    using namespace ngi::detail;
    const auto expected = expected_tensors(unet_spec(cfg));
    if (expected.empty()) __builtin_trap();
    SafetensorsFile file;
    for (const auto& [name, shape] : expected) {
        for (int d : shape)
            if (d < 1) __builtin_trap();
        file.tensors[name] = shaped(shape);
    }
    validate_unet_tensors(cfg, file);  // the implied tensors satisfy the config
}

void check_voxel_sh(const ngi::ModelConfig& cfg) {
    const auto& v = cfg.voxel_sh;
    for (int g : v.grid)
        if (g < 1) __builtin_trap();
    if (v.input_lo.size() != 10 || v.input_hi.size() != 10 || v.output_mean.size() != 27 || v.output_std.size() != 27)
        __builtin_trap();
    for (const auto* w : {&v.hidden, &v.phi, &v.rho})
        for (int x : *w)
            if (x < 1) __builtin_trap();
}

// Family ssgi: what the pipeline's gather relies on (pipeline/ssgi.cpp): a known view, a cluster level and bounce
// count within their bounds, finite non-negative distances, visibility samples within theirs, 3 output channels of indirect light and no network input.
void check_ssgi(const ngi::ModelConfig& cfg) {
    const ngi::ModelConfig::Ssgi& s = cfg.ssgi;
    if ((s.view != "surround" && s.view != "front") || s.cluster_level < 0 ||
        s.cluster_level > ngi::detail::kSsgiMaxClusterLevel || s.bounces < 1 || s.bounces > ngi::detail::kSsgiMaxBounces ||
        !std::isfinite(s.near_factor) || s.near_factor < 0 || !std::isfinite(s.min_distance) || s.min_distance < 0 ||
        s.visibility_steps < 0 || s.visibility_steps > ngi::detail::kSsgiMaxVisibilitySteps ||
        !std::isfinite(s.thickness) || s.thickness < 0 ||
        cfg.input_nc != 0 || cfg.output_nc != 3 || cfg.output_mode != "indirect")
        __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const unsigned pick = data[0] % 7u;
    std::string text = ngi::fuzz::bytes(data + 1, size - 1);
    if (pick < 6) {
        try {
            nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
            if (j.is_object() && !(j.contains("family") && j["family"] == kFamilies[pick])) {
                j["family"] = kFamilies[pick];
                text = j.dump();
            }
        } catch (const nlohmann::json::exception&) {
            // not re-serializable (the harness's own step): the text goes in as it is
        }
    }
    return ngi::fuzz::expect_ngi_errors_only([&] {
        const ngi::ModelConfig cfg = ngi::detail::parse_model_config(text, "fuzz.safetensors");
        if (cfg.family == "ssgi") {  // no network (reached "as written" only): the gather's settings in range
            check_ssgi(cfg);
            return;
        }
        if (cfg.input_nc < 1 || cfg.input_nc > ngi::detail::kMaxChannels || cfg.output_nc < 1 ||
            cfg.output_nc > ngi::detail::kMaxChannels || !finite_range(cfg.output_range))
            __builtin_trap();
        // The graph family's default input range is unbounded (+-FLT_MAX, still finite).
        if (!finite_range(cfg.input_range)) __builtin_trap();
        if (cfg.family == "graph") {
            check_graph(cfg);
        } else if (cfg.family == "mlp") {
            check_mlp(cfg);
        } else if (cfg.family == "voxel_sh") {
            check_voxel_sh(cfg);
        } else if (cfg.family == "neural_gi") {
            try {
                ngi::detail::validate_neural_gi_tensors(cfg, ngi::detail::SafetensorsFile{});
            } catch (const ngi::Error&) {
                return;  // a network needs tensors
            }
            __builtin_trap();
        } else if (cfg.family == "pix2pix_unet" || cfg.family == "deepillumination") {
            check_unet(cfg);
        } else if (!ngi::detail::find_model_family(cfg.family)) {
            __builtin_trap();  // parse_model_config returned a family the registry does not know
        }  // a family without checks of its own here (reached "as written"): its parser's acceptance is enough
    });
}

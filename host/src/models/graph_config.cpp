// The node list of a family "graph" file (docs/MODEL_FORMAT.md "graph"): parse_graph_desc, checked as hostile input.
// graph_family.cpp parses the rest of the config, graph_model.cpp checks the weights and builds the graph.
#include "models/graph_model.hpp"

#include <cmath>
#include <map>
#include <set>

#include "models/config_fields.hpp"
#include "models/float_field.hpp"
#include "models/mlp_model.hpp"

namespace ngi::detail {

namespace {

constexpr int kMaxKernel = kMaxGraphKernel, kMaxStride = kMaxGraphStride, kMaxPad = kMaxGraphPad,
              kMaxNameLength = kMaxGraphNameLength;

const std::set<std::string> kActivations = {"none", "relu", "leaky_relu", "tanh", "sigmoid", "exp", "softplus", "erf"};

bool is_name(const nlohmann::json& v) {
    return v.is_string() && !v.get<std::string>().empty() && v.get<std::string>().size() <= kMaxNameLength;
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
    if (!j.contains("input_nc") || !is_integer_in(j["input_nc"], 1, kMaxChannels))
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
        const std::optional<NodeKind> kind = node_kind_from_name(node.op);
        if (!kind) throw bad("op '" + node.op.substr(0, 80) + "' is not one of " + node_kind_list());
        node.kind = *kind;
        // The fields of each kind besides name, op, inputs, output and source.
        static const std::map<NodeKind, std::set<std::string>> kFields = {
            {NodeKind::conv2d,
             {"in", "out", "kernel", "stride", "pad", "weight", "bias", "activation", "input_activation", "slope"}},
            {NodeKind::conv_transpose2d,
             {"in", "out", "kernel", "stride", "pad", "weight", "bias", "activation", "input_activation", "slope"}},
            {NodeKind::dense, {"in", "out", "weight", "bias", "activation", "slope"}},
            {NodeKind::concat, {}},
            {NodeKind::activation, {"activation", "slope"}},
            {NodeKind::affine, {"scale", "shift"}},
            {NodeKind::add, {"broadcast"}},
            {NodeKind::mul, {"broadcast"}},
            {NodeKind::frequency_encode, {"encoding"}},
            {NodeKind::nan_to_num, {}},
            {NodeKind::max_pool2d, {"kernel", "stride", "pads"}},
            {NodeKind::global_avg_pool, {}},
            {NodeKind::instance_norm, {"scale", "shift", "eps"}},
            {NodeKind::group_norm, {"groups", "scale", "shift", "eps"}},
            {NodeKind::pad2d, {"pads", "mode", "value"}},
            {NodeKind::resize_bilinear, {"scales", "sizes", "coordinate"}}};
        const std::set<std::string>& allowed = kFields.at(node.kind);
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
        const std::size_t arity = node.kind == NodeKind::concat                                 ? 0
                                  : node.kind == NodeKind::add || node.kind == NodeKind::mul ? 2
                                                                                             : 1;
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
        if (node.kind == NodeKind::activation && !n.contains("activation")) throw bad("'activation' is missing");
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
            if (!n.contains(key) || !is_integer_in(n[key], lo, hi))
                throw bad(std::string("'") + key + "' must be an integer in " + std::to_string(lo) + ".." +
                          std::to_string(hi));
            return int(n[key].get<long long>());
        };

        if (node.kind == NodeKind::conv2d || node.kind == NodeKind::conv_transpose2d || node.kind == NodeKind::dense) {
            const int in = int_field("in", 1, kMaxChannels);
            node.out_channels = int_field("out", 1, kMaxChannels);
            if (in != cin)
                throw bad("'in' is " + std::to_string(in) + ", its input has " + std::to_string(cin) + " channels");
            tensor_field("weight", true);
            tensor_field("bias", false);
            if (node.kind != NodeKind::dense) {
                const std::string rule = "[kh, kw], integers in 1.." + std::to_string(kMaxKernel);
                if (!n.contains("kernel") || !n["kernel"].is_array() || n["kernel"].size() != 2 ||
                    !is_integer_in(n["kernel"][0], 1, kMaxKernel) || !is_integer_in(n["kernel"][1], 1, kMaxKernel))
                    throw bad("'kernel' must be " + rule);
                const int stride = int_field("stride", 1, kMaxStride), pad = int_field("pad", 0, kMaxPad);
                if (nc && (n["kernel"][0] != 1 || n["kernel"][1] != 1 || stride != 1 || pad != 0))
                    throw bad("layout \"nc\" has no spatial axes: only 1 x 1 kernels, stride 1, pad 0");
            }
        } else if (node.kind == NodeKind::concat) {
            long long c = 0;
            for (int i : node.inputs) c += channels[i];
            if (c > kMaxChannels) throw bad("concatenates " + std::to_string(c) + " channels (at most " +
                                            std::to_string(kMaxChannels) + ")");
            node.out_channels = int(c);
        } else if (node.kind == NodeKind::add || node.kind == NodeKind::mul) {
            if (n.contains("broadcast") && !n["broadcast"].is_boolean()) throw bad("'broadcast' must be true or false");
            if (channels[node.inputs[1]] != cin)
                throw bad("combines " + std::to_string(cin) + " and " + std::to_string(channels[node.inputs[1]]) +
                          " channels (the second input may be one value a channel, 'broadcast', not fewer channels)");
            if (nc && n.value("broadcast", false)) throw bad("layout \"nc\" has no spatial axes to broadcast over");
            node.out_channels = cin;
        } else if (node.kind == NodeKind::max_pool2d) {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pool");
            auto pair = [&](const char* key, int lo, int hi) {
                const std::string rule = std::string("'") + key + "' must be [h, w], integers in " + std::to_string(lo) +
                                         ".." + std::to_string(hi);
                if (!n.contains(key) || !n[key].is_array() || n[key].size() != 2 || !is_integer_in(n[key][0], lo, hi) ||
                    !is_integer_in(n[key][1], lo, hi))
                    throw bad(rule);
                return std::pair<int, int>{n[key][0].get<int>(), n[key][1].get<int>()};
            };
            const auto [kh, kw] = pair("kernel", 1, kMaxKernel);
            pair("stride", 1, kMaxStride);
            const std::string rule = "'pads' must be [top, left, bottom, right], integers in 0.." +
                                     std::to_string(kMaxPad) + ", each below its kernel side";
            if (!n.contains("pads") || !n["pads"].is_array() || n["pads"].size() != 4) throw bad(rule);
            for (int s = 0; s < 4; ++s)
                if (!is_integer_in(n["pads"][s], 0, kMaxPad) || n["pads"][s].get<int>() >= (s % 2 ? kw : kh)) throw bad(rule);
            node.out_channels = cin;
        } else if (node.kind == NodeKind::pad2d) {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pad");
            const std::string rule = "'pads' must be [top, left, bottom, right], integers in -" +
                                     std::to_string(kMaxPad) + ".." + std::to_string(kMaxPad) + " (negative: a crop)";
            if (!n.contains("pads") || !n["pads"].is_array() || n["pads"].size() != 4) throw bad(rule);
            for (const auto& p : n["pads"])
                if (!is_integer_in(p, -kMaxPad, kMaxPad)) throw bad(rule);
            if (!n.contains("mode") || !n["mode"].is_string() ||
                (n["mode"] != "constant" && n["mode"] != "reflect" && n["mode"] != "edge"))
                throw bad("'mode' must be \"constant\", \"reflect\" or \"edge\"");
            if (n.contains("value") && (!n["value"].is_number() || !float32_representable(n["value"].get<double>())))
                throw bad(std::string("'value' must be a number ") + kFloat32Rule);
            node.out_channels = cin;
        } else if (node.kind == NodeKind::resize_bilinear) {
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
                if (!n["sizes"].is_array() || n["sizes"].size() != 2 || !is_integer_in(n["sizes"][0], 1, 65536) ||
                    !is_integer_in(n["sizes"][1], 1, 65536))
                    throw bad(rule);
            }
            static const std::set<std::string> kCoords = {"half_pixel", "pytorch_half_pixel", "align_corners",
                                                          "asymmetric"};
            if (!n.contains("coordinate") || !n["coordinate"].is_string() || !kCoords.count(n["coordinate"].get<std::string>()))
                throw bad("'coordinate' must be \"half_pixel\", \"pytorch_half_pixel\", \"align_corners\" or "
                          "\"asymmetric\"");
            node.out_channels = cin;
        } else if (node.kind == NodeKind::global_avg_pool) {
            if (nc) throw bad("layout \"nc\" has no spatial axes to pool");
            node.out_channels = cin;
        } else if (node.kind == NodeKind::instance_norm || node.kind == NodeKind::group_norm) {
            if (nc) throw bad("layout \"nc\" has no spatial axes to normalize over");
            if (node.kind == NodeKind::group_norm && cin % int_field("groups", 1, kMaxChannels) != 0)
                throw bad("'groups' (" + n["groups"].dump() + ") must divide the input's " + std::to_string(cin) +
                          " channels");
            tensor_field("scale", true);
            tensor_field("shift", true);
            const nlohmann::json* eps = n.contains("eps") ? &n["eps"] : nullptr;
            if (!eps || !eps->is_number() || !(eps->get<double>() > 0) || !(eps->get<double>() <= 1.0) ||
                !float32_representable(eps->get<double>()) || !(float(eps->get<double>()) > 0.0f))
                throw bad(std::string("'eps' must be a number in (0, 1] ") + kFloat32Rule);
            node.out_channels = cin;
        } else if (node.kind == NodeKind::affine) {
            tensor_field("scale", false);
            tensor_field("shift", false);
            if (!n.contains("scale") && !n.contains("shift")) throw bad("neither 'scale' nor 'shift' is given");
            node.out_channels = cin;
        } else if (node.kind == NodeKind::frequency_encode) {
            if (!n.contains("encoding") || !n["encoding"].is_object()) throw bad("'encoding' must be an object");
            ModelConfig::Encoding e;
            parse_encoding_fields(n, e, what + label + ": ");
            if (e.bands < 1) throw bad("'encoding.bands' must be at least 1");
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

}  // namespace ngi::detail

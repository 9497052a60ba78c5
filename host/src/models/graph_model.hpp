// The "graph" model family (docs/MODEL_FORMAT.md "graph"): a network stored as a list of nodes over named tensors,
// as python3 -m ngi.convert writes it from an ONNX file. Each node is one of the node kinds of graph/node_kind.hpp
// (conv2d, conv_transpose2d, dense, concat, activation, affine, add, mul, ...); the loader checks the list as hostile
// input (unknown op or field, a tensor used before it is made or never made, channel counts that do not chain,
// weights missing, misshaped or unused) and names the node in every error. graph_family.cpp is the family's
// front-end (config, runner), graph_config.cpp parses the node list, graph_model.cpp checks the weights and builds the
// ops (graph/nodes.hpp) and the graph.
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "graph/graph.hpp"
#include "graph/node_kind.hpp"
#include "models/safetensors.hpp"
#include "ngi/model.hpp"
#include "ops/gemm.hpp"

namespace ngi::detail {

// The loader's limits (shared with the converter, which refuses what the loader would: bindings/python/ngi/
// onnx_import.py reads them from ngi/_constants.py).
inline constexpr int kMaxGraphNodes = 4096;
inline constexpr int kMaxGraphKernel = 64, kMaxGraphStride = 64, kMaxGraphPad = 64;
inline constexpr int kMaxGraphNameLength = 512;  // node and tensor names, in bytes
inline constexpr int kMaxGraphNodeInputs = 1024;

// One node of the list, checked: its inputs are tensor indices (0 = the graph input, i + 1 = node i's output), so
// every input is made before it is read (a list cannot hold a cycle).
struct GraphNodeDesc {
    std::string name, op, output;  // op: the kind's name, as the file writes it
    NodeKind kind = NodeKind::conv2d;
    std::vector<int> inputs;
    int out_channels = 0;
    nlohmann::json fields;  // the node's JSON object (weights, geometry, activation)
    std::vector<std::string> folded;  // the nodes the loader's fusion folded into this one (graph_fuse.hpp), in order
};

// A node as errors and profiles name it: its name, then what was folded into it ("conv + bn + relu").
inline std::string graph_node_label(const GraphNodeDesc& n) {
    std::string s = n.name;
    for (const std::string& f : n.folded) s += " + " + f;
    return s;
}

struct GraphDesc {
    std::string layout = "nchw";  // "nchw" | "nc"
    std::string input_name;
    int input_nc = 0;
    std::vector<GraphNodeDesc> nodes;
    int output = 0;  // tensor index
};

// The node list of a family "graph" config (graph_family.cpp parses the rest); InputError starting with `what` and
// naming the field and, for node problems, the node.
GraphDesc parse_graph_desc(const nlohmann::json& j, const std::string& what);

// The weight tensors of one node (nullptr where the node names none), pointing into the file.
struct GraphNodeWeights {
    const StoredTensor *w = nullptr, *b = nullptr, *scale = nullptr, *shift = nullptr;
};
// Every tensor the nodes of `d` name present in `file` with the shape the node implies (docs/MODEL_FORMAT.md
// "graph"), and no other tensor in the file: InputError naming the node and the tensor otherwise. Needs no device
// (build_graph_model_ops runs it first; the fuzz target fuzz_model_config calls it directly).
std::vector<GraphNodeWeights> check_graph_weights(const GraphDesc& d, const SafetensorsFile& file);

struct GraphModelOps {
    GraphDesc desc;  // the node list after the loader's fusion (graph_fuse.hpp)
    std::vector<std::shared_ptr<Op>> ops;  // per node; nullptr for concat
    std::shared_ptr<Op> copy;              // inserted where a tensor must live in a second place
    std::size_t weight_bytes = 0;
};

// Every weight the nodes name present with the shape the node implies (and no other tensor in the file), then the
// node list fused (fuse_graph: affines and activations folded into the layers before them where exact), then the
// ops built and their weights uploaded.
GraphModelOps build_graph_model_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file,
                                    const GemmParams& gemm, const std::optional<GemmParams>& conv_gemm);
// input [input_nc, height, width] -> the output tensor. An in-place node whose input is read elsewhere too, and a
// concat member that already lives somewhere (the graph input, another concat), get a copy first.
std::unique_ptr<Graph> build_graph_model_graph(const GraphModelOps& ops, int height, int width);

}  // namespace ngi::detail

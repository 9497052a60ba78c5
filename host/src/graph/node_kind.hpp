// The node kinds a model file names (docs/MODEL_FORMAT.md "graph", the "op" of a node), ggml style: an enum and
// its name table, in the order the loader's messages list them. Each kind is built on a node adapter of
// graph/nodes.hpp (dense on ConvNode as a 1 x 1 convolution, instance_norm on BatchNormNode, add and mul on
// BinaryNode or BroadcastNode; concat is Graph::concat, no node). Op::kind() is the adapter's own name (profiles,
// build errors), not this one.
#pragma once
#include <cstddef>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>

namespace ngi::detail {

enum class NodeKind {
    conv2d,
    conv_transpose2d,
    dense,
    concat,
    activation,
    affine,
    add,
    mul,
    frequency_encode,
    nan_to_num,
    max_pool2d,
    global_avg_pool,
    instance_norm,
    group_norm,
    pad2d,
    resize_bilinear,
};

inline constexpr std::string_view kNodeKindNames[] = {
    "conv2d",
    "conv_transpose2d",
    "dense",
    "concat",
    "activation",
    "affine",
    "add",
    "mul",
    "frequency_encode",
    "nan_to_num",
    "max_pool2d",
    "global_avg_pool",
    "instance_norm",
    "group_norm",
    "pad2d",
    "resize_bilinear",
};
inline constexpr std::size_t kNodeKinds = std::size(kNodeKindNames);
static_assert(kNodeKinds == std::size_t(NodeKind::resize_bilinear) + 1, "a name for every NodeKind");

inline constexpr std::string_view node_kind_name(NodeKind k) { return kNodeKindNames[std::size_t(k)]; }

// The kind a file's "op" names; nullopt for a name that is none of them.
inline std::optional<NodeKind> node_kind_from_name(std::string_view name) {
    for (std::size_t k = 0; k < kNodeKinds; ++k)
        if (kNodeKindNames[k] == name) return NodeKind(k);
    return std::nullopt;
}

// "conv2d, conv_transpose2d, ..., resize_bilinear": every name, in order.
inline std::string node_kind_list() {
    std::string s;
    for (std::string_view n : kNodeKindNames) s += (s.empty() ? "" : ", ") + std::string(n);
    return s;
}

}  // namespace ngi::detail

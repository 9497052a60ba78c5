// The loader's fusion of a family "graph" node list (docs/MODEL_FORMAT.md "graph", "Fusion at load"). A graph file
// describes the network as its source (ONNX) does: batch norms and other per-channel affines, activations, as nodes of
// their own. build_graph_model_ops runs fuse_graph on the checked list before it builds the ops, folding, where the
// result is exact:
//   1. an `affine` into the weights and bias of the conv2d / conv_transpose2d / dense node that makes its input
//      (weights scaled per output channel, bias = bias * scale + shift, in double, rounded to float32 once);
//   2. an `activation` into that node's epilogue (`activation`, `slope`);
//   3. a ReLU / LeakyReLU read only by convolutions into their `input_activation` (applied while they gather).
// Each only where the producer's output has that one reader (the graph output counts as a reader), the producer has no
// output activation yet, and no slope changes meaning (one `slope` serves a node's input_activation and activation).
// Files written before the loader fused (the converter fused, writing `input_activation` and fused `activation`s)
// are already at the passes' fixed point: nothing folds, and they load as before. Needs no device.
#pragma once
#include <memory>
#include <vector>

#include "models/graph_model.hpp"

namespace ngi::detail {

struct FusedGraph {
    GraphDesc desc;                          // the nodes that remain, inputs renumbered; `folded` names what each took
    std::vector<GraphNodeWeights> weights;   // per node of desc: into the file, or into `made`
    std::vector<std::unique_ptr<StoredTensor>> made;  // the weights and biases an affine fold rewrote
    int affines = 0, activations = 0, input_activations = 0;  // nodes folded away by passes 1 (two kinds) and 2
};

// `weights` is check_graph_weights(d, file): one entry per node of d.
FusedGraph fuse_graph(const GraphDesc& d, const std::vector<GraphNodeWeights>& weights);

}  // namespace ngi::detail

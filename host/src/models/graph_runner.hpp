// The runner of the families whose network is a graph (graph/graph.hpp): the U-Net generators, neural_gi, graph and
// pixel_cnn. One graph per input size, built, planned and compiled on first use and reused afterwards; Model::run,
// Model::enqueue and the surround pipeline's enqueue run it. Library-internal.
#pragma once
#include <map>
#include <memory>
#include <utility>

#include "graph/graph.hpp"
#include "models/family.hpp"

namespace ngi::detail {

class GraphRunner : public FamilyRunner {
public:
    // [1, input_nc, H, W] -> [1, C, H', W'] (the graph's output; the input's size unless the graph resamples).
    Tensor run(Context& ctx, const ModelConfig& cfg, const Tensor& input, RunInfo* info) override;
    // H and W positive multiples of 2^num_downs; the output buffer holds output_bytes().
    void enqueue(const Device& device, const ModelConfig& cfg, const DeviceBuffer& input, const DeviceBuffer& output,
                 int height, int width) override;
    void enqueue_frame(Context& ctx, const ModelConfig& cfg, cl_mem in, std::size_t in_offset, cl_mem out,
                       std::size_t out_offset, int height, int width) override;
    int sanitized_inputs(Context& ctx) override;

protected:
    // The family's graph for an input of height x width: input [input_nc, height, width] -> its output.
    virtual std::unique_ptr<Graph> build_graph(const ModelConfig& cfg, int height, int width) const = 0;
    virtual std::size_t weight_bytes() const = 0;  // RunInfo::weight_bytes
    // Bytes Model::enqueue's output buffer must hold: output_nc planes of the input's size (a family whose graph may
    // resample overrides it).
    virtual std::size_t output_bytes(Context& ctx, const ModelConfig& cfg, int height, int width);
    // The graph for an input of height x width (input limits: the config's input_range).
    Graph& graph(Context& ctx, const ModelConfig& cfg, int height, int width);

private:
    std::map<std::pair<int, int>, std::unique_ptr<Graph>> graphs_;  // per input H x W
    Graph* last_ = nullptr;                                          // of the last enqueue (its sanitize counter)
};

}  // namespace ngi::detail

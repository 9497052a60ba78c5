// The graph families' runner (models/graph_runner.hpp).
#include "models/graph_runner.hpp"

#include "ngi/host_memory.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

Graph& GraphRunner::graph(Context& ctx, const ModelConfig& cfg, int height, int width) {
    auto& g = graphs_[{height, width}];
    if (!g) {
        auto fresh = build_graph(cfg, height, width);
        fresh->set_input_limits(cfg.input_range[0], cfg.input_range[1]);
        fresh->compile(ctx);
        g = std::move(fresh);
    }
    return *g;
}

Tensor GraphRunner::run(Context& ctx, const ModelConfig& c, const Tensor& input, RunInfo* info) {
    if (input.shape.size() != 4 || input.shape[0] != 1 || input.shape[1] != c.input_nc)
        throw InputError("run model: input tensor is " + shape_string(input.shape) + ", expected [1, " +
                         std::to_string(c.input_nc) + ", H, W] (NCHW, batch 1)");
    if (input.data.size() != Tensor::element_count(input.shape))
        throw InputError("run model: input tensor has " + std::to_string(input.data.size()) + " values for shape " +
                         shape_string(input.shape));
    Graph& g = graph(ctx, c, input.shape[2], input.shape[3]);
    const Shape os = g.output_shape();  // [output_nc, h, w] except for graphs that resample
    {   // The host output is judged with everything already held (issue 51: two stride-64 transposed convolutions
        // on a 4 x 4 input made a 3 GiB output on a GPU device, where the arena is not host memory).
        const HostMemoryHold room("run model: its output tensor [1, " + std::to_string(os.c) + ", " +
                                      std::to_string(os.h) + ", " + std::to_string(os.w) + "]",
                                  4ull * std::uint64_t(os.c) * std::uint64_t(os.h) * std::uint64_t(os.w));
    }
    Tensor out({1, os.c, os.h, os.w});
    const RunStats stats = g.run(ctx, input.data.data(), out.data.data());
    if (info) {
        info->sanitized_inputs = stats.sanitized_inputs;
        info->layers.clear();
        for (const auto& n : stats.nodes) info->layers.push_back({n.name, n.kind, n.ms, n.gflop, n.launches});
        info->arena_bytes = g.arena_bytes();
        info->naive_bytes = g.naive_bytes();
        info->scratch_bytes = g.scratch_bytes();
        info->weight_bytes = weight_bytes();
    }
    return out;
}

std::size_t GraphRunner::output_bytes(Context&, const ModelConfig& cfg, int height, int width) {
    return std::size_t(height) * std::size_t(width) * sizeof(float) * std::size_t(cfg.output_nc);
}

void GraphRunner::enqueue(const Device& device, const ModelConfig& c, const DeviceBuffer& input,
                          const DeviceBuffer& output, int height, int width) {
    const int step = 1 << c.unet.num_downs;
    if (height < step || width < step || height % step || width % step)
        throw InputError("enqueue model: input " + std::to_string(height) + "x" + std::to_string(width) +
                         " (HxW) must be positive multiples of 2^num_downs = " + std::to_string(step));
    Context& ctx = context_of(device);
    const std::size_t plane = std::size_t(height) * std::size_t(width) * sizeof(float);
    check_enqueue_buffer(input, device, plane * std::size_t(c.input_nc), false, "input");
    check_enqueue_buffer(output, device, output_bytes(ctx, c, height, width), true, "output");
    Graph& g = graph(ctx, c, height, width);
    g.enqueue(ctx, input.opencl_mem(), 0, output.opencl_mem(), 0);
    last_ = &g;
}

void GraphRunner::enqueue_frame(Context& ctx, const ModelConfig& cfg, cl_mem in, std::size_t in_offset, cl_mem out,
                                std::size_t out_offset, int height, int width) {
    Graph& g = graph(ctx, cfg, height, width);
    g.enqueue(ctx, in, in_offset, out, out_offset);
    last_ = &g;
}

int GraphRunner::sanitized_inputs(Context& ctx) { return last_ ? last_->sanitized_count(ctx) : 0; }

}  // namespace ngi::detail

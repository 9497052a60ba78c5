#include "ngi/model.hpp"

#include <map>

#include "ngi/host_memory.hpp"
#include "models/graph_model.hpp"
#include "models/safetensors.hpp"
#include "models/unet.hpp"
#include "models/mlp_model.hpp"
#include "models/neural_gi_model.hpp"
#include "models/voxel_sh_model.hpp"
#include "models/model_access.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi {

struct Model::Impl {
    Device device;
    ModelConfig config;
    detail::UNetOps ops;
    std::map<std::pair<int, int>, std::unique_ptr<detail::Graph>> graphs;  // per input H x W
    detail::Graph* last = nullptr;  // of the last enqueue (its sanitize counter)
    std::unique_ptr<detail::MlpRunner> mlp;  // family "mlp" (instead of ops and graphs)
    bool mlp_enqueued = false;
    std::unique_ptr<detail::VoxelShRunner> voxel_sh;  // family "voxel_sh" (instead of ops and graphs)
    bool voxel_sh_enqueued = false;
    std::unique_ptr<detail::NeuralGiOps> neural_gi;  // family "neural_gi" (instead of ops; graphs as a U-Net's)
    std::unique_ptr<detail::GraphModelOps> graph_model;  // family "graph" (instead of ops; its own graphs)
    nlohmann::json ao;  // family "mlp": the metadata's "ao" value (null when absent; ModelAccess::ao)

    // The graph for an input of h x w, built, planned and allocated on first use.
    detail::Graph& graph(int h, int w) {
        auto& g = graphs[{h, w}];
        if (!g) {
            auto fresh = graph_model ? detail::build_graph_model_graph(*graph_model, h, w)
                         : neural_gi ? detail::build_neural_gi_graph(*neural_gi, config.input_nc, h, w)
                                     : detail::build_unet_graph(ops, h, w);
            fresh->set_input_limits(config.input_range[0], config.input_range[1]);
            fresh->compile(ngi::detail::context_of(device));
            g = std::move(fresh);
        }
        return *g;
    }
};

Model::Model(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Model::Model(Model&&) noexcept = default;
Model& Model::operator=(Model&&) noexcept = default;
Model::~Model() = default;

Model Model::load(const Device& device, const std::string& path, const ModelOptions& options) {
    const detail::SafetensorsFile file = detail::read_safetensors(path);
    auto meta = file.metadata.find("ngi");
    if (meta == file.metadata.end())
        throw InputError("load model " + path + ": no __metadata__[\"ngi\"] architecture config; convert the "
                         "checkpoint with python3 -m ngi.convert (docs/MODEL_FORMAT.md)");
    nlohmann::json ao;
    ModelConfig cfg = detail::parse_model_config(meta->second, path, &ao);  // every family, the JSON parsed once
    if (cfg.family == "graph" && (!options.bn_mode.empty() || !options.dropout.empty()))
        throw InputError("load model " + path + ": bn_mode and dropout apply to the U-Net families; an imported "
                         "graph runs as exported (inference batch norm folded in, no dropout)");
    if (!options.bn_mode.empty()) cfg.bn_mode = options.bn_mode;
    if (!options.dropout.empty()) cfg.dropout = options.dropout;
    auto impl = std::make_unique<Impl>(
        Impl{device, cfg, {}, {}, nullptr, nullptr, false, nullptr, false, nullptr, nullptr, std::move(ao)});
    auto& ctx = ngi::detail::context_of(device);
    if (cfg.family == "ssgi") {  // no network: nothing to build; the pipeline runs it on frames
        if (!options.bn_mode.empty() || !options.dropout.empty() || !options.mlp_path.empty())
            throw InputError("load model " + path + ": bn_mode, dropout and mlp_path apply to networks; an ssgi rung "
                             "has none");
        return Model(std::move(impl));
    }
    if (cfg.family == "voxel_sh") {
        if (!options.mlp_path.empty())
            throw InputError("load model " + path + ": mlp_path applies to the mlp family, this is voxel_sh");
        impl->voxel_sh = std::make_unique<detail::VoxelShRunner>(ctx, cfg, file, path, detail::gemm_selection(ctx).params);
        return Model(std::move(impl));
    }
    if (cfg.family == "mlp") {
        impl->mlp = std::make_unique<detail::MlpRunner>(ctx, detail::mlp_spec(cfg, file, path),
                                                        detail::gemm_selection(ctx).params, options.mlp_path,
                                                        cfg.input_range[0], cfg.input_range[1]);
        return Model(std::move(impl));
    }
    if (!options.mlp_path.empty())
        throw InputError("load model " + path + ": mlp_path applies to the mlp family, this is " + cfg.family);
    try {
        const detail::GemmSelection& gemm = detail::gemm_selection(ngi::detail::context_of(device));
        if (cfg.family == "graph")
            impl->graph_model = std::make_unique<detail::GraphModelOps>(
                detail::build_graph_model_ops(ngi::detail::context_of(device), cfg, file, gemm.params, gemm.conv_params));
        else if (cfg.family == "neural_gi")
            impl->neural_gi = std::make_unique<detail::NeuralGiOps>(
                detail::build_neural_gi_ops(ngi::detail::context_of(device), cfg, file, gemm.params, gemm.conv_params));
        else
            impl->ops = detail::build_unet_ops(ngi::detail::context_of(device), cfg, file, gemm.params, gemm.conv_params);
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + " (file " + path + ")");
    }
    return Model(std::move(impl));
}

const ModelConfig& Model::config() const { return impl_->config; }

namespace {

// Family "ssgi" has no network to run on a tensor.
void refuse_ssgi(const ModelConfig& c, const char* what) {
    if (c.family == "ssgi")
        throw InputError(std::string(what) + ": family ssgi has no network; it runs on frames (SurroundPipeline::run "
                         "or enqueue, ngi lightmap, ngi_pipeline_run, Pipeline.run)");
}

}  // namespace

Tensor Model::run(const Tensor& input, RunInfo* info) {
    const auto& c = impl_->config;
    refuse_ssgi(c, "run model");
    if (impl_->mlp) {
        impl_->mlp_enqueued = false;
        return impl_->mlp->run(ngi::detail::context_of(impl_->device), input, info);
    }
    if (impl_->voxel_sh) {
        impl_->voxel_sh_enqueued = false;
        return impl_->voxel_sh->run(ngi::detail::context_of(impl_->device), input, info);
    }
    if (impl_->graph_model && c.graph.layout == "nc" && input.shape.size() == 2) return run_items(input, info);
    if (input.shape.size() != 4 || input.shape[0] != 1 || input.shape[1] != c.input_nc)
        throw InputError("run model: input tensor is " + shape_string(input.shape) + ", expected [1, " +
                         std::to_string(c.input_nc) + ", H, W] (NCHW, batch 1)");
    if (input.data.size() != Tensor::element_count(input.shape))
        throw InputError("run model: input tensor has " + std::to_string(input.data.size()) + " values for shape " +
                         shape_string(input.shape));
    const int h = input.shape[2], w = input.shape[3];
    detail::Graph* graph = &impl_->graph(h, w);
    const Shape os = graph->output_shape();  // [output_nc, h, w] except for graphs that resample
    {   // The host output is judged with everything already held (issue 51: two stride-64 transposed convolutions
        // on a 4 x 4 input made a 3 GiB output on a GPU device, where the arena is not host memory).
        const HostMemoryHold room("run model: its output tensor [1, " + std::to_string(os.c) + ", " +
                                      std::to_string(os.h) + ", " + std::to_string(os.w) + "]",
                                  4ull * std::uint64_t(os.c) * std::uint64_t(os.h) * std::uint64_t(os.w));
    }
    Tensor out({1, os.c, os.h, os.w});
    const detail::RunStats stats = graph->run(ngi::detail::context_of(impl_->device), input.data.data(), out.data.data());
    if (info) {
        info->sanitized_inputs = stats.sanitized_inputs;
        info->layers.clear();
        for (const auto& n : stats.nodes) info->layers.push_back({n.name, n.kind, n.ms, n.gflop, n.launches});
        info->arena_bytes = graph->arena_bytes();
        info->naive_bytes = graph->naive_bytes();
        info->scratch_bytes = graph->scratch_bytes();
        info->weight_bytes = impl_->graph_model ? impl_->graph_model->weight_bytes
                             : impl_->neural_gi ? impl_->neural_gi->weight_bytes : impl_->ops.weight_bytes;
    }
    return out;
}

// Family "graph", layout "nc": [N, C] items, transposed to the planar [C, 1, N] image the graph runs on and back.
Tensor Model::run_items(const Tensor& input, RunInfo* info) {
    const auto& c = impl_->config;
    if (input.shape[1] != c.input_nc || input.shape[0] < 1 || input.shape[0] > (1 << 30))
        throw InputError("run model: input tensor is " + shape_string(input.shape) + ", expected [N, " +
                         std::to_string(c.input_nc) + "] with N in 1 .. 2^30 (or [1, " + std::to_string(c.input_nc) +
                         ", H, W] per pixel)");
    if (input.data.size() != Tensor::element_count(input.shape))
        throw InputError("run model: input tensor has " + std::to_string(input.data.size()) + " values for shape " +
                         shape_string(input.shape));
    const int n = input.shape[0], ci = c.input_nc, co = c.output_nc;
    Tensor planar({1, ci, 1, n});
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < ci; ++k) planar.data[std::size_t(k) * n + i] = input.data[std::size_t(i) * ci + k];
    const Tensor y = run(planar, info);
    Tensor out({n, co});
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < co; ++k) out.data[std::size_t(i) * co + k] = y.data[std::size_t(k) * n + i];
    return out;
}

namespace detail {

void ModelAccess::enqueue(Model& model, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset,
                          int height, int width) {
    Model::Impl& im = *model.impl_;
    refuse_ssgi(im.config, "the surround pipeline's network");
    if (im.mlp) throw InputError("the surround pipeline runs image generators; this model is an mlp");
    if (im.voxel_sh) throw InputError("the surround pipeline runs image generators; this model is a voxel_sh network");
    Graph& g = im.graph(height, width);
    // The pipeline sizes its buffers as [output_nc, height, width]; an imported graph may resample.
    if (im.graph_model && !(g.output_shape() == Shape{im.config.output_nc, height, width}))
        throw InputError("the surround pipeline needs an output of the input's size (" + std::to_string(height) +
                         "x" + std::to_string(width) + "); this graph model gives " + to_string(g.output_shape()));
    g.enqueue(context_of(im.device), in, in_offset, out, out_offset);
    im.last = &g;
}

const Device& ModelAccess::device(const Model& model) { return model.impl_->device; }

AoMetadata ModelAccess::ao(const Model& model, const std::string& what) {
    return parse_ao_metadata(model.impl_->ao, what);
}

}  // namespace detail

namespace {

void check_device_buffer(const DeviceBuffer& b, const Device& device, std::size_t need, bool write, const char* what) {
    if (!b) throw InputError(std::string("enqueue model: the ") + what + " buffer is empty");
    if (detail::shared_context_of(b.device()) != detail::shared_context_of(device))
        throw InputError(std::string("enqueue model: the ") + what + " buffer belongs to another device than the model");
    if (b.bytes() < need)
        throw InputError(std::string("enqueue model: the ") + what + " buffer holds " + std::to_string(b.bytes()) +
                         " bytes, the model needs " + std::to_string(need));
    if (write && !b.writable())
        throw InputError(std::string("enqueue model: the ") + what + " buffer was created CL_MEM_READ_ONLY");
}

}  // namespace

void Model::enqueue(const DeviceBuffer& input, const DeviceBuffer& output, int height, int width) {
    const auto& c = impl_->config;
    refuse_ssgi(c, "enqueue model");
    if (impl_->mlp) {
        if (height < 1 || width < 1 || double(height) * width > double(1 << 30))
            throw InputError("enqueue model: " + std::to_string(height) + "x" + std::to_string(width) +
                             " items are not in 1 .. 2^30");
        const std::size_t items = std::size_t(height) * std::size_t(width) * sizeof(float);
        check_device_buffer(input, impl_->device, items * std::size_t(c.input_nc), false, "input");
        check_device_buffer(output, impl_->device, items * std::size_t(c.output_nc), true, "output");
        impl_->mlp->enqueue(ngi::detail::context_of(impl_->device), input.opencl_mem(), output.opencl_mem(),
                            height * width);
        impl_->mlp_enqueued = true;
        return;
    }
    if (impl_->voxel_sh) {
        if (height < 1 || width < 1 || double(height) * width > double(1 << 30))
            throw InputError("enqueue model: " + std::to_string(height) + "x" + std::to_string(width) +
                             " voxels are not in 1 .. 2^30");
        const std::size_t items = std::size_t(height) * std::size_t(width) * sizeof(float);
        check_device_buffer(input, impl_->device, items * std::size_t(c.input_nc), false, "input");
        check_device_buffer(output, impl_->device, items * std::size_t(c.output_nc), true, "output");
        impl_->voxel_sh->enqueue(ngi::detail::context_of(impl_->device), input.opencl_mem(), output.opencl_mem(),
                                 height * width);
        impl_->voxel_sh_enqueued = true;
        return;
    }
    const int step = 1 << c.num_downs;
    if (height < step || width < step || height % step || width % step)
        throw InputError("enqueue model: input " + std::to_string(height) + "x" + std::to_string(width) +
                         " (HxW) must be positive multiples of 2^num_downs = " + std::to_string(step));
    const std::size_t plane = std::size_t(height) * std::size_t(width) * sizeof(float);
    check_device_buffer(input, impl_->device, plane * std::size_t(c.input_nc), false, "input");
    const std::size_t out_bytes =
        impl_->graph_model ? impl_->graph(height, width).output_bytes() : plane * std::size_t(c.output_nc);
    check_device_buffer(output, impl_->device, out_bytes, true, "output");
    if (impl_->graph_model) {
        detail::Graph& g = impl_->graph(height, width);
        g.enqueue(ngi::detail::context_of(impl_->device), input.opencl_mem(), 0, output.opencl_mem(), 0);
        impl_->last = &g;
        return;
    }
    detail::ModelAccess::enqueue(*this, input.opencl_mem(), 0, output.opencl_mem(), 0, height, width);
}

int Model::sanitized_inputs() {
    if (impl_->mlp) return impl_->mlp_enqueued ? impl_->mlp->sanitized_count(ngi::detail::context_of(impl_->device)) : 0;
    if (impl_->voxel_sh)
        return impl_->voxel_sh_enqueued ? impl_->voxel_sh->sanitized_count(ngi::detail::context_of(impl_->device)) : 0;
    return impl_->last ? impl_->last->sanitized_count(detail::context_of(impl_->device)) : 0;
}

}  // namespace ngi

#include "ngi/model.hpp"

#include <map>

#include "io/file_util.hpp"
#include "models/safetensors.hpp"
#include "models/unet.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi {

struct Model::Impl {
    Device device;
    ModelConfig config;
    detail::UNetOps ops;
    std::map<std::pair<int, int>, std::unique_ptr<detail::Graph>> graphs;  // per input H x W
};

Model::Model(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Model::Model(Model&&) noexcept = default;
Model& Model::operator=(Model&&) noexcept = default;
Model::~Model() = default;

Model Model::load(const Device& device, const std::string& path, const ModelOptions& options) {
    detail::require_readable_file(path);  // the safetensors reader streams: a directory or device fails inside it
    const detail::SafetensorsFile file = detail::read_safetensors(path);
    auto meta = file.metadata.find("ngi");
    if (meta == file.metadata.end())
        throw InputError("load model " + path + ": no __metadata__[\"ngi\"] architecture config; convert the "
                         "checkpoint with tools/ngi_convert.py (docs/MODEL_FORMAT.md)");
    ModelConfig cfg = detail::parse_model_config(meta->second, path);
    if (!options.bn_mode.empty()) cfg.bn_mode = options.bn_mode;
    if (!options.dropout.empty()) cfg.dropout = options.dropout;
    auto impl = std::make_unique<Impl>(Impl{device, cfg, {}, {}});
    try {
        impl->ops = detail::build_unet_ops(device.context(), cfg, file,
                                           detail::gemm_selection(device.context()).params);
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + " (file " + path + ")");
    }
    return Model(std::move(impl));
}

const ModelConfig& Model::config() const { return impl_->config; }

Tensor Model::run(const Tensor& input, RunInfo* info) {
    const auto& c = impl_->config;
    if (input.shape.size() != 4 || input.shape[0] != 1 || input.shape[1] != c.input_nc)
        throw InputError("run model: input tensor is " + shape_string(input.shape) + ", expected [1, " +
                         std::to_string(c.input_nc) + ", H, W] (NCHW, batch 1)");
    if (input.data.size() != Tensor::element_count(input.shape))
        throw InputError("run model: input tensor has " + std::to_string(input.data.size()) + " values for shape " +
                         shape_string(input.shape));
    const int h = input.shape[2], w = input.shape[3];
    auto& graph = impl_->graphs[{h, w}];
    if (!graph) {
        auto g = detail::build_unet_graph(impl_->ops, h, w);
        g->set_input_limits(c.input_range[0], c.input_range[1]);
        g->compile(impl_->device.context());
        graph = std::move(g);
    }
    Tensor out({1, c.output_nc, h, w});
    const detail::RunStats stats = graph->run(impl_->device.context(), input.data.data(), out.data.data());
    if (info) {
        info->sanitized_inputs = stats.sanitized_inputs;
        info->layers.clear();
        for (const auto& n : stats.nodes) info->layers.push_back({n.name, n.kind, n.ms, n.gflop});
        info->arena_bytes = graph->arena_bytes();
        info->naive_bytes = graph->naive_bytes();
        info->scratch_bytes = graph->scratch_bytes();
        info->weight_bytes = impl_->ops.weight_bytes;
    }
    return out;
}

}  // namespace ngi

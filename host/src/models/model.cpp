// ngi::Model: a model file's config parsed by its family (models/family.hpp) and the family's runner, which every
// method dispatches to.
#include "ngi/model.hpp"

#include "models/family.hpp"
#include "models/model_access.hpp"
#include "models/safetensors.hpp"
#include "runtime/context.hpp"

namespace ngi {

struct Model::Impl {
    Device device;
    ModelConfig config;
    nlohmann::json internal;  // FamilyConfig::internal: the metadata ModelConfig does not hold (ModelAccess::ao)
    std::unique_ptr<detail::FamilyRunner> runner;
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
    detail::FamilyConfig parsed = detail::parse_family_config(meta->second, path);  // the JSON parsed once
    auto runner = parsed.family->load(detail::context_of(device), parsed.config, file, path, options);
    return Model(std::make_unique<Impl>(
        Impl{device, std::move(parsed.config), std::move(parsed.internal), std::move(runner)}));
}

const ModelConfig& Model::config() const { return impl_->config; }

Tensor Model::run(const Tensor& input, RunInfo* info) {
    return impl_->runner->run(detail::context_of(impl_->device), impl_->config, input, info);
}

void Model::enqueue(const DeviceBuffer& input, const DeviceBuffer& output, int height, int width) {
    impl_->runner->enqueue(impl_->device, impl_->config, input, output, height, width);
}

int Model::sanitized_inputs() { return impl_->runner->sanitized_inputs(detail::context_of(impl_->device)); }

namespace detail {

void ModelAccess::enqueue(Model& model, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset,
                          int height, int width) {
    Model::Impl& im = *model.impl_;
    im.runner->enqueue_frame(context_of(im.device), im.config, in, in_offset, out, out_offset, height, width);
}

const Device& ModelAccess::device(const Model& model) { return model.impl_->device; }

AoMetadata ModelAccess::ao(const Model& model, const std::string& what) {
    const nlohmann::json& internal = model.impl_->internal;
    return parse_ao_metadata(internal.contains("ao") ? internal["ao"] : nlohmann::json(), what);
}

}  // namespace detail

}  // namespace ngi

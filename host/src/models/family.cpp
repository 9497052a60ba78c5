// What the families' loaders and runners share (models/family.hpp).
#include "models/family.hpp"

#include "runtime/context.hpp"

namespace ngi::detail {

void apply_network_options(ModelConfig& config, const ModelOptions& options) {
    if (!options.bn_mode.empty()) config.unet.bn_mode = options.bn_mode;
    if (!options.dropout.empty()) config.unet.dropout = options.dropout;
}

void refuse_mlp_path(const ModelOptions& options, const std::string& path, const ModelConfig& config) {
    if (!options.mlp_path.empty())
        throw InputError("load model " + path + ": mlp_path applies to the mlp family, this is " + config.family);
}

void check_enqueue_buffer(const DeviceBuffer& b, const Device& device, std::size_t need, bool write, const char* what) {
    if (!b) throw InputError(std::string("enqueue model: the ") + what + " buffer is empty");
    if (shared_context_of(b.device()) != shared_context_of(device))
        throw InputError(std::string("enqueue model: the ") + what + " buffer belongs to another device than the model");
    if (b.bytes() < need)
        throw InputError(std::string("enqueue model: the ") + what + " buffer holds " + std::to_string(b.bytes()) +
                         " bytes, the model needs " + std::to_string(need));
    if (write && !b.writable())
        throw InputError(std::string("enqueue model: the ") + what + " buffer was created CL_MEM_READ_ONLY");
}

void check_enqueue_items(int height, int width, const char* what) {
    if (height < 1 || width < 1 || double(height) * width > double(1 << 30))
        throw InputError("enqueue model: " + std::to_string(height) + "x" + std::to_string(width) + " " + what +
                         " are not in 1 .. 2^30");
}

}  // namespace ngi::detail

// Model files (host/src/models): the safetensors container, then what Model::load does before it needs an OpenCL
// device: the __metadata__["ngi"] config (parse_model_config) and the tensor names/shapes (validate_unet_tensors).
#include "fuzz_common.hpp"
#include "models/family.hpp"
#include "models/safetensors.hpp"
#include "models/unet.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return ngi::fuzz::expect_ngi_errors_only([&] {
        const ngi::detail::SafetensorsFile file =
            ngi::detail::parse_safetensors(ngi::fuzz::bytes(data, size), "fuzz.safetensors");
        for (const auto& [name, t] : file.tensors)
            if (t.data.size() != ngi::Tensor::element_count(t.shape)) __builtin_trap();
        const auto meta = file.metadata.find("ngi");
        if (meta == file.metadata.end()) return;
        const ngi::ModelConfig cfg = ngi::detail::parse_model_config(meta->second, "fuzz.safetensors");
        ngi::detail::validate_unet_tensors(cfg, file);
    });
}

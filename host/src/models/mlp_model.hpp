// The "mlp" model family's network (docs/MODEL_FORMAT.md): the frequency encoding fields (also read by neural_gi and
// graph nodes), its tensors, and the runner its front-end (models/mlp_family.cpp) wraps: the fused kernel when the
// network fits it and the device, else the dense GEMM path.
#pragma once
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "models/safetensors.hpp"
#include "ngi/model.hpp"
#include "ops/elementwise.hpp"
#include "ops/mlp.hpp"

namespace ngi::detail {

// The optional "encoding" object of `j` into `e` (docs/MODEL_FORMAT.md; absent: no encoding).
void parse_encoding_fields(const nlohmann::json& j, ModelConfig::Encoding& e, const std::string& what);
// `e` as the ops take it.
FrequencyEncoding frequency_encoding(const ModelConfig::Encoding& e);

// The network of an "mlp" model file: tensors layers.<i>.weight [out, in] and layers.<i>.bias [out]; every tensor
// present, of that shape, finite, and no other tensor. `path` names the file in errors.
MlpSpec mlp_spec(const ModelConfig& c, const SafetensorsFile& file, const std::string& path);

class MlpRunner {
public:
    // path: "fused", "dense" or "" (fused when the network fits it and the device's loop limit).
    MlpRunner(Context& ctx, const MlpSpec& spec, const GemmParams& gemm, const std::string& path, float input_lo,
              float input_hi);
    bool fused() const { return fused_ != nullptr; }
    std::size_t weight_bytes() const { return weight_bytes_; }
    // Host in, host out: [1, C, H, W] or [N, C]; the input is sanitized on the device (RunInfo::sanitized_inputs).
    Tensor run(Context& ctx, const Tensor& input, RunInfo* info);
    // Device in, device out, planar [C, n] from byte 0: no host transfer. The guard works on a copy of the input.
    void enqueue(Context& ctx, cl_mem in, cl_mem out, int n);
    int sanitized_count(Context& ctx) { return guard_.sanitized_count(ctx); }

private:
    MlpSpec spec_;
    std::unique_ptr<FusedMlp> fused_;
    std::unique_ptr<DenseMlp> dense_;
    Elementwise guard_;
    float lo_, hi_;
    std::size_t weight_bytes_ = 0;
    Buffer in_, out_, scratch_;  // grown on demand
};

}  // namespace ngi::detail

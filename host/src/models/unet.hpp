// The U-Net generators (pix2pix UnetGenerator, DeepIllumination G) as one level-by-level description, so both
// families share the same graph builder and differ only in names, bias, norm placement and concat order. Their
// front-end (config, runner) is models/unet_family.cpp; neural_gi builds its neural buffer here too.
#pragma once
#include <functional>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "graph/graph.hpp"
#include "models/safetensors.hpp"
#include "ngi/model.hpp"
#include "ops/gemm.hpp"

namespace ngi::detail {

// One U-Net level i (0 = outermost): down conv in_c -> inner_c at half resolution, up conv back.
struct LevelSpec {
    int in_c = 0, inner_c = 0;
    std::string down_w, down_b, down_bn;  // state_dict keys / BN module prefix; "" = absent
    int up_in = 0, up_out = 0;
    std::string up_w, up_b, up_bn;
    bool dropout = false;
};

struct UNetSpec {
    std::vector<LevelSpec> levels;
    bool decoder_first = false;  // concat order: pix2pix cat(skip, decoder); DeepIllumination cat(decoder, skip)
};

UNetSpec unet_spec(const ModelConfig& cfg);
// Expected tensor name -> shape, derived from the spec (used to report missing / unexpected / misshaped tensors).
std::vector<std::pair<std::string, std::vector<int>>> expected_tensors(const UNetSpec& spec);

// Device-side ops of every layer, built once per model (weights packed and uploaded).
struct UNetOps {
    struct Level {
        std::shared_ptr<Op> down, down_bn, up, up_bn, dropout;
    };
    std::vector<Level> levels;
    bool decoder_first = false;
    int input_nc = 0;
    std::size_t weight_bytes = 0;
};

// "\n  missing tensors: ...", "\n  unexpected tensors: ...", "\n  shape mismatch: ..." lines for `file` against
// `expected` (empty when they match); tensors for which `other(name)` holds belong to someone else and are not
// reported as unexpected.
std::string tensor_mismatches(const std::vector<std::pair<std::string, std::vector<int>>>& expected,
                              const SafetensorsFile& file,
                              const std::function<bool(const std::string&)>& other = nullptr);
// Every expected tensor present with its shape, no unexpected ones, bn_mode / dropout known: InputError otherwise.
// build_unet_ops calls it first; it needs no device (the fuzz target fuzz_safetensors calls it directly).
void validate_unet_tensors(const ModelConfig& cfg, const SafetensorsFile& file);
// gemm: the GEMM knob set (im2col path); conv_gemm: the implicit convolution's (GemmSelection::conv_params;
// nullopt: the device's tuning entry keeps convolutions on the im2col path). outer_act: the last layer's activation
// (the generators' tanh; none for Neural GI's neural buffer, a free feature map).
UNetOps build_unet_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file, const GemmParams& gemm,
                       const std::optional<GemmParams>& conv_gemm, Act outer_act = Act::tanh());
// The U-Net's nodes on input x of a graph (its height and width multiples of 2^num_downs: InputError otherwise);
// returns the output tensor [output_nc, height, width]. `prefix` starts every node name.
TensorId add_unet(Graph& g, const UNetOps& ops, TensorId x, const std::string& prefix = "");
// A graph of the U-Net alone: input [input_nc, height, width] -> output.
std::unique_ptr<Graph> build_unet_graph(const UNetOps& ops, int height, int width);

}  // namespace ngi::detail

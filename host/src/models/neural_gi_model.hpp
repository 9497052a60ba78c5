// The "neural_gi" model family (seed 002, Gao, Mu, Xu: docs/MODEL_FORMAT.md "neural_gi"): per scene, assembled
// per-pixel inputs I [18, H, W] -> indirect light [3, H, W], as one graph on the device:
//
//   I --frequency encoding (Eq. 3, raw kept)--> Gamma [E, H, W]
//   I --pix2pix U-Net, linear output--> neural buffer B [C_B, H, W]
//   z = concat(Gamma, B) --1x1 conv + ReLU, x skip_layer--> h --concat(h, copy of z)--> ... --> 1x1 conv, exp --> L*
//
// The MLP's layers are 1 x 1 convolutions over the image (the packed GEMM), so every pixel's MLP is one column.
// Tensors: the U-Net's under "buffer." (its UnetGenerator names), "mlp.layers.<i>.weight" [W, in, 1, 1] and
// ".bias" [W], "mlp.output.weight" [3, W, 1, 1] and ".bias" [3] (ngi.neural_gi's names).
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "graph/graph.hpp"
#include "models/safetensors.hpp"
#include "models/unet.hpp"
#include "ngi/model.hpp"

namespace ngi::detail {

struct NeuralGiOps {
    UNetOps buffer;
    std::shared_ptr<Op> encode, skip_copy, output;
    std::vector<std::shared_ptr<Op>> hidden;
    int skip_layer = 0;
    std::size_t weight_bytes = 0;
};

// Checks every tensor against the config (names, shapes, nothing missing or extra) before touching the device.
void validate_neural_gi_tensors(const ModelConfig& cfg, const SafetensorsFile& file);
NeuralGiOps build_neural_gi_ops(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file,
                                const GemmParams& gemm, const std::optional<GemmParams>& conv_gemm);
// input [input_nc, height, width] -> indirect [3, height, width]; height and width multiples of 2^num_downs.
std::unique_ptr<Graph> build_neural_gi_graph(const NeuralGiOps& ops, int input_nc, int height, int width);

}  // namespace ngi::detail

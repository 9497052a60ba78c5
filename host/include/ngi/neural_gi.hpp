// Seed 002 (Neural Global Illumination) on one frame, on the device: the per-pixel inputs assembled from the frame's
// front face (kernels/neural_gi.cl), the network (a "neural_gi" model: encoding, U-Net buffer, MLP as one graph),
// optionally at 1/K of the resolution with the indirect light brought back by joint bilateral upsampling guided by
// the full-resolution normals and positions (seed 002 section 5.3), and lighting = direct + indirect.
// Conventions: docs/MODEL_FORMAT.md "neural_gi" (inputs), docs/CONVENTIONS.md section 18 (upsampling).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "ngi/device.hpp"
#include "ngi/image.hpp"
#include "ngi/model.hpp"

namespace ngi {

struct NeuralGiOptions {
    // 1: the network at the frame's face size N; K > 1: at N / K (the pixel nearest the centre of each K x K block
    // as the low-resolution G-buffer), then joint bilateral upsampling to N. N / K must be a multiple of
    // 2^num_downs.
    int upsample = 1;
    // The upsampling's weights (docs/CONVENTIONS.md section 18).
    float jbu_sigma_spatial = 0.75f, jbu_normal_power = 32.0f, jbu_sigma_plane = 0.1f;
};

struct NeuralGiImages {
    Image indirect;   // N x N x 3, linear; 0 where the pixel has no surface
    Image lighting;   // direct + indirect (irradiance / pi, no albedo: the quantity of the frame's reference)
    int network_size = 0;        // the side the network ran at (N / upsample)
    int jbu_fallbacks = 0;       // pixels the upsampling filled bilinearly (no low-resolution tap matched)
    int sanitized_inputs = 0;    // network input values the model's guard replaced (0 for a sound frame)
    // NaN / +-Inf values in the front face's albedo, normal, depth and direct light, which the input assembly
    // replaced (docs/MODEL_FORMAT.md "neural_gi": NaN -> 0, an infinite vector -> its signs, light clamped)
    std::size_t nonfinite_features = 0;
};

// The channels NeuralGiRenderer assembles, in order (kernels/neural_gi.cl; training's ngi.neural_gi.INPUT_LAYOUT):
// position, normal, albedo, view, log1p_direct, light_dir, each .x/.y/.z or .r/.g/.b. A model whose input_layout
// is not empty must list exactly these.
const std::vector<std::string>& neural_gi_input_channels();

class NeuralGiRenderer {
public:
    explicit NeuralGiRenderer(const Device& device);
    NeuralGiRenderer(NeuralGiRenderer&&) noexcept;
    NeuralGiRenderer& operator=(NeuralGiRenderer&&) noexcept;
    ~NeuralGiRenderer();

    // InputError when the model is not a neural_gi model with a scene box, was loaded on another device, or the
    // frame has no area light or camera position (Renderer::render records both when it renders one), lacks the
    // front face's albedo, normal, depth or direct light, or its size does not fit the model and `upsample`.
    NeuralGiImages run(Model& model, const Frame& frame, const NeuralGiOptions& options = {});

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi

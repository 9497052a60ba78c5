// Seed 002's per-pixel inputs (kernels/neural_gi.cl, host/src/pipeline/neural_gi.cpp): the constants the kernel, the
// host and the Python side (ngi.neural_gi, through the generated ngi._constants) share. Library-internal.
#pragma once
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// Bound of the radiances (the direct-light input, the reference): only replaces +inf and absurd values; keeps
// log1p(L_d) <= 69 and L_d + exp(88) < 3.4e38, so every sum of the forward pass and the loss stays finite in float32.
// Real HDR values pass unchanged. Build option NGI_RADIANCE_MAX; Python's ngi.neural_gi.RADIANCE_MAX.
constexpr float kNeuralGiRadianceMax = 1.0e30f;

// The build options of kernels/neural_gi.cl.
inline std::string neural_gi_defines() { return define("NGI_RADIANCE_MAX", kNeuralGiRadianceMax); }

}  // namespace ngi::detail

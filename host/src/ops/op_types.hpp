// Small value types shared by the ops and the graph (library-internal): activations and CHW shapes (batch 1).
#pragma once
#include <cstddef>
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi {

// The codes reach kernels/activation.cl as build options (activation_defines()).
enum class Activation : int { None = 0, ReLU = 1, LeakyReLU = 2, Tanh = 3, Sigmoid = 4, Exp = 5, Softplus = 6, Erf = 7 };
// The "exp" activation is exp(min(x, kActExpMax)): finite in float32 for every input (docs/CONVENTIONS.md
// section 13). Python's ngi.neural_gi.EXP_CLAMP.
constexpr float kActExpMax = 88.0f;

// The build options of kernels/activation.cl: ACT_NONE ... ACT_ERF (the codes above) and ACT_EXP_MAX.
inline std::string activation_defines() {
    using detail::define;
    return detail::join_defines({define("ACT_NONE", int(Activation::None)), define("ACT_RELU", int(Activation::ReLU)),
                                 define("ACT_LEAKY_RELU", int(Activation::LeakyReLU)), define("ACT_TANH", int(Activation::Tanh)),
                                 define("ACT_SIGMOID", int(Activation::Sigmoid)), define("ACT_EXP", int(Activation::Exp)),
                                 define("ACT_SOFTPLUS", int(Activation::Softplus)), define("ACT_ERF", int(Activation::Erf)),
                                 define("ACT_EXP_MAX", kActExpMax)});
}

struct Act {
    Activation kind = Activation::None;
    float alpha = 0.0f;  // LeakyReLU slope
    static Act none() { return {}; }
    static Act relu() { return {Activation::ReLU, 0.0f}; }
    static Act leaky(float a) { return {Activation::LeakyReLU, a}; }
    static Act tanh() { return {Activation::Tanh, 0.0f}; }
    static Act sigmoid() { return {Activation::Sigmoid, 0.0f}; }
    static Act exp() { return {Activation::Exp, 0.0f}; }  // exp(min(x, 88)): finite for every input
    static Act softplus() { return {Activation::Softplus, 0.0f}; }  // log(1 + exp(x)), without overflow
    static Act erf() { return {Activation::Erf, 0.0f}; }            // the error function (GELU's)
};

std::string to_string(Activation a);

// A C x H x W tensor (batch 1, NCHW: w fastest).
struct Shape {
    int c = 0, h = 0, w = 0;
    std::size_t size() const { return std::size_t(c) * h * w; }
    bool operator==(const Shape&) const = default;
};

std::string to_string(const Shape& s);  // "64x256x512"

// Convolution geometry: square kernels are not assumed.
struct ConvGeometry {
    int kh = 4, kw = 4, stride = 2, pad = 1;
};

}  // namespace ngi

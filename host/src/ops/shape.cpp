#include "ops/op_types.hpp"

namespace ngi {

std::string to_string(Activation a) {
    switch (a) {
        case Activation::None: return "none";
        case Activation::ReLU: return "relu";
        case Activation::LeakyReLU: return "leaky_relu";
        case Activation::Tanh: return "tanh";
        case Activation::Sigmoid: return "sigmoid";
        case Activation::Exp: return "exp";
        case Activation::Softplus: return "softplus";
        case Activation::Erf: return "erf";
    }
    return "unknown";
}

std::string to_string(const Shape& s) {
    return std::to_string(s.c) + "x" + std::to_string(s.h) + "x" + std::to_string(s.w);
}

}  // namespace ngi

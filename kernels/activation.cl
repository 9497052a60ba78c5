// The activations of the dense, convolution, normalization and elementwise ops: listed before the file that uses
// them (programs gemm, im2col, col2im, norm, elementwise, mlp in host/src/runtime/programs.cpp), with the codes of
// ngi::Activation and the exp cap as build options (activation_defines(), host/src/ops/op_types.hpp).
#if !defined(ACT_NONE) || !defined(ACT_RELU) || !defined(ACT_LEAKY_RELU) || !defined(ACT_TANH) || \
    !defined(ACT_SIGMOID) || !defined(ACT_EXP) || !defined(ACT_EXP_MAX)
#error "activation.cl needs the activation codes: build it with activation_defines() (host/src/ops/op_types.hpp)"
#endif

// Branches on a uniform argument: cheap, and keeps one compiled kernel for every activation.
static inline float ngi_activate(float x, int act, float alpha) {
    switch (act) {
        case ACT_RELU: return fmax(x, 0.0f);
        case ACT_LEAKY_RELU: return x >= 0.0f ? x : alpha * x;
        case ACT_TANH: return tanh(x);                       // saturates to +-1, never NaN for finite x
        case ACT_SIGMOID: return 1.0f / (1.0f + exp(-x));    // exp overflow -> inf -> 0, still finite
        case ACT_EXP: return exp(fmin(x, ACT_EXP_MAX));      // capped below FLT_MAX: never +Inf
        default: return x;
    }
}

// The activations of the dense, convolution, normalization and elementwise ops: listed before the file that uses
// them (programs gemm, im2col, col2im, norm, elementwise, mlp in host/src/runtime/programs.cpp), with the codes of
// ngi::Activation and the exp cap as build options (activation_defines(), host/src/ops/op_types.hpp).
#if !defined(ACT_NONE) || !defined(ACT_RELU) || !defined(ACT_LEAKY_RELU) || !defined(ACT_TANH) || \
    !defined(ACT_SIGMOID) || !defined(ACT_EXP) || !defined(ACT_SOFTPLUS) || !defined(ACT_ERF) || !defined(ACT_EXP_MAX)
#error "activation.cl needs the activation codes: build it with activation_defines() (host/src/ops/op_types.hpp)"
#endif

// tanh from exp and a polynomial, not the built-in. Why: PoCL 3.1 evaluates the scalar built-in tanh one value at a
// time (its work-group vectorizer does not widen that call), ~8 ns per value on this machine's CPU, while exp and
// arithmetic vectorize (~0.9 ns): a 10,000-voxel network of three tanh layers 128 wide spent 28 of its 47 ms in
// tanh (docs/PERFORMANCE.md, "small shapes"). Accuracy, measured on PoCL over 3.8 M values: <= 1.51 ulp against
// float64 (the built-in: 1.09; OpenCL 1.2 allows 5). |x| < 0.55: x p(x^2), p a degree-5 fit of tanh(x)/x on that
// range (relative error 9.4e-10 before float rounding); above: (1 - e) / (1 + e) with e = exp(-2|x|) in (0, 0.34],
// which never overflows and has no cancellation there. Saturates to exactly +-1 (as PyTorch's does; PoCL's stops at
// 0.99999994), +-Inf gives +-1, NaN stays NaN. Both branches are computed (no divergence on a GPU). The vector form
// (kernels/mlp.cl) uses the same two macros.
#define NGI_TANH_POLY_LIMIT 0.55f
#define NGI_TANH_POLY(u)                                                                                      \
    (1.0f + (u) * (-0.3333331048488617f +                                                                   \
                   (u) * (0.13332462310791016f +                                                            \
                          (u) * (-0.05384282022714615f + (u) * (0.021039929240942f + (u) * -0.006235715467482805f)))))

static inline float ngi_tanh(float x) {
    const float e = exp(-2.0f * fabs(x));
    const float big = copysign((1.0f - e) / (1.0f + e), x);
    return fabs(x) < NGI_TANH_POLY_LIMIT ? x * NGI_TANH_POLY(x * x) : big;
}

// Branches on a uniform argument: cheap, and keeps one compiled kernel for every activation.
static inline float ngi_activate(float x, int act, float alpha) {
    switch (act) {
        case ACT_RELU: return fmax(x, 0.0f);
        case ACT_LEAKY_RELU: return x >= 0.0f ? x : alpha * x;
        case ACT_TANH: return ngi_tanh(x);                   // saturates to +-1, never NaN for finite x
        case ACT_SIGMOID: return 1.0f / (1.0f + exp(-x));    // exp overflow -> inf -> 0, still finite
        case ACT_EXP: return exp(fmin(x, ACT_EXP_MAX));      // capped below FLT_MAX: never +Inf
        // log(1 + e^x) as max(x, 0) + log1p(e^-|x|): no overflow for large x, no cancellation; +Inf -> +Inf
        case ACT_SOFTPLUS: return fmax(x, 0.0f) + log1p(exp(-fabs(x)));
        case ACT_ERF: return erf(x);                         // the built-in (OpenCL 1.2: within 16 ulp)
        default: return x;
    }
}

// ngi_activate on a vector type T (float2 .. float16, or float): the same formulas lane for lane, selects instead of
// branches. Why: where a kernel holds its results in vector registers (the GEMM's accumulators, the fused MLP's
// lanes), activating them one scalar at a time costs a switch and an unvectorized tanh per value: the GEMM's
// epilogue took 11 of the 12 ms of a 10 -> 128 tanh layer over 10,000 items on PoCL before it went vector
// (docs/PERFORMANCE.md, "small shapes"). NGI_DEFINE_VECTOR_ACTIVATE(float16, v16) defines ngi_tanh_v16 and
// ngi_activate_v16; a kernel file instantiates the widths it uses.
#define NGI_DEFINE_VECTOR_ACTIVATE(T, SUFFIX)                                                                   \
    static inline T ngi_tanh_##SUFFIX(T x) {                                                                  \
        const T e = exp(-2.0f * fabs(x));                                                                     \
        return select(copysign((1.0f - e) / (1.0f + e), x), x * NGI_TANH_POLY(x * x),                         \
                      fabs(x) < NGI_TANH_POLY_LIMIT);                                                         \
    }                                                                                                         \
    static inline T ngi_activate_##SUFFIX(T x, int act, float alpha) {                                        \
        switch (act) {                                                                                        \
            case ACT_RELU: return fmax(x, (T)(0.0f));                                                         \
            case ACT_LEAKY_RELU: return select(alpha * x, x, x >= (T)(0.0f));                                 \
            case ACT_TANH: return ngi_tanh_##SUFFIX(x);                                                       \
            case ACT_SIGMOID: return (T)(1.0f) / ((T)(1.0f) + exp(-x));                                       \
            case ACT_EXP: return exp(fmin(x, (T)(ACT_EXP_MAX)));                                              \
            case ACT_SOFTPLUS: return fmax(x, (T)(0.0f)) + log1p(exp(-fabs(x)));                              \
            case ACT_ERF: return erf(x);                                                                      \
            default: return x;                                                                                \
        }                                                                                                     \
    }

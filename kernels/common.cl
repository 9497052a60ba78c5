// Shared by every ngi program: prepended to each kernels/*.cl file before it is built.
// OpenCL C 1.2, no extensions: the same source builds on PoCL (CPU) and GPU drivers.

#define NGI_CAT_(a, b) a##b
#define NGI_CAT(a, b) NGI_CAT_(a, b)

// Activation codes; keep in sync with ngi::Activation (host/src/ops/op_types.hpp).
#define ACT_NONE 0
#define ACT_RELU 1
#define ACT_LEAKY_RELU 2
#define ACT_TANH 3
#define ACT_SIGMOID 4
#define ACT_EXP 5

// Branches on a uniform argument: cheap, and keeps one compiled kernel for every activation.
static inline float ngi_activate(float x, int act, float alpha) {
    switch (act) {
        case ACT_RELU: return fmax(x, 0.0f);
        case ACT_LEAKY_RELU: return x >= 0.0f ? x : alpha * x;
        case ACT_TANH: return tanh(x);                       // saturates to +-1, never NaN for finite x
        case ACT_SIGMOID: return 1.0f / (1.0f + exp(-x));    // exp overflow -> inf -> 0, still finite
        case ACT_EXP: return exp(fmin(x, 88.0f));            // capped below FLT_MAX: never +Inf
        default: return x;
    }
}

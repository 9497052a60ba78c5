// Small MLPs evaluated per item (pixel or point): the frequency (positional) encoding, a dense layer on the GEMM,
// and the fused kernel that runs every layer of a small MLP in one launch (kernels/mlp.cl). Conventions:
// docs/CONVENTIONS.md section 13.
#pragma once
#include <vector>

#include "ops/conv.hpp"
#include "ops/op_types.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// gamma(x) per component: [x if include_input], then for each band b = 0 .. bands-1 the pair
// sin(s_b x), cos(s_b x) with s_b = 2^(first_exponent + b) (times pi when pi). Neural GI's Eq. 3 (l in [0, L],
// exponent l - 1) is {bands = L + 1, first_exponent = -1, pi, include_input, BandMajor}; tiny-cuda-nn's Frequency
// encoding is {n_frequencies, 0, pi, no input, ComponentMajor}. bands = 0: no encoding (the input as it is).
struct FrequencyEncoding {
    enum class Order : int { ComponentMajor = 0, BandMajor = 1 };  // kernels/mlp.cl ORDER_* (build options)
    int bands = 0;
    int first_exponent = 0;
    bool pi = true;
    bool include_input = true;
    Order order = Order::BandMajor;
    int width(int components) const {  // encoded width
        return bands == 0 ? components : (include_input ? components : 0) + 2 * bands * components;
    }
};

// One fully connected layer: y = act(W x + b), W in PyTorch's nn.Linear layout [out][in] (row-major).
struct DenseSpec {
    int in = 0, out = 0;
    Act act;
    std::vector<float> weight, bias;  // out * in and out values (an empty bias is 0)
};

struct MlpSpec {
    int inputs = 0;
    FrequencyEncoding encoding;
    std::vector<DenseSpec> layers;
    // Throws InputError naming the layer when widths do not chain, weights are missing or not finite.
    void validate(const char* what) const;
};

// Where item i's channel c lives: i * item_stride + c * channel_stride floats after the view's offset. Planar
// images [C, H, W] (n = H W): {1, n}; point lists [n, C]: {C, 1}.
struct ItemLayout {
    int item_stride = 1, channel_stride = 1;
    static ItemLayout planar(int n) { return {1, n}; }
    static ItemLayout points(int channels) { return {channels, 1}; }
};

// The widest layer (encoded input included) the fused kernel takes; wider MLPs take the dense path.
constexpr int kFusedMlpMaxWidth = 128;
// Networks without an encoding, with at most this many layers and multiply-adds per item get a kernel built for
// their exact shape (kernels/mlp.cl mlp_static: fully unrolled, activations in registers; the MAC bound keeps the
// unrolled code, and its compile time, small); the others the generic fused kernel.
constexpr std::size_t kStaticMlpMaxLayers = 8;
constexpr long kStaticMlpMaxMacs = 8192;

// Items per work-item of the shape-specialized kernel (kernels/mlp.cl VEC): the device's knob.
int mlp_items_per_work_item(const DeviceInfo& info);

class FusedMlp {
public:
    // Throws InputError when the spec is invalid or wider than kFusedMlpMaxWidth, and Error when the per-item
    // loop count exceeds the device's limit (Context::loop_limit): use the dense path then (fits_device()).
    // vec: items per work-item of the shape-specialized kernel, 0 = the device's choice (mlp_items_per_work_item).
    FusedMlp(Context& ctx, const MlpSpec& spec, int vec = 0);
    // Loop iterations one work-item runs (what llvmpipe's limit counts).
    static long loop_iterations(const MlpSpec& spec);
    static bool fits_device(Context& ctx, const MlpSpec& spec);
    // n items from x (layout in, from float x_off) to y (layout out, from y_off).
    cl_event enqueue(Context& ctx, cl_mem x, std::size_t x_off, ItemLayout in, int n, cl_mem y, std::size_t y_off,
                     ItemLayout out, bool want_event = false);
    int width_class() const { return max_width_; }
    bool static_architecture() const { return static_arch_; }
    int items_per_work_item() const { return vec_; }
    bool constant_params() const { return constant_; }

private:
    MlpSpec spec_;
    int max_width_ = 0;
    bool constant_ = false;
    bool static_arch_ = false;
    int vec_ = 1;  // items per work-item (static kernel)
    float alpha_ = 0.0f;  // the LeakyReLU slope of the network
    bool alpha_set_ = false;
    Kernel kernel_;
    Buffer params_, desc_;
};

// The frequency encoding materialized: planar x [inputs][n] -> y [encoding.width(inputs)][n] (kernels/mlp.cl
// frequency_encode_planar). Used by DenseMlp and as a graph node (Neural GI's Eq. 3 over an image).
class FrequencyEncodePlanar {
public:
    // vec: items per work-item (kernels/mlp.cl ENC_VEC), 0 = the device's choice (mlp_items_per_work_item).
    FrequencyEncodePlanar(Context& ctx, int inputs, const FrequencyEncoding& encoding, int vec = 0);
    int inputs() const { return inputs_; }
    int items_per_work_item() const { return vec_; }
    int width() const { return encoding_.width(inputs_); }
    // x: inputs() channels of n items (n = h w of its shape); y: width() channels of n items.
    cl_event enqueue(Context& ctx, cl_mem x, std::size_t x_off, cl_mem y, std::size_t y_off, int n,
                     bool want_event = false);

private:
    int inputs_;
    FrequencyEncoding encoding_;
    int vec_;
    Kernel kernel_;
};

// The same MLP on the packed GEMM, one 1 x 1 convolution per layer over the items as a [C, 1, n] image (any width),
// with the encoding materialized first. Planar layouts only (the GEMM's operand layout).
class DenseMlp {
public:
    DenseMlp(Context& ctx, const GemmParams& p, const MlpSpec& spec);
    // Scratch floats for n items: the encoded input, two ping-pong activations and the convolutions' own.
    std::size_t scratch_floats(int n) const;
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::vector<cl_event>* events = nullptr);

private:
    MlpSpec spec_;
    FrequencyEncodePlanar encode_;
    std::vector<Conv2d> layers_;
};

}  // namespace ngi::detail

// 2D max pooling (kernels/max_pool.cl): ONNX MaxPool / PyTorch max_pool2d with ceil_mode 0 and dilation 1, on a
// planar C x H x W tensor (batch 1; a batch N is folded into C = N * channels, since every plane pools on its own).
// Padding is zero-based and may be asymmetric; padded cells count as -Inf, so padding never wins. A window holding
// a NaN pools to NaN (PyTorch's rule; OpenCL's fmax would drop it). Exact: every output is one of the inputs.
#pragma once
#include <string>
#include <vector>

#include "ops/op_types.hpp"
#include "ops/view.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// The work-group size of max_pool2d (MAX_POOL_LOCAL): fixed, as PoCL compiles one work-group function per local size.
constexpr int kMaxPoolLocal = 64;

// The build options of kernels/max_pool.cl.
inline std::string max_pool_defines() { return define("MAX_POOL_LOCAL", kMaxPoolLocal); }

// Kernel, strides and padding. Pads follow ONNX's order of axes: top and bottom pad H, left and right pad W.
// Each pad must be below the kernel side of its axis (a window that is all padding would have no value).
struct MaxPoolGeometry {
    int kh = 2, kw = 2;
    int stride_h = 2, stride_w = 2;
    int pad_top = 0, pad_left = 0, pad_bottom = 0, pad_right = 0;
};

class MaxPool2d {
public:
    // Throws InputError naming "max_pool2d" and the values for a kernel or stride below 1, a negative pad, a pad not
    // below its kernel side, or a window of more taps than the device's loop limit (Context::loop_limit).
    MaxPool2d(Context& ctx, const MaxPoolGeometry& geom);
    // {C, floor((H + pad_top + pad_bottom - kh) / stride_h) + 1, floor((W + pad_left + pad_right - kw) / stride_w) + 1};
    // throws InputError for an empty input, a kernel larger than the padded input, or a tensor of 2^31 floats or more.
    Shape output_shape(const Shape& in) const;
    // y = max_pool2d(x). y.shape must be output_shape(x.shape); x and y must not overlap. Appends the kernel's event
    // to `events` when profiling.
    void enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events = nullptr);
    const MaxPoolGeometry& geometry() const { return geom_; }

private:
    MaxPoolGeometry geom_;
    Kernel kernel_;
};

}  // namespace ngi::detail

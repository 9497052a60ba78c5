// 2D padding (kernels/pad2d.cl): ONNX Pad over the H and W axes (modes constant, reflect, edge) / PyTorch F.pad
// with 4 pads (constant, reflect, replicate), on a planar C x H x W tensor (batch 1; a batch N is folded into
// C = N * channels, since every plane pads on its own). Pads may be asymmetric, and negative (a crop, as ONNX Pad allows); reflect mirrors about
// the edge pixel without repeating it and needs every pad below its axis' size. Exact: every output is an input or
// the constant.
#pragma once
#include <string>
#include <vector>

#include "ops/op_types.hpp"
#include "ops/view.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// The work-group size of pad2d (PAD2D_LOCAL): fixed, as PoCL compiles one work-group function per local size.
constexpr int kPad2dLocal = 64;

// What the padding holds. The codes reach kernels/pad2d.cl as build options (pad2d_defines()).
enum class PadMode : int {
    Constant = 0,  // `value` (ONNX 'constant', PyTorch 'constant')
    Reflect = 1,   // x[-k] = x[k], x[n - 1 + k] = x[n - 1 - k] (ONNX and PyTorch 'reflect'); pads < the axis' size
    Edge = 2,      // the nearest edge pixel (ONNX 'edge', PyTorch 'replicate')
};

std::string pad_mode_name(PadMode m);  // "constant", "reflect", "edge"

// The build options of kernels/pad2d.cl.
inline std::string pad2d_defines() {
    return join_defines({define("PAD2D_LOCAL", kPad2dLocal), define("PAD2D_CONSTANT", int(PadMode::Constant)),
                         define("PAD2D_REFLECT", int(PadMode::Reflect)), define("PAD2D_EDGE", int(PadMode::Edge))});
}

// Pads in ONNX's order of axes (top and bottom pad H, left and right pad W), negative ones crop; the mode; the constant
// mode's value (any float, NaN and +-Inf included; ignored by the other modes).
struct PadGeometry {
    int top = 0, left = 0, bottom = 0, right = 0;
    PadMode mode = PadMode::Constant;
    float value = 0.0f;
};

class Pad2d {
public:
    // Throws InputError naming "pad2d" and the values for an unknown mode.
    Pad2d(Context& ctx, const PadGeometry& geom);
    // {C, H + top + bottom, W + left + right}; throws InputError for an empty input, a reflect pad not below its
    // axis' size (top or bottom >= H, left or right >= W), or a tensor of 2^31 floats or more.
    Shape output_shape(const Shape& in) const;
    // y = pad2d(x). y.shape must be output_shape(x.shape); x and y must not overlap. Appends the kernel's event to
    // `events` when profiling.
    void enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events = nullptr);
    const PadGeometry& geometry() const { return geom_; }

private:
    PadGeometry geom_;
    Kernel kernel_;
};

}  // namespace ngi::detail

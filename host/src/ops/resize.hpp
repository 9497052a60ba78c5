// Bilinear resize (kernels/resize.cl): ONNX Resize with mode 'linear' over the H and W axes, coordinate
// transformation modes half_pixel, pytorch_half_pixel, align_corners and asymmetric (PyTorch F.interpolate
// bilinear: align_corners=False is half_pixel, align_corners=True is align_corners), on a planar C x H x W tensor
// (batch 1; a batch N is folded into C = N * channels). Not covered: ONNX's antialias, exclude_outside,
// tf_crop_and_resize and half_pixel_symmetric (the graph must refuse them).
//
// The source position of each output coordinate is computed exactly (kernels/resize.cl), the taps and weights
// follow PyTorch's rule: positions before the first pixel read it, a NaN among the four taps gives NaN and an Inf
// with weight 0 gives NaN (0 * Inf), an axis the resize leaves unchanged reads one row (column) only. Accuracy: a
// few float roundings of the weights and the sums, within 1e-6 of max |x| (tests/test_resize.cpp).
#pragma once
#include <string>
#include <vector>

#include "ops/op_types.hpp"
#include "ops/view.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// The work-group size of resize_bilinear (RESIZE_LOCAL): fixed, as PoCL compiles one work-group function per local
// size.
constexpr int kResizeLocal = 64;

// The build options of kernels/resize.cl.
inline std::string resize_defines() { return define("RESIZE_LOCAL", kResizeLocal); }

// ONNX Resize's coordinate_transformation_mode: the source position s of output coordinate o along an axis of
// `in` input and `out` output pixels, with the axis' scale (given, or out / in):
enum class ResizeCoord : int {
    HalfPixel = 0,         // s = (o + 0.5) / scale - 0.5
    PytorchHalfPixel = 1,  // the same, but s = 0 when out == 1
    AlignCorners = 2,      // s = o (in - 1) / (out - 1), s = 0 when out == 1; the scale is not used
    Asymmetric = 3,        // s = o / scale
};

std::string resize_coord_name(ResizeCoord m);  // ONNX's names: "half_pixel", "pytorch_half_pixel", ...

// The output size, the scales of the coordinate formulas and the mode. A scale of 0 (the default) stands for
// out / in, exactly (ONNX Resize given 'sizes'); a given scale (ONNX 'scales', with the output size ONNX derives
// from it, floor(in * scale)) must be positive and finite, and is used as it is, even where out / in differs.
struct ResizeGeometry {
    int out_h = 0, out_w = 0;
    float scale_h = 0.0f, scale_w = 0.0f;
    ResizeCoord mode = ResizeCoord::HalfPixel;
};

class ResizeBilinear {
public:
    // Throws InputError naming "resize_bilinear" and the values for an output size below 1, a scale that is
    // negative, NaN or infinite, or an unknown mode.
    ResizeBilinear(Context& ctx, const ResizeGeometry& geom);
    // {C, out_h, out_w}; throws InputError for an empty input, a tensor of 2^31 floats or more, or a scale so far
    // from out / in that the source positions do not fit the kernel's 64-bit integers (|s| near 2^62 / out).
    Shape output_shape(const Shape& in) const;
    // y = resize(x). y.shape must be output_shape(x.shape); x and y must not overlap. Appends the kernel's event to
    // `events` when profiling.
    void enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events = nullptr);
    const ResizeGeometry& geometry() const { return geom_; }

private:
    ResizeGeometry geom_;
    Kernel kernel_;
};

}  // namespace ngi::detail

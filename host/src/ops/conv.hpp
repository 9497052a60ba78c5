// Convolution and transposed convolution on the packed GEMM.
//
// conv2d:            im2col (packed B, optional fused input activation) -> GEMM with epilogue
//                    y = act(scale[co] * conv + shift[co]) written straight into the output view.
// conv_transpose2d:  pack X (im2col with a 1x1 kernel, optional input activation) -> GEMM into cols
//                    (Cout*KH*KW x IH*IW) -> col2im gather with the same epilogue.
// scale/shift carry the bias and a folded eval-mode batch norm (scale = gamma/sqrt(var+eps),
// shift = beta + (bias - mean) * scale); with neither they are 1 and 0.
#pragma once
#include <vector>

#include "ops/gemm.hpp"
#include "ops/view.hpp"

namespace ngi::detail {

struct ConvSpec {
    int cin = 0, cout = 0;
    ConvGeometry geom;
    Act in_act;   // applied to the input while gathering (ReLU before the U-Net's up-convolutions)
    Act out_act;  // applied in the epilogue
};

// Per-output-channel affine of the epilogue. Empty vectors mean scale 1 / shift 0.
struct ChannelAffine {
    std::vector<float> scale, shift;
};

class Conv2d {
public:
    // weight: PyTorch layout [cout][cin][kh][kw].
    Conv2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight, const ChannelAffine& affine);
    Shape output_shape(const Shape& in) const;
    std::size_t scratch_floats(const Shape& in) const;  // packed im2col buffer
    // Appends the events of its kernels to `events` when profiling.
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);
    const ConvSpec& spec() const { return spec_; }

private:
    ConvSpec spec_;
    Gemm gemm_;
    Kernel im2col_;
    Buffer ap_, scale_, shift_;
};

class ConvTranspose2d {
public:
    // weight: PyTorch layout [cin][cout][kh][kw].
    ConvTranspose2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight,
                    const ChannelAffine& affine);
    Shape output_shape(const Shape& in) const;
    std::size_t scratch_floats(const Shape& in) const;  // packed X + cols
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);
    const ConvSpec& spec() const { return spec_; }

private:
    ConvSpec spec_;
    Gemm gemm_;
    Kernel pack_, col2im_;
    Buffer ap_, scale_, shift_, ones_, zeros_;
};

// Output size of a convolution along one axis; throws InputError when it would be < 1.
int conv_out_size(int in, int k, int stride, int pad, const char* what);

}  // namespace ngi::detail

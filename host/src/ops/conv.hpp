// Convolution and transposed convolution on the packed GEMM.
//
// Where the geometry allows (ops/conv_implicit.hpp), both run as an implicit GEMM over a padded copy of the input
// instead; otherwise:
// conv2d:            im2col (packed B, optional fused input activation) -> GEMM with epilogue
//                    y = act(scale[co] * conv + shift[co]) written straight into the output view.
// conv_transpose2d:  pack X (im2col with a 1x1 kernel, optional input activation) -> GEMM into cols
//                    (Cout*KH*KW x IH*IW) -> col2im gather with the same epilogue.
// scale/shift carry the bias and a folded eval-mode batch norm (scale = gamma/sqrt(var+eps),
// shift = beta + (bias - mean) * scale); with neither they are 1 and 0.
#pragma once
#include <optional>
#include <vector>

#include "ops/conv_implicit.hpp"
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
    // implicit_p: the implicit path's knob set (GemmSelection::conv_params); unset: p.
    Conv2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight, const ChannelAffine& affine,
           ConvPath path = ConvPath::automatic, const std::optional<GemmParams>& implicit_p = std::nullopt);
    Shape output_shape(const Shape& in) const;
    std::size_t scratch_floats(const Shape& in) const;  // packed im2col buffer
    // Appends the events of its kernels to `events` when profiling.
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);
    const ConvSpec& spec() const { return spec_; }

    bool implicit() const { return implicit_.has_value(); }

private:
    ConvSpec spec_;
    GemmParams p_;
    std::optional<ImplicitConv> implicit_;  // the implicit-GEMM path where the geometry allows it; else:
    std::optional<Gemm> gemm_;              // im2col + GEMM
    std::optional<PackB> pack_;             // 1 x 1, stride 1, no padding: B is the input, packed
    Kernel im2col_;
    Buffer ap_, scale_, shift_;
};

class ConvTranspose2d {
public:
    // weight: PyTorch layout [cin][cout][kh][kw].
    ConvTranspose2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight,
                    const ChannelAffine& affine, ConvPath path = ConvPath::automatic,
                    const std::optional<GemmParams>& implicit_p = std::nullopt);
    Shape output_shape(const Shape& in) const;
    std::size_t scratch_floats(const Shape& in) const;  // packed X + cols
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);
    const ConvSpec& spec() const { return spec_; }

    bool implicit() const { return implicit_.has_value(); }

private:
    ConvSpec spec_;
    GemmParams p_;
    std::optional<ImplicitConv> implicit_;  // sub-pixel phases on the implicit GEMM where exact; else:
    std::optional<Gemm> gemm_;              // pack + GEMM + col2im
    std::optional<PackB> pack_;
    Kernel col2im_;
    Buffer ap_, scale_, shift_, ones_, zeros_;
};

// Output size of a convolution along one axis; throws InputError when it would be < 1.
int conv_out_size(int in, int k, int stride, int pad, const char* what);

}  // namespace ngi::detail

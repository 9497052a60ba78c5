// Implicit-GEMM convolution: the packed GEMM's micro-kernel reads B straight from a padded copy of the input
// (gemm_conv in kernels/gemm.cl), so no im2col matrix and no col2im pass exist.
//
// Both layer kinds become stride-1 convolutions with TH x TW taps over conv_pad's output (kernels/im2col.cl):
// - conv2d, stride S: the input is zero-padded and split into its S x S polyphase components (Cin*S*S planes);
//   tap (ty, tx) of plane (c, py, px) is weight [co][c][ty*S + py][tx*S + px]. Exact when S divides KH and KW
//   (no zero taps): the U-Net's k4 s2 p1 down-convolutions become 2 x 2 convolutions over 4*Cin planes.
// - conv_transpose2d, stride S: each of the S x S output phases (oy mod S, ox mod S) is a TH x TW convolution of
//   the zero-padded input with KH/S x KW/S of the kernel's taps, written straight into the output with stride S
//   (the "sub-pixel" form). Exact when S divides KH and KW and KH - 2P = KW - 2P = S, so every phase has IH x IW
//   pixels: the U-Net's k4 s2 p1 up-convolutions become four 2 x 2 convolutions.
// The derivation of the tap -> kernel index maps is in docs/ARCHITECTURE.md ("Implicit-GEMM convolution").
// Geometries that are not exact (e.g. k3 s2) keep the im2col / col2im path (ops/conv.hpp).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "ops/gemm.hpp"
#include "ops/view.hpp"

namespace ngi::detail {

// conv_pad's fixed work-group shape (PoCL compiles one work-group function per local size).
inline constexpr std::size_t kPadLocal[2] = {8, 1};

struct ConvSpec;

// Which path a layer takes. automatic: $NGI_CONV = "implicit" | "im2col" if set; otherwise implicit on gemm_packed
// knob sets (CPUs, and GPUs until a tuning run says otherwise) where the geometry is exact and Cout >= MR, im2col on
// gemm_local sets, whose local-memory staging is written for packed panels. implicit: wherever the geometry is
// exact (tests and benchmarks); im2col: never implicit.
enum class ConvPath { automatic, im2col, implicit };

class ImplicitConv {
public:
    // nullopt when the geometry is not exact (see above), or the kernel's loop count would pass the device's loop
    // limit (Context::loop_limit). weight in PyTorch's layout:
    // [cout][cin][kh][kw] (conv2d) or [cin][cout][kh][kw] (transposed).
    static std::optional<ImplicitConv> make(Context& ctx, const GemmParams& p, const ConvSpec& spec,
                                            const float* weight, bool transposed, ConvPath path);

    std::size_t scratch_floats(const Shape& in) const;  // the padded input and its slack (0 when read in place)
    // y = act(scale[co] * conv(x) + shift[co]); out is the layer's output shape. in_act must be the spec's.
    void enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                 cl_mem scale, cl_mem shift, Act in_act, Act out_act, std::vector<cl_event>* events);
    // Whether a layer reads its input x in place (no padded copy): a 1 x 1, stride 1, unpadded convolution with no
    // input activation over a plane of at least NR pixels (gemm_conv's b_limit) whose copy would be laid out as x
    // is (see the definition). $NGI_CONV_DIRECT=0: never.
    bool reads_input_in_place(const Shape& in) const;

private:
    // Everything that depends on the input size.
    struct Layout {
        int pad_stride, pty, ptx;      // conv_pad: polyphase factor and top/left zero padding
        int planes, ph, rs;            // planes of the tap convolution, padded height, row length
        int cs, row;                   // xp's channel and row strides (planar or row-interleaved)
        int tiles_per_row;             // gemm_conv's TPR: 0 = linear tiles over the planar grid
        int tiles;                     // tiles per phase
        std::size_t floats, slack;     // xp's size and the zeroed slack after it
        int rows, cols;                // output pixels per phase: q < rows, r < cols
        int out_h, out_w;              // the layer's output
        std::vector<int> b_off;        // per phase: offset of tap (0, 0) in xp (gemm_conv derives the same)
        int out_step;                  // output stride of a phase (1 for conv2d)
    };
    ImplicitConv(Context& ctx, const GemmParams& p, const std::string& taps, int th, int tw, int cout, int cin, int stride, int pad,
                 bool transposed, Act in_act, Buffer packed, std::size_t phase_floats);
    static bool direct_disabled();
    // Whether gemm_conv's tiles stay in output rows (row-interleaved copy) for rows of `cols` outputs, or run
    // linearly over a planar one ($NGI_CONV_TILES=rows|linear overrides).
    bool tiles_by_rows(int cols) const;
    Layout layout(const Shape& in) const;

    GemmParams p_;  // ku = 1: A is packed with Kpad = K
    int th_, tw_, cout_, cin_, stride_, pad_;
    bool transposed_;
    Act in_act_;
    Kernel pad_kernel_, gemm_;
    Buffer ap_;  // one packed A per phase, back to back
    std::size_t phase_floats_ = 0;
};

}  // namespace ngi::detail

// A dense layer over planar items on the GEMM micro-kernel, its input read in place:
//   y[o][i] = act(scale[o] * sum_k W[o][k] x[k][i] + shift[o]) (+ res[o][i])
// x is [in] rows of n items (row stride x_ld >= n); y and the optional residual are addressed as
// y_off + o * y_plane + i * y_item, so a layer can write planar [out][n] (y_item 1) or item-major [n][out]
// (y_plane 1, y_item out: the point list a host reads back, no transpose).
//
// Why not PackB + Gemm: the packed GEMM copies every layer's input into B panels first, a full pass over
// in x n floats (as long as the GEMM itself for a 128-wide layer over 10,000 items on PoCL), and a residual
// needs one more pass (elementwise add). gemm_conv (kernels/gemm.cl) with one tap reads x's rows directly
// (b_limit keeps the last tile inside them) and adds the residual in its epilogue. Fewer than NR items: the rows
// are first copied into zero-padded rows of NR (conv_pad), which needs scratch_floats(n).
// All knob sets run gemm_conv (which reads global memory; on a GPU set it runs at that set's tile and
// work-group shape), so one path serves every device.
#pragma once
#include <vector>

#include "ops/gemm.hpp"

namespace ngi::detail {

struct DenseOut {
    cl_mem mem = nullptr;
    std::size_t offset = 0;  // floats
    int plane = 0;           // floats between outputs o and o + 1
    int item = 1;            // floats between items i and i + 1
};

class Dense {
public:
    // weight: [out][in] row-major (nn.Linear's layout).
    Dense(Context& ctx, const GemmParams& p, int in, int out, const float* weight);
    int in() const { return in_; }
    int out() const { return out_; }
    std::size_t weight_bytes() const { return ap_.bytes(); }
    std::size_t scratch_floats(int n) const;  // 0 when n >= NR (x read in place)
    // residual: nullptr, or a buffer addressed as y (from res_offset). scale, shift: out floats each. With fewer
    // items than a tile (n < NR) the rows must be exactly n floats apart (x_ld == n); the zero-padding copy is a
    // second launch, which the returned event does not cover.
    cl_event enqueue(Context& ctx, cl_mem x, std::size_t x_off, int x_ld, int n, const DenseOut& y, cl_mem scale,
                     cl_mem shift, Act act, cl_mem residual, std::size_t res_offset, cl_mem scratch,
                     std::size_t scratch_off, bool want_event = false);

private:
    GemmParams p_;  // ku = 1: A is packed with Kpad = in
    int in_, out_;
    Kernel pad_, gemm_;
    Buffer ap_;
};

}  // namespace ngi::detail

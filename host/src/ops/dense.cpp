#include "ops/dense.hpp"

#include "ngi/error.hpp"
#include "ops/conv_implicit.hpp"

namespace ngi::detail {

namespace {

GemmParams one_step(GemmParams p) {
    p.ku = 1;  // gemm_conv walks exactly `in` rows: A is packed with Kpad = in
    return p;
}
}  // namespace

Dense::Dense(Context& ctx, const GemmParams& p, int in, int out, const float* weight)
    : p_(one_step(p)),
      in_(in),
      out_(out),
      pad_(ctx.kernel("im2col", "conv_pad", im2col_defines(p.nr()))),
      // The same build options as ImplicitConv's one-tap layers: one program for both.
      gemm_(ctx.kernel("gemm", "gemm_conv", gemm_kernel_defines(p_) + " -DIMPLICIT=1 -DTH=1 -DTW=1")) {
    if (in < 1 || out < 1) throw InputError("dense layer: " + std::to_string(in) + " -> " + std::to_string(out));
    const std::vector<float> packed = pack_a(weight, out, in, in, p_);
    ap_ = ctx.alloc(packed.size() * sizeof(float), "dense packed weights");
    ctx.write(ap_, 0, packed.size() * sizeof(float), packed.data(), "dense packed weights");
}

std::size_t Dense::scratch_floats(int n) const {
    return n < p_.nr() ? std::size_t(in_) * std::size_t(p_.nr()) : 0;
}

cl_event Dense::enqueue(Context& ctx, cl_mem x, std::size_t x_off, int x_ld, int n, const DenseOut& y, cl_mem scale,
                        cl_mem shift, Act act, cl_mem residual, std::size_t res_offset, cl_mem scratch,
                        std::size_t scratch_off, bool want_event) {
    const int nr = p_.nr();
    if (n < 1 || x_ld < n) throw Error("dense layer: " + std::to_string(n) + " items with row stride " + std::to_string(x_ld));
    cl_mem b = x;
    std::size_t b_off = x_off;
    int cs = x_ld, b_limit = n;
    if (n < nr) {  // rows shorter than a tile: zero-padded rows of NR in scratch, read with no limit
        if (x_ld != n) throw Error("dense layer: fewer items than a tile need rows of exactly n floats");
        pad_.args(x, int(x_off), in_, 1, n, 1, 0, 0, 1, nr, in_, nr, nr, scratch, int(scratch_off), 1.0f,
                  in_ * nr, 0);
        const std::size_t gp[2] = {1, std::size_t(in_)};
        ctx.launch(pad_, 2, gp, kPadLocal, false);
        b = scratch;
        b_off = scratch_off;
        cs = nr;
        b_limit = 0;
    }
    gemm_.args(out_, in_, in_, ap_.get(), 0, b, int(b_off), cs, cs, 1, 1, 0, 1, n, y.mem, int(y.offset), y.plane, 0, 1,
               y.item, scale, shift, int(act.kind), act.alpha, b_limit, residual ? residual : y.mem,
               residual ? int(res_offset) : 0, residual ? 1 : 0, 0, 0, 0);
    const std::size_t global[2] = {std::size_t((out_ + p_.mr - 1) / p_.mr), std::size_t((n + nr - 1) / nr)};
    const std::size_t local[2] = {std::size_t(p_.local0), std::size_t(p_.local1)};
    return ctx.launch(gemm_, 2, global, local, want_event);
}

}  // namespace ngi::detail

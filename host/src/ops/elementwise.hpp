// In-place elementwise ops: activation, seeded dropout, NaN/Inf sanitizing.
#pragma once
#include <cstdint>

#include "ops/view.hpp"
#include "ops/op_types.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

class Elementwise {
public:
    explicit Elementwise(Context& ctx);
    cl_event activate(Context& ctx, const View& x, Act act, bool want_event = false);
    // Inverted dropout; the mask is a hash of (seed, site, flat index): see kernels/elementwise.cl.
    cl_event dropout(Context& ctx, const View& x, std::uint32_t seed, std::uint32_t site, float p,
                     bool want_event = false);
    // Replaces NaN with 0 and values beyond [lo, hi] widened by (hi - lo) / 1024 on each side (+-Inf included)
    // with lo or hi. Only enqueues: the count of replaced values is read
    // by sanitized_count() (which blocks), so a caller can read it after its own work instead of stalling here.
    void sanitize(Context& ctx, const View& x, float lo, float hi);
    int sanitized_count(Context& ctx);
    // y (planar [channels][n] from y_off floats) = scale[c] * x + shift[c], with item i's channel c of x at
    // x_off + i * item_stride + c * channel_stride floats (a point list [n][C] is {C, 1}: transposed on the way).
    // scale and shift hold `channels` floats. NaN stays NaN and overflow gives +-Inf: sanitize y afterwards.
    cl_event channel_affine(Context& ctx, cl_mem x, std::size_t x_off, int item_stride, int channel_stride,
                            int channels, int n, cl_mem scale, cl_mem shift, cl_mem y, std::size_t y_off,
                            bool want_event = false);
    // x += y (same shape, no overlap): a residual connection.
    cl_event add(Context& ctx, const View& x, const View& y, bool want_event = false);
    // x *= y (same shape, no overlap).
    cl_event mul(Context& ctx, const View& x, const View& y, bool want_event = false);

private:
    Kernel act_, dropout_, sanitize_, affine_, add_, mul_;
    Buffer counter_;
};

}  // namespace ngi::detail

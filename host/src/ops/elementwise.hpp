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

private:
    Kernel act_, dropout_, sanitize_;
    Buffer counter_;
};

}  // namespace ngi::detail

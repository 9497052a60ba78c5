#include "ops/elementwise.hpp"

#include <cmath>

namespace ngi::detail {

namespace {
const std::size_t kLocal[1] = {64};
}

Elementwise::Elementwise(Context& ctx)
    : act_(ctx.kernel("elementwise", "activate_inplace")),
      dropout_(ctx.kernel("elementwise", "dropout_seeded")),
      sanitize_(ctx.kernel("elementwise", "sanitize_inplace")),
      counter_(ctx.alloc(sizeof(int), "sanitize counter")) {}

cl_event Elementwise::activate(Context& ctx, const View& x, Act act, bool want_event) {
    const int n = int(x.shape.size());
    act_.args(x.mem, int(x.offset), n, int(act.kind), act.alpha);
    const std::size_t g[1] = {std::size_t(n)};
    return ctx.launch(act_, 1, g, kLocal, want_event);
}

cl_event Elementwise::dropout(Context& ctx, const View& x, std::uint32_t seed, std::uint32_t site, float p,
                              bool want_event) {
    if (!(p >= 0.0f && p < 1.0f)) throw InputError("dropout: probability " + std::to_string(p) + " not in [0, 1)");
    const int n = int(x.shape.size());
    dropout_.args(x.mem, int(x.offset), n, cl_uint(seed), cl_uint(site), p);
    const std::size_t g[1] = {std::size_t(n)};
    return ctx.launch(dropout_, 1, g, kLocal, want_event);
}

void Elementwise::sanitize(Context& ctx, const View& x, float lo, float hi) {
    const int n = int(x.shape.size());
    ctx.fill_zero(counter_, 0, sizeof(int), "sanitize counter");  // enqueued; the pattern is copied at once
    // The tolerance band: 1/1024 of the range's width on each side. Without limits (+-FLT_MAX, whose width
    // overflows) the band is empty and only +-Inf is clamped.
    const float tol = (hi - lo) * (1.0f / 1024.0f);
    float below = lo - tol, above = hi + tol;
    if (!std::isfinite(below)) below = lo;
    if (!std::isfinite(above)) above = hi;
    sanitize_.args(x.mem, int(x.offset), n, lo, hi, below, above, counter_);
    const std::size_t g[1] = {std::size_t(n)};
    ctx.launch(sanitize_, 1, g, kLocal);
}

int Elementwise::sanitized_count(Context& ctx) {
    int bad = 0;
    ctx.read(counter_, 0, sizeof bad, &bad, "sanitize counter");
    return bad;
}

}  // namespace ngi::detail

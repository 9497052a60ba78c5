#include "ops/elementwise.hpp"

#include <cmath>

namespace ngi::detail {

namespace {
const std::size_t kLocal[1] = {64};
// kernels/elementwise.cl after the activation helper.
const std::string kProgram = "elementwise";
const std::size_t kLocal2[2] = {64, 1};
// Values per work-item of sanitize_inplace (one float16): the kernel's SANITIZE_VEC.
constexpr std::size_t kSanitizeVec = 16;
// The program's build options: the activation codes and SANITIZE_VEC (the same for every kernel: one program).
std::string elementwise_defines() { return activation_defines() + " -DSANITIZE_VEC=" + std::to_string(kSanitizeVec); }
}

Elementwise::Elementwise(Context& ctx)
    : act_(ctx.kernel(kProgram, "activate_inplace", elementwise_defines())),
      dropout_(ctx.kernel(kProgram, "dropout_seeded", elementwise_defines())),
      sanitize_(ctx.kernel(kProgram, "sanitize_inplace", elementwise_defines())),
      affine_(ctx.kernel(kProgram, "channel_affine_planar", elementwise_defines())),
      add_(ctx.kernel(kProgram, "add_inplace", elementwise_defines())),
      mul_(ctx.kernel(kProgram, "mul_inplace", elementwise_defines())),
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
    const std::size_t g[1] = {(std::size_t(n) + kSanitizeVec - 1) / kSanitizeVec};
    ctx.launch(sanitize_, 1, g, kLocal);
}

int Elementwise::sanitized_count(Context& ctx) {
    int bad = 0;
    ctx.read(counter_, 0, sizeof bad, &bad, "sanitize counter");
    return bad;
}

cl_event Elementwise::channel_affine(Context& ctx, cl_mem x, std::size_t x_off, int item_stride, int channel_stride,
                                     int channels, int n, cl_mem scale, cl_mem shift, cl_mem y, std::size_t y_off,
                                     bool want_event) {
    if (n <= 0 || channels <= 0) return nullptr;
    affine_.args(x, int(x_off), item_stride, channel_stride, channels, n, scale, shift, y, int(y_off));
    const std::size_t g[2] = {std::size_t(n), std::size_t(channels)};
    return ctx.launch(affine_, 2, g, kLocal2, want_event);
}

cl_event Elementwise::add(Context& ctx, const View& x, const View& y, bool want_event) {
    if (x.shape.size() != y.shape.size())
        throw InputError("add: shapes " + to_string(x.shape) + " and " + to_string(y.shape) + " differ");
    const int n = int(x.shape.size());
    if (n <= 0) return nullptr;
    add_.args(x.mem, int(x.offset), y.mem, int(y.offset), n);
    const std::size_t g[1] = {std::size_t(n)};
    return ctx.launch(add_, 1, g, kLocal, want_event);
}

cl_event Elementwise::mul(Context& ctx, const View& x, const View& y, bool want_event) {
    if (x.shape.size() != y.shape.size())
        throw InputError("mul: shapes " + to_string(x.shape) + " and " + to_string(y.shape) + " differ");
    const int n = int(x.shape.size());
    if (n <= 0) return nullptr;
    mul_.args(x.mem, int(x.offset), y.mem, int(y.offset), n);
    const std::size_t g[1] = {std::size_t(n)};
    return ctx.launch(mul_, 1, g, kLocal, want_event);
}

}  // namespace ngi::detail

#include "ops/resize.hpp"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

#include "ops/buffer_checks.hpp"

namespace ngi::detail {

namespace {

constexpr const char* kResizeOp = "resize_bilinear";

// The shortest decimal that reads back as v ("0.6", "1e-30", "nan", "inf").
std::string float_text(float v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

std::string resize_text(const ResizeGeometry& g) {
    return "output " + std::to_string(g.out_h) + "x" + std::to_string(g.out_w) + ", scales " + float_text(g.scale_h) +
           " x " + float_text(g.scale_w) + ", mode " + resize_coord_name(g.mode);
}

// An axis' source positions s(o) = (a o + b) / d (d > 0, a >= 0), and the step to the second tap (0 on an axis
// the resize leaves unchanged).
struct AxisMap {
    std::int64_t a = 0, b = 0, d = 1;
    int step = 1;
};

// The exact rational of the mode's formula (resize.hpp) along an axis of `in` input and `out` output pixels, with
// the axis' scale (0: out / in). A float scale is M 2^E with M an integer below 2^24, so 1 / scale = 2^-E / M.
AxisMap axis_map(int in, int out, float scale, ResizeCoord mode, const char* axis) {
    AxisMap m;
    const bool single = out == 1 && (mode == ResizeCoord::PytorchHalfPixel || mode == ResizeCoord::AlignCorners);
    // Limits: the kernel computes a o + b and (in - 1) d in 64-bit integers; 2^61 leaves a margin over doubles'
    // rounding in the checks below.
    const double limit = 2305843009213693952.0;  // 2^61
    auto too_far = [&](const std::string& why) {
        return InputError(std::string(kResizeOp) + ": the " + axis + " scale " + float_text(scale) + " with input " + axis +
                          " " + std::to_string(in) + " and output " + axis + " " + std::to_string(out) + ": " + why);
    };
    if (single) {
        m = {0, 0, 1, 1};
    } else if (mode == ResizeCoord::AlignCorners) {
        m = {in - 1, 0, out - 1, 1};
    } else if (scale == 0.0f) {  // scale = out / in
        if (mode == ResizeCoord::Asymmetric)
            m = {in, 0, out, 1};  // s = o in / out
        else
            m = {2LL * in, (std::int64_t)in - out, 2LL * out, 1};  // s = ((2 o + 1) in - out) / (2 out)
    } else {
        int e = 0;
        const double frac = std::frexp(double(scale), &e);  // scale = frac 2^e, frac in [0.5, 1)
        std::int64_t M = std::int64_t(std::ldexp(frac, 24));  // exact: a float has 24 significant bits
        int E = e - 24;
        while (M % 2 == 0) {
            M /= 2;
            ++E;
        }
        // 1 / scale = P / Q with P = 2^-E, Q = M (E < 0) or P = 1, Q = M 2^E (E >= 0).
        if (E <= -60 || E >= 36) throw too_far("1 / scale is not a ratio of integers below 2^60");
        const std::int64_t P = E < 0 ? (std::int64_t(1) << -E) : 1;
        const std::int64_t Q = E < 0 ? M : (M << E);
        if (mode == ResizeCoord::Asymmetric)
            m = {P, 0, Q, 1};  // s = o P / Q
        else
            m = {2 * P, P - Q, 2 * Q, 1};  // s = (o + 1/2) P / Q - 1/2 = ((2 o + 1) P - Q) / (2 Q)
    }
    // Lowest terms (the same positions, smaller numbers).
    const std::int64_t g = std::gcd(std::gcd(m.a, m.b < 0 ? -m.b : m.b), m.d);
    if (g > 1) {
        m.a /= g;
        m.b /= g;
        m.d /= g;
    }
    if (double(m.a) * double(out - 1) + std::abs(double(m.b)) > limit || double(m.d) * double(in) > limit)
        throw too_far("the source positions do not fit 64-bit integers (a scale that far from output / input?)");
    // An unchanged axis (s(o) = o everywhere) reads one pixel per output, as PyTorch's copy when out == in.
    if (out == in && m.a == m.d && m.b == 0) m.step = 0;
    return m;
}

}  // namespace

std::string resize_coord_name(ResizeCoord m) {
    switch (m) {
        case ResizeCoord::HalfPixel: return "half_pixel";
        case ResizeCoord::PytorchHalfPixel: return "pytorch_half_pixel";
        case ResizeCoord::AlignCorners: return "align_corners";
        case ResizeCoord::Asymmetric: return "asymmetric";
    }
    return "mode " + std::to_string(int(m));
}

ResizeBilinear::ResizeBilinear(Context& ctx, const ResizeGeometry& geom) : geom_(geom) {
    const auto& g = geom;
    if (g.mode != ResizeCoord::HalfPixel && g.mode != ResizeCoord::PytorchHalfPixel &&
        g.mode != ResizeCoord::AlignCorners && g.mode != ResizeCoord::Asymmetric)
        throw InputError(std::string(kResizeOp) + ": unknown coordinate transformation mode " + std::to_string(int(g.mode)) +
                         " (half_pixel 0, pytorch_half_pixel 1, align_corners 2, asymmetric 3)");
    if (g.out_h < 1 || g.out_w < 1)
        throw InputError(std::string(kResizeOp) + ": invalid geometry (" + resize_text(g) +
                         "): the output size must be >= 1");
    for (const auto& [scale, axis] : {std::pair{g.scale_h, "height"}, std::pair{g.scale_w, "width"}})
        if (!std::isfinite(scale) || scale < 0.0f)
            throw InputError(std::string(kResizeOp) + ": invalid geometry (" + resize_text(g) + "): the " + axis +
                             " scale must be positive and finite (0: output / input)");
    kernel_ = ctx.kernel("resize", "resize_bilinear", resize_defines());
}

Shape ResizeBilinear::output_shape(const Shape& in) const {
    if (in.c < 1 || in.h < 1 || in.w < 1) throw InputError(std::string(kResizeOp) + ": empty input " + to_string(in));
    const auto& g = geom_;
    const Shape out{in.c, g.out_h, g.out_w};
    // The kernel indexes outputs and input planes with 32-bit ints.
    if (in.size() > std::size_t(INT_MAX) || out.size() > std::size_t(INT_MAX))
        throw InputError(std::string(kResizeOp) + ": input " + to_string(in) + " or output " + to_string(out) +
                         " holds 2^31 floats or more");
    axis_map(in.h, out.h, g.scale_h, g.mode, "height");
    axis_map(in.w, out.w, g.scale_w, g.mode, "width");
    return out;
}

void ResizeBilinear::enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events) {
    const Shape out = output_shape(x.shape);
    if (!(y.shape == out))
        throw InputError(std::string(kResizeOp) + ": the output is " + to_string(y.shape) + ", input " + to_string(x.shape) +
                         " resizes to " + to_string(out));
    if (!x.mem || !y.mem) throw InputError(std::string(kResizeOp) + ": the " + (x.mem ? "output" : "input") + " buffer is null");
    require_int_indexable(x, kResizeOp, "input");
    require_int_indexable(y, kResizeOp, "output");
    const auto& g = geom_;
    const AxisMap mh = axis_map(x.shape.h, out.h, g.scale_h, g.mode, "height");
    const AxisMap mw = axis_map(x.shape.w, out.w, g.scale_w, g.mode, "width");
    kernel_.args(x.mem, int(x.offset), x.shape.c, x.shape.h, x.shape.w, y.mem, int(y.offset), out.h, out.w,
                 cl_long(mh.a), cl_long(mh.b), cl_long(mh.d), mh.step, cl_long(mw.a), cl_long(mw.b), cl_long(mw.d),
                 mw.step);
    const std::size_t global[1] = {out.size()};
    const std::size_t local[1] = {std::size_t(kResizeLocal)};
    cl_event e = ctx.launch(kernel_, 1, global, local, events != nullptr);
    if (events && e) events->push_back(e);
}

}  // namespace ngi::detail

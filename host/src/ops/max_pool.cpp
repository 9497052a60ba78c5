#include "ops/max_pool.hpp"

#include <climits>
#include <string>

#include "ops/buffer_checks.hpp"

namespace ngi::detail {

namespace {

constexpr const char* kMaxPoolOp = "max_pool2d";

std::string max_pool_text(const MaxPoolGeometry& g) {
    return "kernel " + std::to_string(g.kh) + "x" + std::to_string(g.kw) + ", stride " + std::to_string(g.stride_h) +
           "x" + std::to_string(g.stride_w) + ", pads top " + std::to_string(g.pad_top) + " left " +
           std::to_string(g.pad_left) + " bottom " + std::to_string(g.pad_bottom) + " right " +
           std::to_string(g.pad_right);
}

void check_geometry(const MaxPoolGeometry& g) {
    if (g.kh < 1 || g.kw < 1 || g.stride_h < 1 || g.stride_w < 1 || g.pad_top < 0 || g.pad_left < 0 ||
        g.pad_bottom < 0 || g.pad_right < 0)
        throw InputError(std::string(kMaxPoolOp) + ": invalid geometry (" + max_pool_text(g) +
                         "): kernel and stride must be >= 1, pads >= 0");
    // A pad as large as its kernel side would let a window lie wholly in the padding (no value to take; ONNX gives
    // -Inf there, PyTorch refuses pads above half the kernel).
    const struct {
        const char* side;
        int pad, k;
        const char* k_name;
    } pads[] = {{"top", g.pad_top, g.kh, "height"},
                {"bottom", g.pad_bottom, g.kh, "height"},
                {"left", g.pad_left, g.kw, "width"},
                {"right", g.pad_right, g.kw, "width"}};
    for (const auto& p : pads)
        if (p.pad >= p.k)
            throw InputError(std::string(kMaxPoolOp) + ": the " + p.side + " padding " + std::to_string(p.pad) +
                             " is not below the kernel " + p.k_name + " " + std::to_string(p.k) + " (" +
                             max_pool_text(g) + ")");
}

// Output size along one axis (ceil_mode 0); throws when the kernel is larger than the padded input.
int out_size(int in, int k, int stride, int pad_lo, int pad_hi, const char* axis) {
    const long long padded = (long long)in + pad_lo + pad_hi;
    if (padded < k)
        throw InputError(std::string(kMaxPoolOp) + ": input " + axis + " " + std::to_string(in) + " (padded " +
                         std::to_string(padded) + ") is smaller than the kernel " + axis + " " + std::to_string(k));
    return int((padded - k) / stride + 1);
}

}  // namespace

MaxPool2d::MaxPool2d(Context& ctx, const MaxPoolGeometry& geom) : geom_(geom) {
    check_geometry(geom);
    // Each work-item's inner loop runs up to kh * kw times: keep it below the driver's loop limit (llvmpipe 65535).
    const long long taps = (long long)geom.kh * geom.kw;
    if (const long limit = ctx.loop_limit(); limit > 0 && taps > limit)
        throw InputError(std::string(kMaxPoolOp) + ": a " + std::to_string(geom.kh) + "x" + std::to_string(geom.kw) +
                         " window is " + std::to_string(taps) + " taps, more than this device's loop limit of " +
                         std::to_string(limit) + " iterations");
    kernel_ = ctx.kernel("max_pool", "max_pool2d", max_pool_defines());
}

Shape MaxPool2d::output_shape(const Shape& in) const {
    if (in.c < 1 || in.h < 1 || in.w < 1)
        throw InputError(std::string(kMaxPoolOp) + ": empty input " + to_string(in));
    const auto& g = geom_;
    const Shape out{in.c, out_size(in.h, g.kh, g.stride_h, g.pad_top, g.pad_bottom, "height"),
                    out_size(in.w, g.kw, g.stride_w, g.pad_left, g.pad_right, "width")};
    // The kernel indexes outputs and input planes with 32-bit ints.
    if (in.size() > std::size_t(INT_MAX) || out.size() > std::size_t(INT_MAX))
        throw InputError(std::string(kMaxPoolOp) + ": input " + to_string(in) + " or output " + to_string(out) +
                         " holds 2^31 floats or more");
    return out;
}

void MaxPool2d::enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events) {
    const Shape out = output_shape(x.shape);
    if (!(y.shape == out))
        throw InputError(std::string(kMaxPoolOp) + ": the output is " + to_string(y.shape) + ", input " + to_string(x.shape) +
                         " pools to " + to_string(out));
    if (!x.mem || !y.mem) throw InputError(std::string(kMaxPoolOp) + ": the " + (x.mem ? "output" : "input") + " buffer is null");
    require_int_indexable(x, kMaxPoolOp, "input");
    require_int_indexable(y, kMaxPoolOp, "output");
    const auto& g = geom_;
    kernel_.args(x.mem, int(x.offset), x.shape.c, x.shape.h, x.shape.w, y.mem, int(y.offset), out.h, out.w, g.kh, g.kw,
                 g.stride_h, g.stride_w, g.pad_top, g.pad_left);
    const std::size_t global[1] = {out.size()};
    const std::size_t local[1] = {std::size_t(kMaxPoolLocal)};
    cl_event e = ctx.launch(kernel_, 1, global, local, events != nullptr);
    if (events && e) events->push_back(e);
}

}  // namespace ngi::detail

#include "ops/pad2d.hpp"

#include <charconv>
#include <climits>
#include <string>

#include "ops/buffer_checks.hpp"

namespace ngi::detail {

namespace {

constexpr const char* kPad2dOp = "pad2d";

std::string pad_text(const PadGeometry& g) {
    std::string s = "pads top " + std::to_string(g.top) + " left " + std::to_string(g.left) + " bottom " +
                    std::to_string(g.bottom) + " right " + std::to_string(g.right) + ", mode " + pad_mode_name(g.mode);
    if (g.mode == PadMode::Constant) {
        // The value as the shortest decimal that reads back as it.
        char buf[64];
        const auto r = std::to_chars(buf, buf + sizeof buf, g.value);
        s += " " + std::string(buf, r.ptr);
    }
    return s;
}

}  // namespace

std::string pad_mode_name(PadMode m) {
    switch (m) {
        case PadMode::Constant: return "constant";
        case PadMode::Reflect: return "reflect";
        case PadMode::Edge: return "edge";
    }
    return "mode " + std::to_string(int(m));
}

Pad2d::Pad2d(Context& ctx, const PadGeometry& geom) : geom_(geom) {
    const auto& g = geom;
    if (g.mode != PadMode::Constant && g.mode != PadMode::Reflect && g.mode != PadMode::Edge)
        throw InputError(std::string(kPad2dOp) + ": unknown mode " + std::to_string(int(g.mode)) +
                         " (constant 0, reflect 1, edge 2)");
    kernel_ = ctx.kernel("pad2d", "pad2d", pad2d_defines());
}

Shape Pad2d::output_shape(const Shape& in) const {
    if (in.c < 1 || in.h < 1 || in.w < 1) throw InputError(std::string(kPad2dOp) + ": empty input " + to_string(in));
    const auto& g = geom_;
    if (g.mode == PadMode::Reflect) {
        // A reflection about the edge pixel that does not repeat it reaches n - 1 pixels into the plane at most
        // (ONNX and PyTorch refuse larger pads too).
        const struct {
            const char* side;
            int pad, size;
            const char* axis;
        } pads[] = {{"top", g.top, in.h, "height"},
                    {"bottom", g.bottom, in.h, "height"},
                    {"left", g.left, in.w, "width"},
                    {"right", g.right, in.w, "width"}};
        for (const auto& p : pads)
            if (p.pad >= p.size)
                throw InputError(std::string(kPad2dOp) + ": the reflect " + p.side + " padding " + std::to_string(p.pad) +
                                 " is not below the input " + p.axis + " " + std::to_string(p.size) + " (input " +
                                 to_string(in) + ", " + pad_text(g) + ")");
    }
    const long long oh = (long long)in.h + g.top + g.bottom, ow = (long long)in.w + g.left + g.right;
    if (oh < 1 || ow < 1)  // negative pads crop (ONNX Pad allows them): not the whole input
        throw InputError(std::string(kPad2dOp) + ": " + pad_text(g) + " crops the whole input " + to_string(in));
    // The kernel indexes outputs and input planes with 32-bit ints.
    if (in.size() > std::size_t(INT_MAX) || oh > INT_MAX || ow > INT_MAX || (long long)in.c * oh * ow > INT_MAX)
        throw InputError(std::string(kPad2dOp) + ": input " + to_string(in) + " or its padded output " +
                         std::to_string(in.c) + "x" + std::to_string(oh) + "x" + std::to_string(ow) +
                         " holds 2^31 floats or more");
    return Shape{in.c, int(oh), int(ow)};
}

void Pad2d::enqueue(Context& ctx, const View& x, const View& y, std::vector<cl_event>* events) {
    const Shape out = output_shape(x.shape);
    if (!(y.shape == out))
        throw InputError(std::string(kPad2dOp) + ": the output is " + to_string(y.shape) + ", input " + to_string(x.shape) +
                         " pads to " + to_string(out));
    if (!x.mem || !y.mem) throw InputError(std::string(kPad2dOp) + ": the " + (x.mem ? "output" : "input") + " buffer is null");
    require_int_indexable(x, kPad2dOp, "input");
    require_int_indexable(y, kPad2dOp, "output");
    const auto& g = geom_;
    kernel_.args(x.mem, int(x.offset), x.shape.c, x.shape.h, x.shape.w, y.mem, int(y.offset), out.h, out.w, g.top,
                 g.left, int(g.mode), g.value);
    const std::size_t global[1] = {out.size()};
    const std::size_t local[1] = {std::size_t(kPad2dLocal)};
    cl_event e = ctx.launch(kernel_, 1, global, local, events != nullptr);
    if (events && e) events->push_back(e);
}

}  // namespace ngi::detail

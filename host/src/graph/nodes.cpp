// The longer bodies of the node adapters of graph/nodes.hpp.
#include "graph/nodes.hpp"

#include <cmath>

namespace ngi::detail {

Shape BinaryNode::infer(const std::vector<Shape>& in) const {
    if (in.size() != 2) throw InputError(kind() + " takes two inputs");
    if (!(in[0] == in[1]))
        throw InputError(kind() + ": the inputs are " + to_string(in[0]) + " and " + to_string(in[1]) +
                         " (no broadcasting between computed tensors)");
    return in[0];
}

BroadcastNode::BroadcastNode(Context& ctx, bool mul, int channels) : ew_(ctx), mul_(mul), channels_(channels) {
    const std::vector<float> ones(std::size_t(channels), 1.0f), zeros(std::size_t(channels), 0.0f);
    operand_ = ctx.alloc(std::size_t(channels) * sizeof(float), "graph broadcast operand");
    fixed_ = ctx.alloc(std::size_t(channels) * sizeof(float), "graph broadcast identity");
    ctx.write(fixed_, 0, std::size_t(channels) * sizeof(float), mul ? zeros.data() : ones.data(),
              "graph broadcast identity");
}

Shape BroadcastNode::infer(const std::vector<Shape>& in) const {
    if (in.size() != 2) throw InputError(kind() + " takes two inputs");
    if (in[0].c != channels_ || !(in[1] == Shape{channels_, 1, 1}))
        throw InputError(kind() + ": the inputs are " + to_string(in[0]) + " and " + to_string(in[1]) +
                         "; the second must be " + std::to_string(channels_) + "x1x1 (one value a channel)");
    return in[0];
}

void BroadcastNode::enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem,
                            std::vector<cl_event>* ev) {
    ctx.copy(in[1].mem, in[1].offset * sizeof(float), operand_.get(), 0, std::size_t(channels_) * sizeof(float),
             "graph broadcast operand");
    const int n = in[0].shape.h * in[0].shape.w;
    cl_event e = ew_.channel_affine(ctx, in[0].mem, in[0].offset, 1, n, channels_, n,
                                    mul_ ? operand_.get() : fixed_.get(), mul_ ? fixed_.get() : operand_.get(),
                                    out.mem, out.offset, ev != nullptr);
    if (ev && e) ev->push_back(e);
}

AffineNode::AffineNode(Context& ctx, const std::vector<float>& scale, const std::vector<float>& shift)
    : ew_(ctx), channels_(int(scale.size())) {
    scale_ = ctx.alloc(scale.size() * sizeof(float), "graph affine scale");
    shift_ = ctx.alloc(shift.size() * sizeof(float), "graph affine shift");
    ctx.write(scale_, 0, scale.size() * sizeof(float), scale.data(), "graph affine scale");
    ctx.write(shift_, 0, shift.size() * sizeof(float), shift.data(), "graph affine shift");
}

Shape AffineNode::infer(const std::vector<Shape>& in) const {
    const Shape& s = ConvNode::one(in);
    if (s.c != channels_)
        throw InputError("affine: the input has " + std::to_string(s.c) + " channels, the node " +
                         std::to_string(channels_));
    return s;
}

void AffineNode::enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem,
                         std::vector<cl_event>* ev) {
    const int n = in[0].shape.h * in[0].shape.w;
    cl_event e = ew_.channel_affine(ctx, in[0].mem, in[0].offset, 1, n, channels_, n, scale_.get(), shift_.get(),
                                    out.mem, out.offset, ev != nullptr);
    if (ev && e) ev->push_back(e);
}

Shape GroupNormNode::infer(const std::vector<Shape>& in) const {
    const Shape& s = ConvNode::one(in);
    if (s.c != channels_)
        throw InputError("group_norm: the input has " + std::to_string(s.c) + " channels, the node " +
                         std::to_string(channels_));
    return s;
}

void GroupNormNode::enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem scratch,
                            std::vector<cl_event>* ev) {
    const Shape& s = in[0].shape;
    bn_.enqueue(ctx, View{in[0].mem, in[0].offset, {groups_, 1, channels_ / groups_ * s.h * s.w}}, scratch, 0, ev);
}

Shape ResizeNode::infer(const std::vector<Shape>& in) const {
    const Shape& s = ConvNode::one(in);
    if (out_h_ > 0) return op(out_h_, out_w_).output_shape(s);
    const float ph = float(s.h) * scale_h_, pw = float(s.w) * scale_w_;  // a float32 product (FLT_EVAL_METHOD 0)
    const double oh = std::floor(double(ph)), ow = std::floor(double(pw));
    if (!(oh >= 1 && ow >= 1 && oh <= kMaxDim && ow <= kMaxDim))
        throw InputError("resize_bilinear: scales " + std::to_string(scale_h_) + " x " + std::to_string(scale_w_) +
                         " make " + to_string(s) + " an output of " + std::to_string(oh) + " x " +
                         std::to_string(ow) + " (each side 1.." + std::to_string(kMaxDim) + ")");
    return op(int(oh), int(ow)).output_shape(s);
}

ResizeBilinear& ResizeNode::op(int oh, int ow) const {
    auto& r = ops_[{oh, ow}];
    if (!r) r = std::make_unique<ResizeBilinear>(ctx_, ResizeGeometry{oh, ow, scale_h_, scale_w_, mode_});
    return *r;
}

}  // namespace ngi::detail

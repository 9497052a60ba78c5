// Graph adapters over the ops in host/src/ops (one small class per op; no model knowledge).
#pragma once
#include <memory>

#include "graph/graph.hpp"
#include "ops/conv.hpp"
#include "ops/elementwise.hpp"
#include "ops/mlp.hpp"
#include "ops/norm.hpp"

namespace ngi::detail {

class ConvNode : public Op {
public:
    template <class... A>
    explicit ConvNode(A&&... a) : conv_(std::forward<A>(a)...) {}
    std::string kind() const override { return "conv2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return conv_.output_shape(one(in)); }
    std::size_t scratch_floats(const std::vector<Shape>& in) const override { return conv_.scratch_floats(one(in)); }
    double flops(const std::vector<Shape>& in) const override {
        const Shape o = conv_.output_shape(in[0]);
        const auto& s = conv_.spec();
        return 2.0 * s.cout * s.cin * s.geom.kh * s.geom.kw * o.h * o.w;
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem scratch,
                 std::vector<cl_event>* ev) override {
        conv_.enqueue(ctx, in[0], out, scratch, 0, ev);
    }
    static const Shape& one(const std::vector<Shape>& in) {
        if (in.size() != 1) throw InputError("conv2d takes one input");
        return in[0];
    }

private:
    Conv2d conv_;
};

class ConvTransposeNode : public Op {
public:
    template <class... A>
    explicit ConvTransposeNode(A&&... a) : conv_(std::forward<A>(a)...) {}
    std::string kind() const override { return "conv_transpose2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return conv_.output_shape(ConvNode::one(in)); }
    std::size_t scratch_floats(const std::vector<Shape>& in) const override {
        return conv_.scratch_floats(ConvNode::one(in));
    }
    double flops(const std::vector<Shape>& in) const override {
        const auto& s = conv_.spec();
        return 2.0 * s.cout * s.cin * s.geom.kh * s.geom.kw * in[0].h * in[0].w;
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem scratch,
                 std::vector<cl_event>* ev) override {
        conv_.enqueue(ctx, in[0], out, scratch, 0, ev);
    }

private:
    ConvTranspose2d conv_;
};

class BatchNormNode : public Op {
public:
    template <class... A>
    explicit BatchNormNode(A&&... a) : bn_(std::forward<A>(a)...) {}
    std::string kind() const override { return "batch_norm_per_image"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    std::size_t scratch_floats(const std::vector<Shape>& in) const override { return bn_.scratch_floats(in[0]); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem scratch,
                 std::vector<cl_event>* ev) override {
        bn_.enqueue(ctx, in[0], scratch, 0, ev);
    }

private:
    BatchNormPerImage bn_;
};

class DropoutNode : public Op {
public:
    DropoutNode(Context& ctx, std::uint32_t seed, std::uint32_t site, float p)
        : ew_(ctx), seed_(seed), site_(site), p_(p) {}
    std::string kind() const override { return "dropout_seeded"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = ew_.dropout(ctx, in[0], seed_, site_, p_, ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    std::uint32_t seed_, site_;
    float p_;
};

// A copy of its input: lets one tensor take part in a second concat (a concat places its members inside itself,
// so a tensor can live inside only one), e.g. Neural GI's MLP input re-injected at the middle layer (DeepSDF).
class CopyNode : public Op {
public:
    std::string kind() const override { return "copy"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>*) override {
        ctx.copy(in[0].mem, in[0].offset * sizeof(float), out.mem, out.offset * sizeof(float),
                 in[0].shape.size() * sizeof(float), "graph copy node");
    }
};

// The frequency (positional) encoding of every pixel: C channels -> encoding.width(C) (docs/CONVENTIONS.md
// section 13).
class FrequencyEncodeNode : public Op {
public:
    FrequencyEncodeNode(Context& ctx, int inputs, const FrequencyEncoding& encoding) : encode_(ctx, inputs, encoding) {}
    std::string kind() const override { return "frequency_encode"; }
    Shape infer(const std::vector<Shape>& in) const override {
        const Shape& s = ConvNode::one(in);
        if (s.c != encode_.inputs())
            throw InputError("frequency encoding: the input has " + std::to_string(s.c) + " channels, the encoding takes " +
                             std::to_string(encode_.inputs()));
        return {encode_.width(), s.h, s.w};
    }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = encode_.enqueue(ctx, in[0].mem, in[0].offset, out.mem, out.offset, in[0].shape.h * in[0].shape.w,
                                     ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    FrequencyEncodePlanar encode_;
};

}  // namespace ngi::detail

// Graph adapters over the ops in host/src/ops (one small class per op; no model knowledge): every node kind a graph
// is built from. The bodies longer than a line or two are in nodes.cpp. What a model file calls each node is
// graph/node_kind.hpp; the families' builders in host/src/models make these nodes.
#pragma once
#include <cfloat>
#include <map>
#include <memory>
#include <utility>

#include "graph/graph.hpp"
#include "ops/conv.hpp"
#include "ops/elementwise.hpp"
#include "ops/max_pool.hpp"
#include "ops/mlp.hpp"
#include "ops/norm.hpp"
#include "ops/pad2d.hpp"
#include "ops/resize.hpp"
#include "ops/set_pool.hpp"

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

// y = act(x), in place.
class ActivationNode : public Op {
public:
    ActivationNode(Context& ctx, Act act) : ew_(ctx), act_(act) {}
    std::string kind() const override { return "activation"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = ew_.activate(ctx, in[0], act_, ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    Act act_;
};

// torch.nan_to_num(x) with its defaults: NaN -> 0, +-Inf -> +-FLT_MAX, in place. The sanitize kernel with the
// float range as limits (its own counter, so the graph input's count is not touched).
class NanToNumNode : public Op {
public:
    explicit NanToNumNode(Context& ctx) : ew_(ctx) {}
    std::string kind() const override { return "nan_to_num"; }
    Shape infer(const std::vector<Shape>& in) const override { return ConvNode::one(in); }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>*) override {
        ew_.sanitize(ctx, in[0], -FLT_MAX, FLT_MAX);
    }

private:
    Elementwise ew_;
};

// x += y or x *= y (same shape), in place on input 0.
class BinaryNode : public Op {
public:
    BinaryNode(Context& ctx, bool mul) : ew_(ctx), mul_(mul) {}
    std::string kind() const override { return mul_ ? "mul" : "add"; }
    Shape infer(const std::vector<Shape>& in) const override;
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem, std::vector<cl_event>* ev) override {
        cl_event e = mul_ ? ew_.mul(ctx, in[0], in[1], ev != nullptr) : ew_.add(ctx, in[0], in[1], ev != nullptr);
        if (ev && e) ev->push_back(e);
    }

private:
    Elementwise ew_;
    bool mul_;
};

// y = x * s or x + s with s of shape C x 1 x 1 (a squeeze-excitation's channel weights): s is copied into the
// scale (or shift) of a per-channel affine. Not in place (the affine kernel's input and output are restrict).
class BroadcastNode : public Op {
public:
    BroadcastNode(Context& ctx, bool mul, int channels);
    std::string kind() const override { return mul_ ? "mul (broadcast)" : "add (broadcast)"; }
    Shape infer(const std::vector<Shape>& in) const override;
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem,
                 std::vector<cl_event>* ev) override;

private:
    Elementwise ew_;
    bool mul_;
    int channels_;
    Buffer operand_, fixed_;
};

// y[c] = scale[c] x[c] + shift[c] (a batch norm that follows no convolution, a Mul or Add by a constant).
class AffineNode : public Op {
public:
    AffineNode(Context& ctx, const std::vector<float>& scale, const std::vector<float>& shift);
    std::string kind() const override { return "affine"; }
    Shape infer(const std::vector<Shape>& in) const override;
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem,
                 std::vector<cl_event>* ev) override;

private:
    Elementwise ew_;
    int channels_;
    Buffer scale_, shift_;
};

// GroupNorm's normalization (ONNX's export: Reshape [0, G, -1], InstanceNormalization, Reshape back): each of G
// groups of C / G channels normalized over its channels and pixels together (mean and biased variance), then
// scale[g], shift[g]. A group's channels are contiguous in C x H x W, so this is the per-image batch norm over the
// same memory viewed as G x 1 x (C / G) H W; in place.
class GroupNormNode : public Op {
public:
    GroupNormNode(Context& ctx, int channels, int groups, const std::vector<float>& scale,
                  const std::vector<float>& shift, float eps)
        : bn_(ctx, groups, scale, shift, eps, Act::none()), channels_(channels), groups_(groups) {}
    std::string kind() const override { return "group_norm"; }
    Shape infer(const std::vector<Shape>& in) const override;
    std::size_t scratch_floats(const std::vector<Shape>&) const override {
        return bn_.scratch_floats(Shape{groups_, 1, 1});
    }
    bool in_place() const override { return true; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View&, cl_mem scratch,
                 std::vector<cl_event>* ev) override;

private:
    BatchNormPerImage bn_;
    int channels_, groups_;
};

// ONNX MaxPool (ops/max_pool.hpp): padded cells never win.
class MaxPoolNode : public Op {
public:
    MaxPoolNode(Context& ctx, const MaxPoolGeometry& g) : pool_(ctx, g) {}
    std::string kind() const override { return "max_pool2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return pool_.output_shape(ConvNode::one(in)); }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        pool_.enqueue(ctx, in[0], out, ev);
    }

private:
    MaxPool2d pool_;
};

// The mean of every channel over H x W: C x H x W -> C x 1 x 1 (ONNX GlobalAveragePool, ReduceMean over H and W).
class GlobalAvgPoolNode : public Op {
public:
    explicit GlobalAvgPoolNode(Context& ctx) : pool_(ctx) {}
    std::string kind() const override { return "global_avg_pool"; }
    Shape infer(const std::vector<Shape>& in) const override { return {ConvNode::one(in).c, 1, 1}; }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>*) override {
        const int n = in[0].shape.h * in[0].shape.w;
        pool_.pool_planar(ctx, in[0].mem, in[0].offset, in[0].shape.c, n, 0, n, PoolMode::Mean, out.mem, out.offset);
    }

private:
    SetPool pool_;
};

// ONNX Pad over H and W (ops/pad2d.hpp): constant, reflect or edge.
class PadNode : public Op {
public:
    PadNode(Context& ctx, const PadGeometry& g) : pad_(ctx, g) {}
    std::string kind() const override { return "pad2d"; }
    Shape infer(const std::vector<Shape>& in) const override { return pad_.output_shape(ConvNode::one(in)); }
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        pad_.enqueue(ctx, in[0], out, ev);
    }

private:
    Pad2d pad_;
};

// ONNX Resize, mode linear, by constant scales (ops/resize.hpp): the output is floor(in * scale) a side with the
// product taken in float32, as onnxruntime does (PyTorch's exporter declares floor(10 * 0.7) = 7 for scale_factor
// 0.7, whose float32 scale 0.699999988 times 10 is 6.99999988 in double: 6), so the op is made per output size (a
// graph is built per input size).
class ResizeNode : public Op {
public:
    ResizeNode(Context& ctx, float scale_h, float scale_w, ResizeCoord mode)
        : ctx_(ctx), scale_h_(scale_h), scale_w_(scale_w), mode_(mode) {}
    // A fixed output size (ONNX 'sizes'): the scales of the coordinates are out / in, exactly.
    ResizeNode(Context& ctx, int out_h, int out_w, ResizeCoord mode)
        : ctx_(ctx), scale_h_(0.0f), scale_w_(0.0f), mode_(mode), out_h_(out_h), out_w_(out_w) {}
    std::string kind() const override { return "resize_bilinear"; }
    Shape infer(const std::vector<Shape>& in) const override;
    void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem, std::vector<cl_event>* ev) override {
        op(out.shape.h, out.shape.w).enqueue(ctx, in[0], out, ev);
    }

private:
    static constexpr int kMaxDim = 1 << 16;
    ResizeBilinear& op(int oh, int ow) const;  // made on first use, one per output size
    Context& ctx_;
    float scale_h_, scale_w_;
    ResizeCoord mode_;
    int out_h_ = 0, out_w_ = 0;  // > 0: a fixed output size
    mutable std::map<std::pair<int, int>, std::unique_ptr<ResizeBilinear>> ops_;
};

}  // namespace ngi::detail

#include "ops/conv.hpp"

namespace ngi::detail {

namespace {

// Fixed work-group shapes: PoCL compiles one work-group function per local size, so never let it vary.
const std::size_t kIm2colLocal[1] = {64};
const std::size_t kCol2imLocal[3] = {16, 4, 1};

std::vector<float> filled(const std::vector<float>& v, int n, float value, const char* what) {
    if (v.empty()) return std::vector<float>(n, value);
    if (int(v.size()) != n)
        throw InputError(std::string(what) + ": expected " + std::to_string(n) + " values, got " +
                         std::to_string(v.size()));
    return v;
}

void check_spec(const ConvSpec& s, const char* op) {
    if (s.cin < 1 || s.cout < 1 || s.geom.kh < 1 || s.geom.kw < 1 || s.geom.stride < 1 || s.geom.pad < 0)
        throw InputError(std::string(op) + ": invalid geometry (cin " + std::to_string(s.cin) + ", cout " +
                         std::to_string(s.cout) + ", kernel " + std::to_string(s.geom.kh) + "x" +
                         std::to_string(s.geom.kw) + ", stride " + std::to_string(s.geom.stride) + ", pad " +
                         std::to_string(s.geom.pad) + ")");
}

void maybe_push(std::vector<cl_event>* events, cl_event e) {
    if (events && e) events->push_back(e);
}

}  // namespace

int conv_out_size(int in, int k, int stride, int pad, const char* what) {
    const int out = (in + 2 * pad - k) / stride + 1;
    if (in + 2 * pad < k || out < 1)
        throw InputError(std::string(what) + ": input size " + std::to_string(in) + " is too small for kernel " +
                         std::to_string(k) + " with padding " + std::to_string(pad));
    return out;
}

// ---- conv2d -------------------------------------------------------------------------------------------

Conv2d::Conv2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight,
               const ChannelAffine& affine, ConvPath path, const std::optional<GemmParams>& implicit_p)
    : spec_(spec), p_(p) {
    check_spec(spec, "conv2d");
    implicit_ = ImplicitConv::make(ctx, implicit_p.value_or(p), spec, weight, false, path);
    if (!implicit_) {
        const int K = spec.cin * spec.geom.kh * spec.geom.kw;
        gemm_.emplace(ctx, p);
        const auto& g = spec.geom;
        if (g.kh == 1 && g.kw == 1 && g.stride == 1 && g.pad == 0)
            pack_.emplace(ctx, p);  // B is the input itself: a straight panel pack
        else
            im2col_ = ctx.kernel("im2col", "im2col_packed", im2col_defines(p.nr()));
        ap_ = upload_floats(ctx, pack_a(weight, spec.cout, K, K, p), "conv2d packed weights");
    }
    scale_ = upload_floats(ctx, filled(affine.scale, spec.cout, 1.0f, "conv2d scale"), "conv2d scale");
    shift_ = upload_floats(ctx, filled(affine.shift, spec.cout, 0.0f, "conv2d shift"), "conv2d shift");
}

Shape Conv2d::output_shape(const Shape& in) const {
    if (in.c != spec_.cin)
        throw InputError("conv2d: input has " + std::to_string(in.c) + " channels, the layer expects " +
                         std::to_string(spec_.cin));
    return {spec_.cout, conv_out_size(in.h, spec_.geom.kh, spec_.geom.stride, spec_.geom.pad, "conv2d height"),
            conv_out_size(in.w, spec_.geom.kw, spec_.geom.stride, spec_.geom.pad, "conv2d width")};
}

std::size_t Conv2d::scratch_floats(const Shape& in) const {
    const Shape out = output_shape(in);
    if (implicit_) return implicit_->scratch_floats(in);
    return packed_b_floats(spec_.cin * spec_.geom.kh * spec_.geom.kw, out.h * out.w, p_);
}

void Conv2d::enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                     std::vector<cl_event>* events) {
    const Shape out = output_shape(x.shape);
    if (implicit_) {
        implicit_->enqueue(ctx, x, y, scratch, scratch_off, scale_.get(), shift_.get(), spec_.in_act, spec_.out_act,
                           events);
        return;
    }
    const GemmParams& p = p_;
    const int K = spec_.cin * spec_.geom.kh * spec_.geom.kw, N = out.h * out.w, kp = padded_k(K, p);
    if (pack_) {  // B is the input: a panel pack
        maybe_push(events, pack_->enqueue(ctx, x.mem, x.offset, K, N, scratch, scratch_off, spec_.in_act,
                                          events != nullptr));
    } else {
        im2col_.args(x.mem, int(x.offset), x.shape.c, x.shape.h, x.shape.w, spec_.geom.kh, spec_.geom.kw,
                     spec_.geom.stride, spec_.geom.pad, out.h, out.w, kp, scratch, int(scratch_off),
                     int(spec_.in_act.kind), spec_.in_act.alpha);
        const std::size_t g[1] = {round_up(std::size_t(N), std::size_t(p.nr()))};
        maybe_push(events, ctx.launch(im2col_, 1, g, kIm2colLocal, events != nullptr));
    }
    maybe_push(events, gemm_->enqueue(ctx, spec_.cout, N, K, ap_.get(), scratch, scratch_off, y.mem, y.offset, N,
                                     scale_.get(), shift_.get(), spec_.out_act, events != nullptr));
}

// ---- conv_transpose2d ---------------------------------------------------------------------------------

ConvTranspose2d::ConvTranspose2d(Context& ctx, const GemmParams& p, const ConvSpec& spec, const float* weight,
                                 const ChannelAffine& affine, ConvPath path,
                                 const std::optional<GemmParams>& implicit_p)
    : spec_(spec), p_(p) {
    check_spec(spec, "conv_transpose2d");
    implicit_ = ImplicitConv::make(ctx, implicit_p.value_or(p), spec, weight, true, path);
    if (!implicit_) {
        const auto& g = spec.geom;
        gemm_.emplace(ctx, p);
        pack_.emplace(ctx, p);
        col2im_ = ctx.kernel("col2im", "col2im_gather",
                             "-DKH=" + std::to_string(g.kh) + " -DKW=" + std::to_string(g.kw) + " -DSTRIDE=" +
                                 std::to_string(g.stride) + " -DPAD=" + std::to_string(g.pad) + " " +
                                 activation_defines());
        // GEMM A is W^T: row m = (co, ky, kx), column k = ci; weight[ci][m] in PyTorch's [cin][cout][kh][kw].
        const int M = spec.cout * g.kh * g.kw;
        std::vector<float> at(std::size_t(M) * spec.cin);
        for (int ci = 0; ci < spec.cin; ++ci)
            for (int m = 0; m < M; ++m) at[std::size_t(m) * spec.cin + ci] = weight[std::size_t(ci) * M + m];
        ap_ = upload_floats(ctx, pack_a(at.data(), M, spec.cin, spec.cin, p), "conv_transpose2d packed weights");
        ones_ = upload_floats(ctx, std::vector<float>(M, 1.0f), "conv_transpose2d unit scale");
        zeros_ = upload_floats(ctx, std::vector<float>(M, 0.0f), "conv_transpose2d zero shift");
    }
    scale_ = upload_floats(ctx, filled(affine.scale, spec.cout, 1.0f, "conv_transpose2d scale"), "conv_transpose2d scale");
    shift_ = upload_floats(ctx, filled(affine.shift, spec.cout, 0.0f, "conv_transpose2d shift"), "conv_transpose2d shift");
}

Shape ConvTranspose2d::output_shape(const Shape& in) const {
    if (in.c != spec_.cin)
        throw InputError("conv_transpose2d: input has " + std::to_string(in.c) + " channels, the layer expects " +
                         std::to_string(spec_.cin));
    const auto& g = spec_.geom;
    const int oh = (in.h - 1) * g.stride - 2 * g.pad + g.kh, ow = (in.w - 1) * g.stride - 2 * g.pad + g.kw;
    if (in.h < 1 || in.w < 1 || oh < 1 || ow < 1)
        throw InputError("conv_transpose2d: input " + to_string(in) + " gives an empty output");
    return {spec_.cout, oh, ow};
}

std::size_t ConvTranspose2d::scratch_floats(const Shape& in) const {
    if (implicit_) return implicit_->scratch_floats(in);
    const int N = in.h * in.w, M = spec_.cout * spec_.geom.kh * spec_.geom.kw;
    return packed_b_floats(spec_.cin, N, p_) + std::size_t(M) * N;
}

void ConvTranspose2d::enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                              std::vector<cl_event>* events) {
    const Shape out = output_shape(x.shape);
    if (implicit_) {
        implicit_->enqueue(ctx, x, y, scratch, scratch_off, scale_.get(), shift_.get(), spec_.in_act, spec_.out_act,
                           events);
        return;
    }
    const GemmParams& p = p_;
    const auto& g = spec_.geom;
    const int N = x.shape.h * x.shape.w, M = spec_.cout * g.kh * g.kw;
    const std::size_t cols_off = scratch_off + packed_b_floats(spec_.cin, N, p);
    maybe_push(events, pack_->enqueue(ctx, x.mem, x.offset, x.shape.c, N, scratch, scratch_off, spec_.in_act,
                                      events != nullptr));
    maybe_push(events, gemm_->enqueue(ctx, M, N, spec_.cin, ap_.get(), scratch, scratch_off, scratch, cols_off, N,
                                     ones_.get(), zeros_.get(), Act::none(), events != nullptr));
    col2im_.args(scratch, int(cols_off), N, spec_.cout, x.shape.h, x.shape.w, out.h, out.w, y.mem, int(y.offset), scale_.get(), shift_.get(), int(spec_.out_act.kind),
                 spec_.out_act.alpha);
    const std::size_t gc[3] = {std::size_t(out.w), std::size_t(out.h), std::size_t(out.c)};
    maybe_push(events, ctx.launch(col2im_, 3, gc, kCol2imLocal, events != nullptr));
}

}  // namespace ngi::detail

#include "op_harness/op_cases.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "ops/conv.hpp"
#include "ops/dense.hpp"
#include "ops/elementwise.hpp"
#include "ops/gather_image.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "ops/jbu.hpp"
#include "ops/max_pool.hpp"
#include "ops/mlp.hpp"
#include "ops/norm.hpp"
#include "ops/pad2d.hpp"
#include "ops/probe_shade.hpp"
#include "ops/resize.hpp"
#include "ops/set_pool.hpp"
#include "ops/sh.hpp"
#include "compare.hpp"
#include "jbu_scene.hpp"
#include "ops/voxel_ltf.hpp"
#include "reference.hpp"
#include "reference_image_desc.hpp"
#include "reference_jbu.hpp"
#include "reference_voxel.hpp"

namespace ngi::harness {

using namespace ngi::detail;
using BufferPtr = std::shared_ptr<GuardedBuffer>;

namespace {

// ---- buffers and data ----------------------------------------------------------------------------------------

template <class T>
BufferPtr add(Context& ctx, Prepared& p, const std::string& name, Role role, const std::vector<T>& v) {
    static_assert(sizeof(T) == 4, "the harness counts buffers in 4-byte words");
    auto b = std::make_shared<GuardedBuffer>(ctx, name, role, v.size(), v.empty() ? nullptr : v.data());
    p.buffers.push_back(b);
    return b;
}

BufferPtr add_out(Context& ctx, Prepared& p, const std::string& name, Role role, std::size_t words) {
    auto b = std::make_shared<GuardedBuffer>(ctx, name, role, words, nullptr);
    p.buffers.push_back(b);
    return b;
}

std::vector<float> uniform(std::size_t n, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
    std::uniform_real_distribution<float> u(lo, hi);
    std::vector<float> v(n);
    for (float& x : v) x = u(rng);
    return v;
}

std::vector<double> to_double(const std::vector<float>& v) { return {v.begin(), v.end()}; }

// An integer in [lo, hi], for the rows whose shapes are drawn from their own seeded RNG ("random shape k").
int draw(std::mt19937& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }

std::string dims(std::initializer_list<std::pair<const char*, long>> d) {
    std::ostringstream s;
    for (const auto& [k, v] : d) s << (s.tellp() > 0 ? " " : "") << k << v;
    return s.str();
}

Act act_of(int code) { return {Activation(code), 0.2f}; }

// ---- GEMM and packing ----------------------------------------------------------------------------------------

// One GEMM of a knob set at a shape (M N K) with an activation in the epilogue.
struct GemmRun {
    GemmParams p;
    int M, N, K, act;
};

// One or more GEMMs, each on its own guarded buffers, compared together (their outputs concatenated, all O(1)): a
// knob set at several shapes, or every set of a fallback chain. `knobs`: each run's shape names its set.
Prepared gemm_runs_case(Context& ctx, const std::vector<GemmRun>& runs, bool knobs, std::mt19937& rng) {
    Prepared r;
    std::vector<std::function<void(Context&)>> enqueues;
    std::vector<std::function<void(Context&, Comparison&)>> compares;
    for (std::size_t i = 0; i < runs.size(); ++i) {
        // Plain copies, not a structured binding: clang 15 (the sanitize build) cannot capture bindings in lambdas.
        const GemmParams p = runs[i].p;
        const int M = runs[i].M, N = runs[i].N, K = runs[i].K, act = runs[i].act;
        const std::string tag = runs.size() == 1 ? "" : "[" + std::to_string(i) + "]";
        r.shape += (i ? ", " : "") + (knobs ? p.to_string() + ": " : "") +
                   dims({{"M", M}, {"N", N}, {"K", K}, {"act", act}});
        auto op = std::make_shared<Gemm>(ctx, p);
        // Weights ~ U(-1/sqrt(K), 1/sqrt(K)), as the generators' layers: outputs O(1) at any K.
        const float wa = 1.0f / std::sqrt(float(K));
        const auto a = uniform(std::size_t(M) * K, rng, -wa, wa), b = uniform(std::size_t(K) * N, rng);
        const auto scale = uniform(M, rng, 0.5f, 1.5f), shift = uniform(M, rng);
        const int ldc = N + 3;  // a row stride > N, as the planner's arena rows
        auto ap = add(ctx, r, "Ap" + tag, Role::Input, pack_a(a.data(), M, K, K, p));
        auto bp = add(ctx, r, "Bp" + tag, Role::Input, pack_b(b.data(), K, N, N, p));
        auto sc = add(ctx, r, "scale" + tag, Role::Input, scale), sh = add(ctx, r, "shift" + tag, Role::Input, shift);
        auto c = add_out(ctx, r, "C" + tag, Role::Output, std::size_t(M) * ldc);
        r.flops += 2.0 * M * N * K;
        r.bytes += 4.0 * (double(ap->words()) + double(bp->words()) + double(M) * N + 2.0 * M);
        enqueues.push_back([=](Context& cx) {
            op->enqueue(cx, M, N, K, ap->payload(), bp->mem(), bp->offset(), c->mem(), c->offset(), ldc,
                        sc->payload(), sh->payload(), act_of(act));
        });
        compares.push_back([=](Context& cx, Comparison& cmp) {
            const auto full = c->read_floats(cx);
            for (int m = 0; m < M; ++m)
                for (int n = 0; n < N; ++n) cmp.got.push_back(full[std::size_t(m) * ldc + n]);
            const auto want = ref::gemm(M, N, K, a, b, scale, shift, act);
            cmp.want.insert(cmp.want.end(), want.begin(), want.end());
        });
    }
    r.run = [enqueues](Context& cx) {
        for (const auto& e : enqueues) e(cx);
    };
    r.compare = [compares](Context& cx) {
        Comparison cmp;
        for (const auto& c : compares) c(cx, cmp);
        return cmp;
    };
    return r;
}

Prepared gemm_case(Context& ctx, const GemmParams& p, int M, int N, int K, int act, std::mt19937& rng) {
    return gemm_runs_case(ctx, {{p, M, N, K, act}}, false, rng);
}

// tests/test_gemm.cpp's random small shapes: M, N, K in 1..70 and an activation 0..4, `count` of them per knob set.
std::vector<GemmRun> random_gemm_runs(const std::vector<GemmParams>& sets, int count, std::mt19937& rng) {
    std::vector<GemmRun> runs;
    for (const GemmParams& p : sets)
        for (int i = 0; i < count; ++i) {
            const int M = draw(rng, 1, 70), N = draw(rng, 1, 70), K = draw(rng, 1, 70);
            runs.push_back({p, M, N, K, draw(rng, 0, 4)});
        }
    return runs;
}

// gemm_local's edges for one knob set (tests/test_gemm.cpp's): shapes around its block (L0 MR) x (L1 NR) and chunk
// KWG (one less, equal and one more, several blocks with a remainder), K = 1, a single output, skinny rows and
// columns, a generator layer (64 x 1031 x 192); those of K <= 90 (`long_sums` false) or K > 90, then 3 random shapes
// of M, N in 1..150 and K in 1..90 or 91..150 (that file drew 6 in 1..150). Each with an activation 0..4.
std::vector<GemmRun> local_gemm_runs(const GemmParams& p, bool long_sums, std::mt19937& rng) {
    const int bm = p.local0 * p.mr, bn = p.local1 * p.nr(), kc = p.kwg;
    const std::array<int, 3> edges[] = {{1, 1, 1},    {1, 300, 1},          {300, 1, 7},
                                        {bm - 1, bn + 1, kc + 1},           {bm, bn, kc},
                                        {bm + 1, bn - 1, 2 * kc - 1},       {2 * bm + 3, 3, 3 * kc + 5},
                                        {5, 2 * bn + 7, kc - 1},            {64, 1031, 192}};
    std::vector<std::array<int, 3>> shapes;
    for (const auto& e : edges)
        if ((e[2] > 90) == long_sums) shapes.push_back(e);
    for (int i = 0; i < 3; ++i)
        shapes.push_back({draw(rng, 1, 150), draw(rng, 1, 150), long_sums ? draw(rng, 91, 150) : draw(rng, 1, 90)});
    std::vector<GemmRun> runs;
    for (const auto& [M, N, K] : shapes) runs.push_back({p, M, N, K, draw(rng, 0, 4)});
    return runs;
}

Prepared pack_b_case(Context& ctx, const GemmParams& p, int K, int N, int act, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"K", K}, {"N", N}, {"act", act}});
    auto op = std::make_shared<PackB>(ctx, p);
    const auto x = uniform(std::size_t(K) * N, rng, -3.0f, 3.0f);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto bp = add_out(ctx, r, "Bp", Role::Output, packed_b_floats(K, N, p));
    r.bytes = 4.0 * (double(x.size()) + double(bp->words()));
    r.run = [=](Context& cx) { op->enqueue(cx, xb->mem(), xb->offset(), K, N, bp->mem(), bp->offset(), act_of(act)); };
    r.compare = [=](Context& cx) {
        std::vector<float> activated(x.size());
        for (std::size_t i = 0; i < x.size(); ++i) activated[i] = float(ref::activate(x[i], act, 0.2));
        return Comparison{bp->read_floats(cx), to_double(pack_b(activated.data(), K, N, N, p)), {}, {}};
    };
    return r;
}

// A dense layer over planar items (ops/dense.hpp), its input read in place: n >= NR reads x itself (the last tile
// kept inside it: the guards after x must stay unread... and unwritten), n < NR through zero-padded rows in scratch.
Prepared dense_case(Context& ctx, const GemmParams& p, int in, int out, int n, int x_ld, bool item_major,
                    bool residual, int act, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"in", in}, {"out", out}, {"n", n}, {"ld", x_ld}, {"item_major", item_major},
                    {"residual", residual}, {"act", act}});
    const float wa = 1.0f / std::sqrt(float(in));
    const auto w = uniform(std::size_t(out) * in, rng, -wa, wa), x = uniform(std::size_t(in) * x_ld, rng);
    const auto scale = uniform(out, rng, 0.5f, 1.5f), shift = uniform(out, rng);
    const auto res = uniform(std::size_t(out) * n, rng);
    auto op = std::make_shared<Dense>(ctx, p, in, out, w.data());
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto sc = add(ctx, r, "scale", Role::Input, scale), sh = add(ctx, r, "shift", Role::Input, shift);
    auto rb = add(ctx, r, "residual", Role::Input, res);
    auto yb = add_out(ctx, r, "y", Role::Output, std::size_t(out) * n);
    auto sb = add_out(ctx, r, "scratch", Role::Scratch, std::max<std::size_t>(1, op->scratch_floats(n)));
    r.flops = 2.0 * in * out * double(n);
    r.bytes = 4.0 * (double(in) * n + double(w.size()) + double(out) * n * (residual ? 2 : 1));
    r.run = [=](Context& cx) {
        const DenseOut o{yb->mem(), yb->offset(), item_major ? 1 : n, item_major ? out : 1};
        op->enqueue(cx, xb->mem(), xb->offset(), x_ld, n, o, sc->payload(), sh->payload(), act_of(act),
                    residual ? rb->mem() : nullptr, rb->offset(), sb->mem(), sb->offset());
    };
    r.compare = [=](Context& cx) {
        Comparison cmp;
        cmp.got = yb->read_floats(cx);
        cmp.want.assign(std::size_t(out) * n, 0.0);
        for (int o = 0; o < out; ++o)
            for (int i = 0; i < n; ++i) {
                double s = 0;
                for (int k = 0; k < in; ++k) s += double(w[std::size_t(o) * in + k]) * x[std::size_t(k) * x_ld + i];
                const std::size_t at = item_major ? std::size_t(i) * out + o : std::size_t(o) * n + i;
                cmp.want[at] = ref::activate(s * scale[o] + shift[o], act, 0.2) + (residual ? res[at] : 0.0);
            }
        return cmp;
    };
    return r;
}

// ---- convolutions --------------------------------------------------------------------------------------------

struct ConvShape {
    int c, h, w, co, kh, kw, s, p, in_act, act;
};

// expect_implicit: the path the op must take (default: the one asked for; a random geometry asking for the implicit
// path keeps im2col where it is not exact, conv_takes_implicit).
Prepared conv_case(Context& ctx, const GemmParams& gp, const ConvShape& k, bool transposed, ConvPath path,
                   std::mt19937& rng, std::optional<bool> expect_implicit = std::nullopt) {
    const bool expected = expect_implicit.value_or(path == ConvPath::implicit);
    Prepared r;
    r.shape = dims({{"C", k.c}, {"H", k.h}, {"W", k.w}, {"Co", k.co}, {"k", k.kh}, {"x", k.kw}, {"s", k.s},
                    {"p", k.p}, {"in_act", k.in_act}, {"act", k.act}});
    const ConvSpec spec{k.c, k.co, {k.kh, k.kw, k.s, k.p}, act_of(k.in_act), act_of(k.act)};
    const float wa = 1.0f / std::sqrt(float(k.c * k.kh * k.kw));
    const auto x = uniform(std::size_t(k.c) * k.h * k.w, rng);
    const auto w = uniform(std::size_t(k.c) * k.co * k.kh * k.kw, rng, -wa, wa);
    const ChannelAffine aff{uniform(k.co, rng, 0.5f, 1.5f), uniform(k.co, rng)};
    const Shape in{k.c, k.h, k.w};
    // One of the two op classes behind a common run: both have output_shape, scratch_floats, enqueue, implicit.
    std::shared_ptr<Conv2d> conv;
    std::shared_ptr<ConvTranspose2d> up;
    if (transposed) up = std::make_shared<ConvTranspose2d>(ctx, gp, spec, w.data(), aff, path);
    else conv = std::make_shared<Conv2d>(ctx, gp, spec, w.data(), aff, path);
    const Shape out = transposed ? up->output_shape(in) : conv->output_shape(in);
    const std::size_t scratch = transposed ? up->scratch_floats(in) : conv->scratch_floats(in);
    const bool implicit = transposed ? up->implicit() : conv->implicit();
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, out.size());
    auto sb = add_out(ctx, r, "scratch", Role::Scratch, scratch);
    const double macs = transposed ? double(in.size()) * k.co * k.kh * k.kw : double(out.size()) * k.c * k.kh * k.kw;
    r.flops = 2.0 * macs;
    r.bytes = 4.0 * (double(x.size()) + double(w.size()) + double(out.size()));
    r.run = [=](Context& cx) {
        const View xv{xb->mem(), xb->offset(), in}, yv{yb->mem(), yb->offset(), out};
        if (up) up->enqueue(cx, xv, yv, sb->mem(), sb->offset());
        else conv->enqueue(cx, xv, yv, sb->mem(), sb->offset());
    };
    r.compare = [=](Context& cx) {
        Comparison cmp;
        cmp.got = yb->read_floats(cx);
        int oh = 0, ow = 0;
        cmp.want = to_double(transposed ? ref::conv_transpose2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p,
                                                                aff.scale, aff.shift, k.in_act, k.act, 0.2, oh, ow)
                                        : ref::conv2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p, aff.scale,
                                                      aff.shift, k.in_act, k.act, 0.2, oh, ow));
        if (oh != out.h || ow != out.w) cmp.mismatch = "output shape differs from the reference's";
        // The case's name says which path it covers: the op must have taken it.
        if (expected != implicit)
            cmp.mismatch = std::string("the op took the ") + (implicit ? "implicit" : "im2col") + " path";
        return cmp;
    };
    return r;
}

// A convolution of tests/test_conv.cpp's random sweep at the given stride: C, Cout 1..40, H, W 1..23 (transposed:
// 1..17), kernels 1..5 on each axis, padding min(KH, KW) / 2, an input activation 0..2, an output activation 0..4;
// redrawn until the output is at least 1 x 1. `exact`: redrawn until the implicit path takes it (transposed: the
// padding drawn in 0..min(KH, KW) / 2, as K - 2P = S needs; the sweep's min / 2 gives it at stride 1 only).
ConvShape random_conv(std::mt19937& rng, bool transposed, int stride, bool exact, const GemmParams& gp) {
    for (int attempt = 0; attempt < 100000; ++attempt) {
        ConvShape k{draw(rng, 1, 40), 0, 0, draw(rng, 1, 40), draw(rng, 1, 5), draw(rng, 1, 5), stride, 0,
                    draw(rng, 0, 2), draw(rng, 0, 4)};
        k.h = draw(rng, 1, transposed ? 17 : 23);
        k.w = draw(rng, 1, transposed ? 17 : 23);
        k.p = exact && transposed ? draw(rng, 0, std::min(k.kh, k.kw) / 2) : std::min(k.kh, k.kw) / 2;
        const bool fits = transposed ? (k.h - 1) * k.s - 2 * k.p + k.kh >= 1 && (k.w - 1) * k.s - 2 * k.p + k.kw >= 1
                                     : k.h + 2 * k.p >= k.kh && k.w + 2 * k.p >= k.kw;
        if (fits && (!exact || conv_takes_implicit(k.kh, k.kw, k.s, k.p, k.in_act, transposed, gp))) return k;
    }
    throw std::runtime_error("random_conv: no geometry found");
}

// A drawn geometry at perf size: its kernel, stride, padding and activations over 32 channels of a U-Net-sized plane.
ConvShape perf_conv(ConvShape k, bool transposed) {
    k.c = k.co = 32;
    k.h = transposed ? 64 : 128;
    k.w = transposed ? 128 : 256;
    return k;
}

// ---- batch norm and elementwise ------------------------------------------------------------------------------

Prepared batch_norm_case(Context& ctx, bool chunked, BatchNormPerImage::Form form, int C, int H, int W,
                         std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"C", C}, {"H", H}, {"W", W}});
    const auto x = uniform(std::size_t(C) * H * W, rng, -3.0f, 5.0f);
    const auto g = uniform(C, rng, 0.5f, 1.5f), b = uniform(C, rng);
    auto op = std::make_shared<BatchNormPerImage>(ctx, C, g, b, 1e-5f, Act::leaky(0.2f), chunked, form);
    auto xb = add(ctx, r, "x", Role::InOut, x);
    auto sb = add_out(ctx, r, "scratch", Role::Scratch, op->scratch_floats({C, H, W}));
    r.flops = 6.0 * double(x.size());  // mean, variance, normalize, activation
    r.bytes = 4.0 * 3 * double(x.size());  // two reads (statistics, apply) and a write
    r.run = [=](Context& cx) { op->enqueue(cx, View{xb->mem(), xb->offset(), {C, H, W}}, sb->mem(), sb->offset()); };
    r.compare = [=](Context& cx) {
        return Comparison{xb->read_floats(cx),
                          to_double(ref::batch_norm_per_image(x, C, H * W, g, b, 1e-5, int(Activation::LeakyReLU), 0.2)),
                          {}, {}};
    };
    return r;
}

Prepared activate_case(Context& ctx, Act act, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}, {"act", int(act.kind)}});
    auto op = std::make_shared<Elementwise>(ctx);
    const auto x = uniform(n, rng, -6.0f, 6.0f);
    auto xb = add(ctx, r, "x", Role::InOut, x);
    r.bytes = 8.0 * n;
    r.run = [=](Context& cx) { op->activate(cx, View{xb->mem(), xb->offset(), {1, 1, n}}, act); };
    r.compare = [=](Context& cx) {
        Comparison cmp{xb->read_floats(cx), {}, {}, {}};
        for (float v : x) cmp.want.push_back(ref::activate(v, int(act.kind), act.alpha));
        return cmp;
    };
    return r;
}

Prepared dropout_case(Context& ctx, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}});
    auto op = std::make_shared<Elementwise>(ctx);
    const auto x = uniform(n, rng);
    const std::uint32_t seed = 1234, site = 3;
    const float p = 0.3f;
    auto xb = add(ctx, r, "x", Role::InOut, x);
    r.bytes = 8.0 * n;
    r.run = [=](Context& cx) { op->dropout(cx, View{xb->mem(), xb->offset(), {1, 1, n}}, seed, site, p); };
    r.compare = [=](Context& cx) {
        Comparison cmp{xb->read_floats(cx), {}, {}, {}};
        for (int i = 0; i < n; ++i)
            cmp.want.push_back(ref::dropout_keeps(seed, site, std::uint32_t(i), p) ? x[i] / (1.0 - p) : 0.0);
        return cmp;
    };
    return r;
}

Prepared sanitize_case(Context& ctx, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}});
    auto op = std::make_shared<Elementwise>(ctx);
    auto x = uniform(n, rng, -1.2f, 1.2f);  // a sixth beyond [-1, 1] + its margin: replaced
    const float inf = std::numeric_limits<float>::infinity();
    const float specials[] = {std::numeric_limits<float>::quiet_NaN(), inf, -inf, 3.4e38f, -65504.0f};
    for (std::size_t k = 0; k < x.size(); k += 7) x[k] = specials[(k / 7) % 5];
    auto xb = add(ctx, r, "x", Role::InOut, x);
    r.bytes = 8.0 * n;
    r.run = [=](Context& cx) { op->sanitize(cx, View{xb->mem(), xb->offset(), {1, 1, n}}, -1.0f, 1.0f); };
    r.compare = [=](Context& cx) {
        Comparison cmp{xb->read_floats(cx), {}, {}, {}};
        int replaced = 0;
        for (float v : x) {
            const double s = ref::sanitize(v, -1.0, 1.0);
            replaced += std::isnan(v) || s != double(v);
            cmp.want.push_back(s);
        }
        const int count = op->sanitized_count(cx);
        if (count != replaced)
            cmp.mismatch = "sanitized_count " + std::to_string(count) + ", the reference replaced " + std::to_string(replaced);
        return cmp;
    };
    return r;
}

Prepared channel_affine_case(Context& ctx, bool points, int C, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"C", C}, {"n", n}}) + (points ? " points in" : " planar in");
    auto op = std::make_shared<Elementwise>(ctx);
    const auto x = uniform(std::size_t(C) * n, rng, -100.0f, 100.0f);
    const auto scale = uniform(C, rng, -3.0f, 3.0f), shift = uniform(C, rng);
    const int item_stride = points ? C : 1, channel_stride = points ? 1 : n;
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto sb = add(ctx, r, "scale", Role::Input, scale), tb = add(ctx, r, "shift", Role::Input, shift);
    auto yb = add_out(ctx, r, "y", Role::Output, x.size());
    r.flops = 2.0 * double(x.size());
    r.bytes = 8.0 * double(x.size());
    r.run = [=](Context& cx) {
        op->channel_affine(cx, xb->mem(), xb->offset(), item_stride, channel_stride, C, n, sb->payload(),
                           tb->payload(), yb->mem(), yb->offset());
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{yb->read_floats(cx), std::vector<double>(x.size()), {}, {}};
        for (int c = 0; c < C; ++c)
            for (int i = 0; i < n; ++i)
                cmp.want[std::size_t(c) * n + i] =
                    double(scale[c]) * x[std::size_t(i) * item_stride + std::size_t(c) * channel_stride] + shift[c];
        return cmp;
    };
    return r;
}

Prepared binary_case(Context& ctx, bool multiply, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}});
    auto op = std::make_shared<Elementwise>(ctx);
    const auto x = uniform(n, rng, -2.0f, 2.0f), y = uniform(n, rng, -2.0f, 2.0f);
    auto xb = add(ctx, r, "x", Role::InOut, x), yb = add(ctx, r, "y", Role::Input, y);
    r.flops = n;
    r.bytes = 12.0 * n;
    r.run = [=](Context& cx) {
        // Shapes that differ but hold the same count, as the voxel_sh runner's residual.
        const View xv{xb->mem(), xb->offset(), {1, 1, n}}, yv{yb->mem(), yb->offset(), {n, 1, 1}};
        if (multiply) op->mul(cx, xv, yv);
        else op->add(cx, xv, yv);
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{xb->read_floats(cx), {}, {}, {}};
        for (int i = 0; i < n; ++i) cmp.want.push_back(multiply ? double(x[i]) * y[i] : double(x[i]) + y[i]);
        return cmp;
    };
    return r;
}

// ---- MLPs ----------------------------------------------------------------------------------------------------

// An MLP of the given widths; hidden activations cycle through ReLU, LeakyReLU, tanh, sigmoid; the last is `last`.
MlpSpec mlp_spec(int inputs, const FrequencyEncoding& enc, const std::vector<int>& widths, Act last, std::mt19937& rng) {
    MlpSpec s;
    s.inputs = inputs;
    s.encoding = enc;
    int in = enc.width(inputs);
    const Act hidden[4] = {Act::relu(), Act::leaky(0.2f), Act::tanh(), Act::sigmoid()};
    for (std::size_t l = 0; l < widths.size(); ++l) {
        DenseSpec d;
        d.in = in;
        d.out = widths[l];
        d.act = l + 1 == widths.size() ? last : hidden[l % 4];
        const float a = std::sqrt(3.0f / float(in));  // He-like: activations O(1) through the layers
        d.weight = uniform(std::size_t(d.in) * d.out, rng, -a, a);
        d.bias = uniform(d.out, rng, -0.5f, 0.5f);
        s.layers.push_back(std::move(d));
        in = widths[l];
    }
    return s;
}

// tests/test_mlp.cpp's random architectures: 1..6 inputs, a random encoding (0..4 bands, none at 0, first exponent
// -1..2, with or without pi and the raw input, either order; redrawn while wider than the fused kernel's
// kFusedMlpMaxWidth), 1..4 layers, hidden widths 1..40 with ReLU, LeakyReLU, tanh, sigmoid or none, 1..5 outputs
// linear or exp, biases on three layers in four. top_band: the encoding's highest frequency the draw allows, 4 bands
// from 2^2 (arguments up to 2^5 pi = 100 rad), the rest drawn.
MlpSpec random_mlp_spec(std::mt19937& rng, bool top_band = false) {
    FrequencyEncoding e;
    const int inputs = draw(rng, 1, 6);
    do {
        e.bands = draw(rng, 0, 4);
        e.first_exponent = draw(rng, -1, 2);
        e.pi = draw(rng, 0, 1);
        e.include_input = draw(rng, 0, 1);
        e.order = draw(rng, 0, 1) ? FrequencyEncoding::Order::BandMajor : FrequencyEncoding::Order::ComponentMajor;
        if (top_band) {
            e.bands = 4;
            e.first_exponent = 2;
        }
    } while (e.width(inputs) > kFusedMlpMaxWidth);
    const int depth = draw(rng, 1, 4);
    MlpSpec s;
    s.inputs = inputs;
    s.encoding = e;
    int in = e.width(inputs);
    const Act acts[5] = {Act::relu(), Act::leaky(0.2f), Act::tanh(), Act::sigmoid(), Act::none()};
    for (int l = 0; l < depth; ++l) {
        const bool last = l + 1 == depth;
        DenseSpec d;
        d.in = in;
        d.out = last ? draw(rng, 1, 5) : draw(rng, 1, 40);
        d.act = last ? (draw(rng, 0, 1) ? Act::none() : Act::exp()) : acts[draw(rng, 0, 4)];
        const float a = std::sqrt(3.0f / float(in));  // He-like: activations O(1) through the layers
        d.weight = uniform(std::size_t(d.in) * d.out, rng, -a, a);
        if (draw(rng, 0, 3)) d.bias = uniform(d.out, rng, -0.5f, 0.5f);
        s.layers.push_back(std::move(d));
        in = s.layers.back().out;
    }
    return s;
}

// The reference of n items: [n][out] in double (ref::frequency_encode, then ref::dense per layer).
std::vector<std::vector<double>> mlp_reference(const MlpSpec& s, const std::vector<float>& x, int n, ItemLayout in) {
    std::vector<std::vector<double>> out(n);
    const FrequencyEncoding& e = s.encoding;
    for (int i = 0; i < n; ++i) {
        std::vector<double> v(s.inputs);
        for (int c = 0; c < s.inputs; ++c) v[c] = x[std::size_t(i) * in.item_stride + std::size_t(c) * in.channel_stride];
        v = ref::frequency_encode(v, e.bands, e.first_exponent, e.pi, e.include_input, int(e.order));
        for (const DenseSpec& d : s.layers) v = ref::dense(v, d.weight, d.bias, d.out, int(d.act.kind), d.act.alpha);
        out[i] = std::move(v);
    }
    return out;
}

double mlp_flops(const MlpSpec& s) {
    double macs = 0;
    for (const DenseSpec& d : s.layers) macs += double(d.in) * d.out;
    return 2.0 * macs;
}

Prepared fused_mlp_case(Context& ctx, const MlpSpec& spec, int n, bool planar_in, std::mt19937& rng) {
    Prepared r;
    const int out_c = spec.layers.back().out;
    r.shape = dims({{"n", n}, {"in", spec.inputs}, {"bands", spec.encoding.bands}, {"e0", spec.encoding.first_exponent},
                    {"layers", long(spec.layers.size())}, {"out", out_c}}) +
              (planar_in ? " planar->points" : " points->planar");
    const ItemLayout lin = planar_in ? ItemLayout::planar(n) : ItemLayout::points(spec.inputs);
    const ItemLayout lout = planar_in ? ItemLayout::points(out_c) : ItemLayout::planar(n);
    const auto x = uniform(std::size_t(n) * spec.inputs, rng);
    std::shared_ptr<FusedMlp> op;
    if (FusedMlp::fits_device(ctx, spec)) op = std::make_shared<FusedMlp>(ctx, spec);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, std::size_t(n) * out_c);
    r.flops = n * mlp_flops(spec);
    r.bytes = 4.0 * (double(x.size()) + double(n) * out_c);
    r.run = [=](Context& cx) {
        if (op) op->enqueue(cx, xb->mem(), xb->offset(), lin, n, yb->mem(), yb->offset(), lout);
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{yb->read_floats(cx), std::vector<double>(std::size_t(n) * out_c), {}, {}};
        if (!op) cmp.mismatch = "FusedMlp::fits_device refused the case's network on this device";
        const auto want = mlp_reference(spec, x, n, lin);
        for (int i = 0; i < n; ++i)
            for (int o = 0; o < out_c; ++o)
                cmp.want[std::size_t(i) * lout.item_stride + std::size_t(o) * lout.channel_stride] = want[i][o];
        return cmp;
    };
    return r;
}

Prepared dense_mlp_case(Context& ctx, const MlpSpec& spec, int n, std::mt19937& rng) {
    Prepared r;
    const int out_c = spec.layers.back().out;
    r.shape = dims({{"n", n}, {"in", spec.inputs}, {"bands", spec.encoding.bands}, {"e0", spec.encoding.first_exponent},
                    {"layers", long(spec.layers.size())}, {"out", out_c}});
    auto op = std::make_shared<DenseMlp>(ctx, gemm_selection(ctx).params, spec);
    const auto x = uniform(std::size_t(n) * spec.inputs, rng);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, std::size_t(n) * out_c);
    auto sb = add_out(ctx, r, "scratch", Role::Scratch, op->scratch_floats(n));
    r.flops = n * mlp_flops(spec);
    r.bytes = 4.0 * (double(x.size()) + double(n) * out_c);
    r.run = [=](Context& cx) {
        op->enqueue(cx, View{xb->mem(), xb->offset(), Shape{spec.inputs, 1, n}},
                    View{yb->mem(), yb->offset(), Shape{out_c, 1, n}}, sb->payload());
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{yb->read_floats(cx), std::vector<double>(std::size_t(n) * out_c), {}, {}};
        const auto want = mlp_reference(spec, x, n, ItemLayout::planar(n));
        for (int i = 0; i < n; ++i)
            for (int o = 0; o < out_c; ++o) cmp.want[std::size_t(o) * n + i] = want[i][o];
        return cmp;
    };
    return r;
}

Prepared frequency_encode_case(Context& ctx, int inputs, const FrequencyEncoding& enc, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}, {"in", inputs}, {"bands", enc.bands}, {"e0", enc.first_exponent}});
    auto op = std::make_shared<FrequencyEncodePlanar>(ctx, inputs, enc);
    const int width = op->width();
    const auto x = uniform(std::size_t(n) * inputs, rng);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, std::size_t(n) * width);
    r.flops = double(n) * width;
    r.bytes = 4.0 * (double(x.size()) + double(n) * width);
    r.run = [=](Context& cx) { op->enqueue(cx, xb->mem(), xb->offset(), yb->mem(), yb->offset(), n); };
    r.compare = [=](Context& cx) {
        Comparison cmp{yb->read_floats(cx), std::vector<double>(std::size_t(n) * width), {}, {}};
        for (int i = 0; i < n; ++i) {
            std::vector<double> v(inputs);
            for (int c = 0; c < inputs; ++c) v[c] = x[std::size_t(c) * n + i];
            const auto e = ref::frequency_encode(v, enc.bands, enc.first_exponent, enc.pi, enc.include_input, int(enc.order));
            for (int k = 0; k < width; ++k) cmp.want[std::size_t(k) * n + i] = e[k];
        }
        return cmp;
    };
    return r;
}

// ---- joint bilateral upsampling ------------------------------------------------------------------------------

// Guides of a w x h view of a fixed scene, sampled at pixel centres (u, v) in [0, 1]^2: a strip of sky at the top,
// a floor on the left, a slanted wall on the right (a crease between them), so the geometric weights, the fallback
// and surfaceless pixels all occur.
void jbu_guides(int w, int h, std::vector<float>& normal, std::vector<float>& position) {
    const std::size_t plane = std::size_t(w) * h;
    normal.assign(3 * plane, 0.0f);
    position.assign(3 * plane, 0.0f);
    const double wall_n[3] = {0.6, 0.0, 0.8};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double u = (x + 0.5) / w, v = (y + 0.5) / h;
            const std::size_t i = std::size_t(y) * w + x;
            if (v < 0.15) continue;  // sky
            if (u < 0.55) {          // floor y = 0
                const double p[3] = {2.0 * u, 0.0, 2.0 * v}, n[3] = {0.0, 1.0, 0.0};
                for (int k = 0; k < 3; ++k) { normal[k * plane + i] = float(n[k]); position[k * plane + i] = float(p[k]); }
            } else {  // a wall through (1.1, 0, 0) spanned by (0.8, 0, -0.6) and (0, 1, 0)
                const double s = 2.0 * (u - 0.55), t = 2.0 * v;
                const double p[3] = {1.1 + 0.8 * s, t, -0.6 * s};
                for (int k = 0; k < 3; ++k) { normal[k * plane + i] = float(wall_n[k]); position[k * plane + i] = float(p[k]); }
            }
        }
}

// Low values in [0, 4]; the guides of `scene` (tests/jbu_scene.hpp) or, without one, of jbu_guides' fixed scene.
Prepared jbu_case(Context& ctx, int w, int h, int W, int H, int channels, const JbuParams& params,
                  const test::jbu_scene::Scene* scene, std::mt19937& rng) {
    Prepared r;
    const int radius = params.radius;
    std::ostringstream extra;
    if (params.normal_power != JbuParams{}.normal_power) extra << " normal power " << params.normal_power;
    if (params.kernel != JbuParams::Kernel::Auto)
        extra << (params.kernel == JbuParams::Kernel::Rows8 ? " kernel rows8" : " kernel one-pixel");
    r.shape = std::to_string(w) + "x" + std::to_string(h) + " -> " + std::to_string(W) + "x" + std::to_string(H) +
              " C" + std::to_string(channels) + " r" + std::to_string(radius) + extra.str();
    test::JbuRefImage low{w, h, channels, uniform(std::size_t(channels) * w * h, rng, 0.0f, 4.0f), {}, {}};
    std::vector<float> normal, position;
    if (scene) {
        const auto lo = test::jbu_scene::render_guides(*scene, w, h), hi = test::jbu_scene::render_guides(*scene, W, H);
        low.normal = lo.normal;
        low.position = lo.position;
        normal = hi.normal;
        position = hi.position;
    } else {
        jbu_guides(w, h, low.normal, low.position);
        jbu_guides(W, H, normal, position);
    }
    auto op = std::make_shared<JointBilateralUpsample>(ctx);
    auto vb = add(ctx, r, "low", Role::Input, low.values), lnb = add(ctx, r, "low_normal", Role::Input, low.normal);
    auto lpb = add(ctx, r, "low_position", Role::Input, low.position);
    auto nb = add(ctx, r, "normal", Role::Input, normal), pb = add(ctx, r, "position", Role::Input, position);
    auto ob = add_out(ctx, r, "out", Role::Output, std::size_t(channels) * W * H);
    const double taps = 4.0 * radius * radius;
    r.flops = double(W) * H * taps * (2.0 * channels + 30.0);  // per tap: ~30 for the weight, 2 per channel
    r.bytes = 4.0 * (double(low.values.size()) + 6.0 * w * h + 6.0 * W * H + double(channels) * W * H);
    r.run = [=](Context& cx) {
        JbuInputs in;
        in.low_width = w;
        in.low_height = h;
        in.channels = channels;
        in.low = vb->payload();
        in.low_normal = lnb->payload();
        in.low_position = lpb->payload();
        in.width = W;
        in.height = H;
        in.normal = nb->payload();
        in.position = pb->payload();
        op->enqueue(cx, in, params, ob->payload(), false);
    };
    r.compare = [=](Context& cx) {
        const test::JbuRefResult want =
            test::jbu_reference(low, normal, position, W, H, test::jbu_ref_params(params));
        Comparison cmp{ob->read_floats(cx), want.out, {}, {}};
        int borderline = 0;
        for (int c = 0; c < channels; ++c) cmp.skip.insert(cmp.skip.end(), want.borderline.begin(), want.borderline.end());
        for (char b : want.borderline) borderline += b;
        const int fallbacks = op->fallback_count(cx);
        if (std::abs(fallbacks - want.fallbacks) > borderline)
            cmp.mismatch = std::to_string(fallbacks) + " fallbacks, the reference " + std::to_string(want.fallbacks) +
                           " (" + std::to_string(borderline) + " borderline)";
        return cmp;
    };
    return r;
}

// ---- spherical harmonics and set pooling ---------------------------------------------------------------------

Prepared sh_case(Context& ctx, int n, int channels, bool irradiance, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}, {"C", channels}}) + (irradiance ? " irradiance" : " radiance");
    auto op = std::make_shared<ShEvaluate>(ctx);
    std::vector<float> dir = uniform(3 * std::size_t(n), rng, -3.0f, 3.0f);  // not unit length: the kernel normalizes
    dir[0] = dir[1] = dir[2] = 0.0f;                                           // a zero direction: band 0 only
    const auto coef = uniform(std::size_t(n) * channels * kShCoefficients, rng);
    auto cb = add(ctx, r, "coef", Role::Input, coef), db = add(ctx, r, "dir", Role::Input, dir);
    auto ob = add_out(ctx, r, "out", Role::Output, std::size_t(n) * channels);
    r.flops = double(n) * (30.0 + 2.0 * kShCoefficients * channels);
    r.bytes = 4.0 * (double(coef.size()) + double(dir.size()) + double(n) * channels);
    r.run = [=](Context& cx) { op->enqueue(cx, cb->payload(), db->payload(), n, channels, irradiance, ob->payload()); };
    r.compare = [=](Context& cx) {
        Comparison cmp{ob->read_floats(cx), std::vector<double>(std::size_t(n) * channels), {}, {}};
        const double kPi = 3.14159265358979323846, lobe[3] = {kPi, 2 * kPi / 3, kPi / 4};
        for (int i = 0; i < n; ++i) {
            const double x = dir[3 * i], y = dir[3 * i + 1], z = dir[3 * i + 2];
            const double len = std::sqrt(x * x + y * y + z * z);
            for (int c = 0; c < channels; ++c) {
                double s = 0;
                for (int l = 0; l <= 2; ++l)
                    for (int m = -l; m <= l; ++m) {
                        const double Y = len > 0 ? ref::sh_basis(l, m, x / len, y / len, z / len)
                                                 : (l == 0 ? ref::sh_basis(0, 0, 0, 0, 1) : 0.0);
                        s += coef[(std::size_t(i) * channels + c) * 9 + l * (l + 1) + m] * (irradiance ? lobe[l] : 1.0) * Y;
                    }
                cmp.want[std::size_t(i) * channels + c] = s;
            }
        }
        return cmp;
    };
    return r;
}

// Set boundaries: `sets` sets of 0 .. 2 * mean items, set 3 empty (when there is one).
std::vector<int> set_boundaries(int sets, int mean, std::mt19937& rng) {
    std::vector<int> first = {0};
    for (int s = 0; s < sets; ++s) first.push_back(first.back() + (s == 3 ? 0 : int(rng() % unsigned(2 * mean + 1))));
    return first;
}

Prepared pool_case(Context& ctx, PoolMode mode, int channels, int sets, int mean, std::mt19937& rng) {
    Prepared r;
    const std::vector<int> first = set_boundaries(sets, mean, rng);
    const int n = first.back();
    r.shape = dims({{"sets", sets}, {"items", n}, {"C", channels}});
    auto op = std::make_shared<SetPool>(ctx);
    const auto x = uniform(std::size_t(n) * channels, rng, -5.0f, 5.0f);
    auto xb = add(ctx, r, "x", Role::Input, x), fb = add(ctx, r, "first", Role::Input, first);
    auto pb = add_out(ctx, r, "pooled", Role::Output, std::size_t(sets) * channels);
    r.flops = double(x.size());
    r.bytes = 4.0 * (double(x.size()) + double(first.size()) + double(sets) * channels);
    r.run = [=](Context& cx) { op->pool(cx, xb->payload(), channels, fb->payload(), sets, mode, pb->payload()); };
    r.compare = [=](Context& cx) {
        return Comparison{pb->read_floats(cx), ref::set_pool(x, channels, 1, channels, first, mode == PoolMode::Max), {}, {}};
    };
    return r;
}

Prepared broadcast_case(Context& ctx, int cx_channels, int cp, int sets, int mean, std::mt19937& rng) {
    Prepared r;
    const std::vector<int> first = set_boundaries(sets, mean, rng);
    const int n = first.back();
    r.shape = dims({{"sets", sets}, {"items", n}, {"Cx", cx_channels}, {"Cp", cp}});
    auto op = std::make_shared<SetPool>(ctx);
    std::vector<int> set_of(n);
    for (int s = 0; s < sets; ++s)
        for (int i = first[s]; i < first[s + 1]; ++i) set_of[i] = s;
    const auto x = uniform(std::size_t(n) * cx_channels, rng), pooled = uniform(std::size_t(sets) * cp, rng);
    auto xb = add(ctx, r, "x", Role::Input, x), pb = add(ctx, r, "pooled", Role::Input, pooled);
    auto sb = add(ctx, r, "set_of", Role::Input, set_of);
    const int width = cx_channels + cp;
    auto yb = add_out(ctx, r, "y", Role::Output, std::size_t(n) * width);
    r.bytes = 4.0 * (double(x.size()) + double(pooled.size()) + n + double(n) * width);
    r.run = [=](Context& cx) {
        op->broadcast_concat(cx, xb->payload(), cx_channels, pb->payload(), cp, sb->payload(), n, yb->payload());
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{yb->read_floats(cx), {}, {}, {}};
        for (int i = 0; i < n; ++i) {
            for (int c = 0; c < cx_channels; ++c) cmp.want.push_back(x[std::size_t(i) * cx_channels + c]);
            for (int c = 0; c < cp; ++c) cmp.want.push_back(pooled[std::size_t(set_of[i]) * cp + c]);
        }
        return cmp;
    };
    return r;
}

Prepared pool_planar_case(Context& ctx, PoolMode mode, int channels, int ld, int begin, int end, int max_per_launch,
                          std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"C", channels}, {"ld", ld}}) + " items " + std::to_string(begin) + ".." + std::to_string(end) +
              (max_per_launch ? " <= " + std::to_string(max_per_launch) + " per launch" : "");
    auto op = std::make_shared<SetPool>(ctx);
    const auto x = uniform(std::size_t(channels) * ld, rng, -3.0f, 2.0f);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto pb = add_out(ctx, r, "pooled", Role::Output, channels);
    r.flops = double(channels) * (end - begin);
    r.bytes = 4.0 * (double(channels) * (end - begin) + channels);
    r.run = [=](Context& cx) {
        op->pool_planar(cx, xb->mem(), xb->offset(), channels, ld, begin, end, mode, pb->mem(), pb->offset(),
                        max_per_launch);
    };
    r.compare = [=](Context& cx) {
        return Comparison{pb->read_floats(cx), ref::set_pool(x, 1, ld, channels, {begin, end}, mode == PoolMode::Max), {}, {}};
    };
    return r;
}

// ---- max pooling ---------------------------------------------------------------------------------------------

Prepared max_pool_case(Context& ctx, const MaxPoolGeometry& g, int C, int H, int W, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"C", C}, {"H", H}, {"W", W}, {"k", g.kh}, {"x", g.kw}, {"s", g.stride_h}, {"x", g.stride_w},
                    {"pad t", g.pad_top}, {"l", g.pad_left}, {"b", g.pad_bottom}, {"r", g.pad_right}});
    auto op = std::make_shared<MaxPool2d>(ctx, g);
    const Shape in{C, H, W}, out = op->output_shape(in);
    const auto x = uniform(in.size(), rng, -5.0f, 5.0f);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, out.size());
    r.flops = double(out.size()) * g.kh * g.kw;  // comparisons
    r.bytes = 4.0 * (double(in.size()) + double(out.size()));
    r.run = [=](Context& cx) { op->enqueue(cx, View{xb->mem(), xb->offset(), in}, View{yb->mem(), yb->offset(), out}); };
    r.compare = [=](Context& cx) {
        Comparison cmp;
        cmp.got = yb->read_floats(cx);
        int oh = 0, ow = 0;
        cmp.want = to_double(ref::max_pool2d(x, C, H, W, g.kh, g.kw, g.stride_h, g.stride_w, g.pad_top, g.pad_left,
                                             g.pad_bottom, g.pad_right, oh, ow));
        if (oh != out.h || ow != out.w) cmp.mismatch = "output shape differs from the reference's";
        return cmp;
    };
    return r;
}

// ---- padding and resizing ------------------------------------------------------------------------------------

Prepared pad_case(Context& ctx, const PadGeometry& g, int C, int H, int W, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"C", C}, {"H", H}, {"W", W}, {"pad t", g.top}, {"l", g.left}, {"b", g.bottom}, {"r", g.right}}) +
              " " + pad_mode_name(g.mode);
    auto op = std::make_shared<Pad2d>(ctx, g);
    const Shape in{C, H, W}, out = op->output_shape(in);
    const auto x = uniform(in.size(), rng, -5.0f, 5.0f);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, out.size());
    r.bytes = 4.0 * (double(in.size()) + double(out.size()));
    r.run = [=](Context& cx) { op->enqueue(cx, View{xb->mem(), xb->offset(), in}, View{yb->mem(), yb->offset(), out}); };
    r.compare = [=](Context& cx) {
        Comparison cmp;
        cmp.got = yb->read_floats(cx);
        cmp.want = to_double(ref::pad2d(x, C, H, W, g.top, g.left, g.bottom, g.right, int(g.mode), g.value));
        return cmp;
    };
    return r;
}

Prepared resize_case(Context& ctx, const ResizeGeometry& g, int C, int H, int W, std::mt19937& rng) {
    Prepared r;
    std::ostringstream scales;
    scales << " scales " << g.scale_h << " x " << g.scale_w << " " << resize_coord_name(g.mode);
    r.shape = dims({{"C", C}, {"H", H}, {"W", W}, {"OH", g.out_h}, {"OW", g.out_w}}) + scales.str();
    auto op = std::make_shared<ResizeBilinear>(ctx, g);
    const Shape in{C, H, W}, out = op->output_shape(in);
    const auto x = uniform(in.size(), rng, -5.0f, 5.0f);
    auto xb = add(ctx, r, "x", Role::Input, x);
    auto yb = add_out(ctx, r, "y", Role::Output, out.size());
    r.flops = 9.0 * double(out.size());  // 6 multiplies and 3 adds per output
    r.bytes = 4.0 * (double(in.size()) + double(out.size()));
    r.run = [=](Context& cx) { op->enqueue(cx, View{xb->mem(), xb->offset(), in}, View{yb->mem(), yb->offset(), out}); };
    r.compare = [=](Context& cx) {
        Comparison cmp;
        cmp.got = yb->read_floats(cx);
        cmp.want = ref::resize_bilinear(x, C, H, W, g.out_h, g.out_w, g.scale_h, g.scale_w, int(g.mode));
        return cmp;
    };
    return r;
}

// ---- image gathering -----------------------------------------------------------------------------------------

// n x n image under a layout: `format`, `channels` stored, interleaved (padded pixels and rows) or planar.
test::Layout gather_layout(PixelFormat format, int channels, int n, bool planar, bool bottom_up, bool scaled) {
    test::Layout l;
    l.format = format;
    l.channels = channels;
    const std::size_t elem = pixel_format_bytes(format);
    l.offset = elem * 5;
    if (pixel_format_packed_channels(format)) {  // one word per pixel (padded to two), its channels in it
        l.channel_stride = 0;
        l.pixel_stride = elem * 2;
        l.row_stride = l.pixel_stride * std::size_t(n) + 2 * elem;
    } else if (planar) {
        l.pixel_stride = elem;
        l.row_stride = elem * (std::size_t(n) + 3);
        l.channel_stride = l.row_stride * std::size_t(n) + elem;
    } else {
        l.channel_stride = elem;
        l.pixel_stride = elem * std::size_t(channels + 1);
        l.row_stride = l.pixel_stride * std::size_t(n) + 2 * elem;
    }
    l.bottom_up = bottom_up;
    l.scale = scaled ? 2.0f : 1.0f;
    l.bias = scaled ? -1.0f : 0.0f;
    return l;
}

Prepared gather_case(Context& ctx, const test::Layout& l, int need, int n, std::mt19937& rng) {
    Prepared r;
    r.shape = dims({{"n", n}, {"C", need}, {"of ", l.channels}}) +
              (pixel_format_packed_channels(l.format) ? " packed"
               : l.channel_stride == pixel_format_bytes(l.format) ? " interleaved" : " planar") +
              (l.bottom_up ? " bottom-up" : "");
    auto op = std::make_shared<GatherImage>(ctx);
    Image src(n, n, l.channels);
    src.data = uniform(src.data.size(), rng, 0.0f, 1.0f);
    if (l.format == PixelFormat::F32 || l.format == PixelFormat::F16)  // HDR values pass through
        for (std::size_t i = 0; i < src.data.size(); i += 7) src.data[i] = (i % 3 ? 65504.0f : -3.5f);
    std::vector<unsigned char> mem = test::store(l, n, src, rng);
    std::vector<std::uint32_t> words((mem.size() + 3) / 4, 0);
    std::memcpy(words.data(), mem.data(), mem.size());
    auto ib = add(ctx, r, "image", Role::Input, words);
    const int plane = n * n;
    auto ob = add_out(ctx, r, "planes", Role::Output, std::size_t(plane) * need);
    r.bytes = double(mem.size()) + 4.0 * plane * need;
    r.run = [=](Context& cx) {
        op->enqueue(cx, test::gather_source(l, ib->mem(), ib->offset_bytes()), need, n, ob->mem(), int(ob->offset()),
                    plane);
    };
    r.compare = [=](Context& cx) {
        Comparison cmp{ob->read_floats(cx), std::vector<double>(std::size_t(plane) * need), {}, {}};
        for (int c = 0; c < need; ++c)
            for (int row = 0; row < n; ++row)
                for (int col = 0; col < n; ++col)
                    cmp.want[std::size_t(c) * plane + std::size_t(row) * n + col] =
                        double(test::decode(mem, test::byte_of(l, n, row, col, c), l.format, c)) * l.scale + l.bias;
        return cmp;
    };
    return r;
}

// ---- probe shading -------------------------------------------------------------------------------------------

// A face looking down -z from above an X x Y x Z grid: every surface pixel gets a random depth and an axis normal,
// with its hit point kept 2e-3 m away from the 0.25 m lattice the lookups step on (where float and double could
// pick different cells); a tenth of the pixels is sky, a few have no normal; about 60% of the blocks hold a voxel.
test::ProbeRefInputs probe_scene(int n, bool sh, std::mt19937& rng) {
    test::ProbeRefInputs r;
    r.n = n;
    r.sh = sh;
    r.grid[0] = 9;
    r.grid[1] = 8;
    r.grid[2] = 7;
    const double centre[3] = {4.6, 3.9, 9.3}, look[3] = {0, 0, -1}, right[3] = {1, 0, 0}, up[3] = {0, 1, 0};
    for (int c = 0; c < 3; ++c) {
        r.centre[c] = float(centre[c]);
        r.look[c] = look[c];
        r.right[c] = right[c];
        r.up[c] = up[c];
    }
    const int npix = n * n;
    r.depth.assign(npix, 1.0e4f);
    r.normal.assign(std::size_t(3) * npix, 0.0f);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    auto near_lattice = [](double x) { return std::abs(x * 4.0 - std::round(x * 4.0)) < 8e-3; };
    for (int pix = 0; pix < npix; ++pix) {
        const double kind = u01(rng);
        if (kind < 0.1) continue;  // sky
        const int f = int(rng() % 6);
        double nr[3] = {0, 0, 0};
        if (kind >= 0.13) nr[f >> 1] = (f & 1) ? -1.0 : 1.0;  // else: a surface without a normal (a miss)
        const int row = pix / n, col = pix % n;
        const double u = 2.0 * (col + 0.5) / n - 1.0, v = 1.0 - 2.0 * (row + 0.5) / n;
        for (;;) {
            const float t = float(3.0 + u01(rng) * 6.0);
            // Along -z the ray's point at planar depth t is centre + t (u, v, -1).
            const double q[3] = {r.centre[0] + u * t - 0.5 * nr[0], r.centre[1] + v * t - 0.5 * nr[1],
                                 r.centre[2] - t - 0.5 * nr[2]};
            if (near_lattice(q[0]) || near_lattice(q[1]) || near_lattice(q[2])) continue;
            r.depth[pix] = t;
            for (int c = 0; c < 3; ++c) r.normal[std::size_t(c) * npix + pix] = float(nr[c]);
            break;
        }
    }
    r.index_of.assign(std::size_t(r.grid[0]) * r.grid[1] * r.grid[2], -1);
    for (int& cell : r.index_of)
        if (u01(rng) < 0.6) cell = r.voxels++;
    r.index_of[5] = r.voxels + 3;  // out of range: empty
    r.field = uniform(std::size_t(r.voxels) * (sh ? 27 : 4), rng);
    for (int i = 0; i < r.voxels; ++i)  // band 0 mostly dominant (lit), some clamped at 0; per-voxel light >= 0
        for (int c = 0; c < (sh ? 3 : 4); ++c) {
            float& v = r.field[sh ? std::size_t(27) * i + 9 * c : std::size_t(4) * i + c];
            v = std::abs(v) * 3.0f;
        }
    return r;
}

// tests/test_probe_shade.cpp's random scenes: a random orthonormal face basis (right x up = -look) from a centre in
// or near a grid of 4..10 blocks per axis; per pixel sky (10%), a damaged pixel (4%: NaN depth or an infinite
// normal component), else a random axis normal and a depth in 0.3..14.3 m whose hit point keeps 2e-3 m from the
// 0.25 m lattice; the block behind three hit points in four occupied, 10 random blocks more, in shuffled order;
// one index out of range (empty); at n >= 7 pixel 3 a surface without a normal (a miss). (A pixel whose 1,000 depths
// all came near the lattice stays sky; that file required there was none.)
test::ProbeRefInputs probe_random_scene(int n, bool sh, std::mt19937& rng) {
    using Vec = std::array<double, 3>;
    auto dot = [](const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    auto normalized = [&](Vec a) {
        const double l = std::sqrt(dot(a, a));
        for (double& x : a) x /= l;
        return a;
    };
    auto near_lattice = [](double x) { return std::abs(x * 4.0 - std::round(x * 4.0)) < 8e-3; };
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    std::normal_distribution<double> g(0.0, 1.0);
    test::ProbeRefInputs r;
    r.n = n;
    r.sh = sh;
    for (int c = 0; c < 3; ++c) r.grid[c] = draw(rng, 4, 10);
    const Vec look = normalized({g(rng), g(rng), g(rng)});
    Vec right = {g(rng), g(rng), g(rng)};
    const double k = dot(right, look);
    for (int c = 0; c < 3; ++c) right[c] -= k * look[c];
    right = normalized(right);
    const Vec up = {right[1] * look[2] - right[2] * look[1], right[2] * look[0] - right[0] * look[2],
                    right[0] * look[1] - right[1] * look[0]};  // right x look: right x up = -look
    for (int c = 0; c < 3; ++c) {  // the float camera is the one both see
        r.centre[c] = float(u01(rng) * (r.grid[c] + 4) - 2);
        r.look[c] = float(look[c]);
        r.right[c] = float(right[c]);
        r.up[c] = float(up[c]);
    }
    const int npix = n * n;
    r.depth.assign(npix, 1.0e4f);
    r.normal.assign(std::size_t(3) * npix, 0.0f);
    r.index_of.assign(std::size_t(r.grid[0]) * r.grid[1] * r.grid[2], -1);
    std::vector<int> cells;  // cells to occupy, in the order pixels claimed them
    for (int pix = 0; pix < npix; ++pix) {
        const double kind = u01(rng);
        if (kind < 0.1) continue;  // sky
        if (kind < 0.14) {         // a damaged pixel
            if (draw(rng, 0, 1)) r.depth[pix] = std::numeric_limits<float>::quiet_NaN();
            else r.normal[std::size_t(draw(rng, 0, 2)) * npix + pix] = std::numeric_limits<float>::infinity();
            continue;
        }
        const int row = pix / n, col = pix % n;
        const double u = 2.0 * (col + 0.5) / n - 1.0, v = 1.0 - 2.0 * (row + 0.5) / n;
        Vec dir;
        for (int c = 0; c < 3; ++c) dir[c] = r.look[c] + u * r.right[c] + v * r.up[c];
        dir = normalized(dir);
        const double along = dir[0] * r.look[0] + dir[1] * r.look[1] + dir[2] * r.look[2];
        const int f = draw(rng, 0, 5);
        double nr[3] = {0, 0, 0};
        nr[f >> 1] = (f & 1) ? -1.0 : 1.0;
        // A ray nearly parallel to a lattice plane near that plane keeps every depth ambiguous: left as sky then.
        for (int attempt = 0; attempt < 1000; ++attempt) {
            const float depth = float(0.3 + u01(rng) * 14.0);
            double q[3];
            bool ambiguous = false;
            for (int c = 0; c < 3; ++c) {
                q[c] = r.centre[c] + dir[c] * (double(depth) / along) - 0.5 * nr[c];
                ambiguous |= near_lattice(q[c]);
            }
            if (ambiguous) continue;
            r.depth[pix] = depth;
            for (int c = 0; c < 3; ++c) r.normal[std::size_t(c) * npix + pix] = float(nr[c]);
            bool inside = true;
            for (int c = 0; c < 3; ++c) inside &= q[c] >= 0 && q[c] < r.grid[c];
            if (inside && u01(rng) < 0.75) cells.push_back(int(q[0]) + r.grid[0] * (int(q[1]) + r.grid[1] * int(q[2])));
            break;
        }
    }
    if (n >= 7) {  // a surface pixel with no normal: counted as a miss
        r.depth[3] = 2.0f;
        for (int c = 0; c < 3; ++c) r.normal[std::size_t(c) * npix + 3] = 0.0f;
    }
    const int blocks = int(r.index_of.size());
    for (int extra = 0; extra < 10; ++extra) cells.push_back(draw(rng, 0, blocks - 1));
    std::shuffle(cells.begin(), cells.end(), rng);
    for (int cell : cells)
        if (r.index_of[cell] < 0) r.index_of[cell] = r.voxels++;
    r.index_of[draw(rng, 0, blocks - 1)] = r.voxels + 3;  // out of range: empty
    // Band 0 mostly dominant (most pixels lit, some clamped at 0); per-voxel light >= 0.
    r.field = uniform(std::size_t(r.voxels) * (sh ? 27 : 4), rng);
    if (sh)
        for (int i = 0; i < r.voxels; ++i)
            for (int c = 0; c < 3; ++c) {
                float& band0 = r.field[std::size_t(27) * i + 9 * c];
                band0 = std::abs(band0) * 3.0f;
            }
    else
        for (float& x : r.field) x = std::abs(x) * 5.0f;
    return r;
}

// random: probe_random_scene, else probe_scene (looking down -z).
Prepared probe_case(Context& ctx, int n, bool sh, std::mt19937& rng, bool random = false) {
    Prepared r;
    r.shape = dims({{"n", n}}) + (sh ? " SH-27" : " per-voxel") + (random ? " random camera" : "");
    const test::ProbeRefInputs s = random ? probe_random_scene(n, sh, rng) : probe_scene(n, sh, rng);
    auto op = std::make_shared<ProbeShade>(ctx);
    auto db = add(ctx, r, "depth", Role::Input, s.depth), nb = add(ctx, r, "normal", Role::Input, s.normal);
    auto ib = add(ctx, r, "index_of", Role::Input, s.index_of), fb = add(ctx, r, "field", Role::Input, s.field);
    auto ob = add_out(ctx, r, "out", Role::Output, std::size_t(3) * n * n);
    r.flops = double(n) * n * (sh ? 120.0 : 40.0);
    r.bytes = 4.0 * 7 * double(n) * n;
    r.run = [=](Context& cx) {
        ProbeShadeInputs in;
        in.n = n;
        in.depth = db->payload();
        in.normal = nb->payload();
        for (int c = 0; c < 3; ++c) {
            in.camera.centre[c] = float(s.centre[c]);
            in.camera.look[c] = float(s.look[c]);
            in.camera.right[c] = float(s.right[c]);
            in.camera.up[c] = float(s.up[c]);
            in.grid[c] = s.grid[c];
        }
        in.index_of = ib->payload();
        in.voxels = s.voxels;
        in.mode = sh ? ProbeField::Sh : ProbeField::PerVoxel;
        in.field = fb->payload();
        op->enqueue(cx, in, ob->payload(), false);
    };
    r.compare = [=](Context& cx) {
        const test::ProbeRefResult want = test::probe_shade_reference(s);
        Comparison cmp{ob->read_floats(cx), want.lighting, {}, {}};
        const ProbeShadeCounts counts = op->counts(cx);
        if (counts.no_voxel != want.no_voxel || counts.non_finite != want.non_finite)
            cmp.mismatch = "counts no_voxel " + std::to_string(counts.no_voxel) + " non_finite " +
                           std::to_string(counts.non_finite) + ", the reference " + std::to_string(want.no_voxel) +
                           " and " + std::to_string(want.non_finite);
        return cmp;
    };
    return r;
}

// ---- light-transition function -------------------------------------------------------------------------------

// V voxels at integer block centres (+0.5) of a cube of side `extent`, face or smooth normals, random exposed
// faces, albedo in [0, 1], direct light in [0, 2].
test::LtfScene ltf_scene(int V, int extent, std::mt19937& rng) {
    test::LtfScene s;
    s.voxels = V;
    for (auto* v : {&s.position, &s.normal, &s.albedo, &s.direct}) v->assign(std::size_t(4) * V, 0.0f);
    s.exposed.resize(V);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    for (int i = 0; i < V; ++i) {
        float* p = &s.position[std::size_t(4) * i];
        float* nr = &s.normal[std::size_t(4) * i];
        for (int c = 0; c < 3; ++c) p[c] = float(rng() % unsigned(extent)) + 0.5f;
        if (i % 3 == 0) {
            float len = 0;
            for (int c = 0; c < 3; ++c) { nr[c] = g(rng); len += nr[c] * nr[c]; }
            for (int c = 0; c < 3; ++c) nr[c] /= std::sqrt(len);
        } else {
            const int f = int(rng() % 6);
            nr[f >> 1] = (f & 1) ? -1.0f : 1.0f;
        }
        s.exposed[i] = 1u + std::uint32_t(rng() % 63);
        for (int c = 0; c < 3; ++c) {
            s.albedo[std::size_t(4) * i + c] = u01(rng);
            s.direct[std::size_t(4) * i + c] = 2.0f * u01(rng);
        }
    }
    return s;
}

Prepared ltf_case(Context& ctx, int V, int bounces, LtfVariant variant, LtfKernelShape shape, bool mask,
                  int max_senders, std::mt19937& rng) {
    Prepared r;
    const bool physical = variant == LtfVariant::Physical;
    r.shape = dims({{"V", V}, {"bounces", bounces}}) + (mask ? " mask" : "") +
              (max_senders ? " senders/launch " + std::to_string(max_senders) : "");
    const test::LtfScene s = ltf_scene(V, V < 40 ? 4 : 12, rng);
    const int words = (V + 31) / 32;
    std::vector<std::uint32_t> vis(std::size_t(V) * words);
    for (auto& w : vis) w = std::uint32_t(rng()) | std::uint32_t(rng());  // three pairs in four visible
    auto op = std::make_shared<VoxelLtf>(ctx, shape);
    op->set_max_senders_per_launch(max_senders);
    auto pb = add(ctx, r, "position", Role::Input, s.position), nb = add(ctx, r, "normal", Role::Input, s.normal);
    auto ab = add(ctx, r, "albedo", Role::Input, s.albedo), db = add(ctx, r, "direct", Role::Input, s.direct);
    auto eb = add(ctx, r, "exposed", Role::Input, s.exposed);
    BufferPtr mb = mask ? add(ctx, r, "visibility", Role::Input, vis) : nullptr;
    auto ob = add_out(ctx, r, "out", Role::Output, std::size_t(4) * V);
    r.flops = double(bounces) * V * double(V) * 40.0;  // ~40 flops per pair term (distance, cosines, areas, rgb)
    r.bytes = 4.0 * 17 * V + (mask ? 4.0 * double(vis.size()) : 0.0);
    r.run = [=](Context& cx) {
        LtfInputs in;
        in.voxels = V;
        in.position = pb->payload();
        in.normal = nb->payload();
        in.albedo = ab->payload();
        in.direct = db->payload();
        in.exposed = eb->payload();
        op->run(cx, in, bounces, variant, mb ? mb->payload() : nullptr, ob->payload());
    };
    r.compare = [=](Context& cx) {
        return Comparison{ob->read_floats(cx), test::ltf_reference(s, bounces, physical, mask ? &vis : nullptr), {}, {}};
    };
    return r;
}

// ---- the table -----------------------------------------------------------------------------------------------

// Tolerances (normalized_error, op_cases.hpp): each a small factor over the worst error observed for the op's rows
// on PoCL 3.1 (CPU) and Mesa rusticl (llvmpipe), 2026-11, and never looser than what the docs and the op's own tests
// claim (docs/RELIABILITY.md, "Op harness", has the table). One float rounding of the largest output is 2^-24 =
// 6e-8 of it; exact ops (comparisons, copies) have tolerance 0: any difference is a bug.
// GEMM: fp32 fma accumulation over K in another order than the double reference; worst 5.4e-7 at K = 512 (the
// generator-layer row), 1.8e-7 at K = 45. docs/RELIABILITY.md claims "near 1e-6"; 4x the worst.
constexpr double kTolGemm = 2e-6;
// GEMMs of K <= 90 only (the rows of tests/test_gemm.cpp's random small shapes): that file's bound, sum_of(K + 8),
// allows at the largest output at least gamma_(K + 8) |want| >= gamma_9 max |want| = 5.4e-7 of it (K = 1); worst
// 2.2e-7 (the device's fallback chain, K <= 70).
constexpr double kTolGemmShortK = 5e-7;
// A dense layer whose exp outputs reach 8.9 (tests/test_dense.cpp bounded it by 1e-5 absolute + relative).
constexpr double kTolDenseExp = 1e-6;
// Convolutions: the same GEMM over K = Cin KH KW <= 192 here; worst 4.4e-7 (k4 s2 im2col).
constexpr double kTolConv = 2e-6;
// PackB: a copy, but for the activation's slope (0.2f on the device, 0.2 in the reference): worst 2.0e-8.
constexpr double kTolPack = 1e-7;
// Batch norm: fp32 statistics over H W (two-pass on the device); worst 2.0e-7 (tiny, interleaved).
constexpr double kTolNorm = 1e-6;
// Activations: OpenCL's exp may be 3 ulp off, activation.cl's tanh is <= 1.51 ulp; worst 8.7e-8 (tanh).
constexpr double kTolActivate = 5e-7;
// One or two roundings (x / (1 - p), scale * x + shift, x + y, x * y): worst 6.2e-8 (channel_affine, rusticl).
constexpr double kTolExactish = 2.5e-7;
constexpr double kTolExact = 0.0;
// MLPs: fp32 dense layers of <= 37 inputs, sin/cos of the encoding; worst 3.7e-7 (fused, band-major encoding).
constexpr double kTolMlp = 2e-6;
// MLPs whose encoding reaches 2^5 pi (the random architectures' top band): the float argument (up to 100 rad) alone
// is rounded by up to ~1e-5 rad (an ulp at 100 is 7.6e-6, and the constant 2^5 pi's rounding as much), which the
// sin/cos features carry into the first layer; worst 1.6e-6 (fused, one layer, max |want| 5.2). Below the 1e-4
// absolute + relative of tests/test_mlp.cpp's sweep while max |want| <= 10 (5.2 and 0.64 for these rows).
constexpr double kTolMlpTopBand = 1e-5;
// Frequency encoding alone: sin/cos of arguments up to 2^2 pi, rounded in float first; worst 8.2e-7.
constexpr double kTolEncode = 4e-6;
// JBU: float exp/pow weights of up to 36 taps; worst 3.7e-7 (radius 3). Its test claims < 1e-5 of the range.
constexpr double kTolJbu = 2e-6;
// SH: 9 products per channel after a normalization; worst 2.5e-7 (irradiance).
constexpr double kTolSh = 1e-6;
// Mean pooling: fp32 sums of up to 5,000 items; worst 9.4e-8.
constexpr double kTolPoolMean = 5e-7;
// Image gathering: exact but for scale * x + bias (a possible fma); sRGB codes through the host's table, the
// reference's pow in double; worst 1.2e-7 (measured while the kernel still used pow).
constexpr double kTolGather = 1e-6;
// Probe shading: SH-27 irradiance per pixel; worst 1.4e-7.
constexpr double kTolProbe = 1e-6;
// Light-transition function: fp32 sums over V = 97 senders per bounce, 2 bounces; worst 3.5e-7 (physical, tiled).
constexpr double kTolLtf = 2e-6;
// Bilinear resize: exact source positions, float weights (one division each) and three lerps; worst 1.2e-7
// (asymmetric 7 -> 3, 9 -> 20, PoCL). tests/test_resize.cpp claims 1e-6 of max |x| (its derivation there; its
// cases reach 2.3e-7 on PoCL and rusticl).
constexpr double kTolResize = 1e-6;

int pick(Size size, int test, int perf) { return size == Size::Perf ? perf : test; }

std::string knobs_name(const GemmParams& p) { return "knobs " + p.to_string(); }

// The device's GEMM knob set, as the convolution tests use it; the implicit path needs a gemm_packed set (its
// GPU entry's tiles without local memory).
GemmParams device_gemm(Context& ctx) { return gemm_params_for(ctx.info()); }
GemmParams implicit_gemm(Context& ctx) {
    GemmParams p = gemm_params_for(ctx.info());
    p.kwg = 0;
    return p;
}

std::vector<OpCase> build_table() {
    std::vector<OpCase> t;
    auto row = [&t](std::string op, std::string name, bool tiny, double tol,
                    std::function<Prepared(Context&, Size, std::mt19937&)> prepare) {
        t.push_back(OpCase{std::move(op), std::move(name), tiny, tol, std::move(prepare)});
    };

    // GEMM: every knob set of the GPU and CPU tables with their fallback chains at one odd shape (every tile
    // dimension has a remainder), the device's own set at a generator layer's shape (K 512), the first GPU and the
    // first CPU set tiny.
    const std::vector<GemmParams> variants = gemm_variants();
    for (std::size_t i = 0; i < variants.size(); ++i) {
        const GemmParams p = variants[i];
        row("Gemm::enqueue", knobs_name(p), false, kTolGemm, [p](Context& c, Size z, std::mt19937& rng) {
            return gemm_case(c, p, pick(z, 37, 256), pick(z, 67, 4099), pick(z, 45, 1152), 2, rng);
        });
    }
    row("Gemm::enqueue", "device set, generator layer", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        return gemm_case(c, gemm_selection(c).params, 64, pick(z, 517, 8192), 512, 2, rng);
    });
    {
        DeviceInfo gpu, cpu;
        gpu.is_gpu = true;
        cpu.is_cpu = true;
        for (const GemmParams& p : {gemm_params_for(gpu), gemm_params_for(cpu)})
            row("Gemm::enqueue", "tiny " + knobs_name(p), true, kTolGemm,
                [p](Context& c, Size, std::mt19937& rng) { return gemm_case(c, p, 7, 9, 13, 3, rng); });
    }

    // Knob sets beyond the table, at tests/test_gemm.cpp's random small shapes (M, N, K in 1..70, an activation 0..4;
    // 3 per set, drawn by the row): the device's fallback chain (its tuning entry's set, often none of the table's
    // generic ones, and every fallback), that set's loop form (UNROLL 0) and each knob at an extreme; gemm_local's
    // sets at the edges of their blocks and at random shapes in 1..150, in a row of sums of K <= 90 and one of longer
    // ones. That file bounded K <= 90 by sum_of(K + 8) (kTolGemmShortK: no looser at the largest output) and longer
    // sums by 1e-4 absolute + relative (kTolGemm is stricter). Perf: the first set at a mid-sized layer (gemm_local's
    // short-sum rows: K 64 over 4099 columns).
    const auto perf_gemm = [](const GemmParams& p, bool short_k = false) {
        return std::vector<GemmRun>{{p, 256, short_k ? 4099 : 1031, short_k ? 64 : 576, 2}};
    };
    row("Gemm::enqueue", "device fallback chain, every set, 3 random shapes each", false, kTolGemmShortK,
        [perf_gemm](Context& c, Size z, std::mt19937& rng) {
            const auto chain = gemm_fallback_chain(gemm_params_for(c.info()));
            return gemm_runs_case(c, z == Size::Perf ? perf_gemm(chain.front()) : random_gemm_runs(chain, 3, rng),
                                  true, rng);
        });
    row("Gemm::enqueue", "device set's loop form (UNROLL 0), 3 random shapes", false, kTolGemmShortK,
        [perf_gemm](Context& c, Size z, std::mt19937& rng) {
            GemmParams p = gemm_params_for(c.info());
            p.unroll = 0;
            return gemm_runs_case(c, z == Size::Perf ? perf_gemm(p) : random_gemm_runs({p}, 3, rng), true, rng);
        });
    for (const GemmParams& p : gemm_extreme_variants())
        row("Gemm::enqueue", "extreme " + knobs_name(p) + ", 3 random shapes", false, kTolGemmShortK,
            [p, perf_gemm](Context& c, Size z, std::mt19937& rng) {
                return gemm_runs_case(c, z == Size::Perf ? perf_gemm(p) : random_gemm_runs({p}, 3, rng), false, rng);
            });
    for (const GemmParams& p : gemm_local_variants())
        for (bool long_sums : {false, true})
            row("Gemm::enqueue",
                "gemm_local " + knobs_name(p) + (long_sums ? ", K 91..192: " : ", K <= 90: ") +
                    "its block's edges and 3 random shapes",
                false, long_sums ? kTolGemm : kTolGemmShortK,
                [p, long_sums, perf_gemm](Context& c, Size z, std::mt19937& rng) {
                    const auto runs = z == Size::Perf ? perf_gemm(p, !long_sums) : local_gemm_runs(p, long_sums, rng);
                    return gemm_runs_case(c, runs, false, rng);
                });

    // PackB: the device's set, K and N not multiples of KU and NR, LeakyReLU on the way (the slope fast path).
    row("PackB::enqueue", "device set", false, kTolPack, [](Context& c, Size z, std::mt19937& rng) {
        const GemmParams p = device_gemm(c);
        return pack_b_case(c, p, pick(z, 13, 512), pick(z, 2 * p.nr() + 1, 8192), 2, rng);
    });
    row("PackB::enqueue", "tiny", true, kTolPack,
        [](Context& c, Size, std::mt19937& rng) { return pack_b_case(c, device_gemm(c), 3, 5, 1, rng); });

    // Convolutions: each path (im2col / pack + GEMM; implicit GEMM) at odd sizes; perf at U-Net layer sizes.
    const struct {
        const char* name;
        ConvShape test, perf;
        ConvPath path;
        bool transposed, tiny;
    } convs[] = {
        {"k3 s1 p1 im2col", {13, 23, 19, 11, 3, 3, 1, 1, 0, 2}, {32, 128, 256, 32, 3, 3, 1, 1, 0, 2}, ConvPath::im2col, false, false},
        {"k4 s2 p1 im2col", {12, 33, 47, 16, 4, 4, 2, 1, 2, 0}, {32, 128, 256, 64, 4, 4, 2, 1, 2, 0}, ConvPath::im2col, false, false},
        {"k4 s2 p1 implicit", {12, 33, 47, 16, 4, 4, 2, 1, 2, 0}, {32, 128, 256, 64, 4, 4, 2, 1, 2, 0}, ConvPath::implicit, false, false},
        {"k1 1x1 (PackB) im2col", {13, 5, 31, 11, 1, 1, 1, 0, 1, 3}, {64, 64, 128, 64, 1, 1, 1, 0, 1, 3}, ConvPath::im2col, false, false},
        {"k1 1x1 implicit, input read in place", {13, 5, 31, 11, 1, 1, 1, 0, 0, 3}, {64, 64, 128, 64, 1, 1, 1, 0, 0, 1}, ConvPath::implicit, false, false},
        {"tiny k1 1x1 implicit, input read in place", {5, 5, 7, 6, 1, 1, 1, 0, 0, 1}, {}, ConvPath::implicit, false, true},
        {"k5x3 s3 p2 im2col", {4, 11, 6, 3, 5, 3, 3, 2, 0, 4}, {16, 128, 256, 16, 5, 3, 3, 2, 0, 4}, ConvPath::im2col, false, false},
        {"tiny k3 s1 p1 im2col", {5, 7, 9, 6, 3, 3, 1, 1, 0, 2}, {}, ConvPath::im2col, false, true},
        {"tiny k4 s2 p1 implicit", {5, 7, 9, 9, 4, 4, 2, 1, 2, 3}, {}, ConvPath::implicit, false, true},
        {"k4 s2 p1 col2im", {16, 9, 13, 12, 4, 4, 2, 1, 1, 0}, {64, 32, 64, 32, 4, 4, 2, 1, 1, 0}, ConvPath::im2col, true, false},
        {"k4 s2 p1 implicit", {16, 9, 13, 12, 4, 4, 2, 1, 1, 0}, {64, 32, 64, 32, 4, 4, 2, 1, 1, 0}, ConvPath::implicit, true, false},
        {"k4 s2 p1 implicit, Cout 3", {16, 9, 13, 3, 4, 4, 2, 1, 1, 3}, {32, 128, 64, 3, 4, 4, 2, 1, 1, 3}, ConvPath::implicit, true, false},
        {"tiny k4 s2 p1 implicit, Cout 3", {5, 3, 5, 3, 4, 4, 2, 1, 1, 3}, {}, ConvPath::implicit, true, true},
        {"k3 s2 p1 col2im", {5, 6, 7, 4, 3, 3, 2, 1, 0, 3}, {32, 64, 128, 16, 3, 3, 2, 1, 0, 3}, ConvPath::im2col, true, false},
        {"tiny k4 s2 p1 col2im", {5, 3, 5, 3, 4, 4, 2, 1, 1, 0}, {}, ConvPath::im2col, true, true},
        {"tiny k4 s2 p1 implicit", {5, 3, 5, 9, 4, 4, 2, 1, 1, 0}, {}, ConvPath::implicit, true, true},
    };
    for (const auto& k : convs)
        row(k.transposed ? "ConvTranspose2d::enqueue" : "Conv2d::enqueue", k.name, k.tiny, kTolConv,
            [k](Context& c, Size z, std::mt19937& rng) {
                const GemmParams p = k.path == ConvPath::implicit ? implicit_gemm(c) : device_gemm(c);
                return conv_case(c, p, z == Size::Perf && !k.tiny ? k.perf : k.test, k.transposed, k.path, rng);
            });
    // tests/test_conv.cpp's random sweeps: geometries drawn by each row (random_conv: C, Cout 1..40, H, W 1..23 or
    // 1..17, kernels 1..5 per axis, padding min / 2, input activation 0..2, output activation 0..4), each stride
    // through im2col, and through an implicit request, which keeps im2col where the geometry is not exact
    // (conv_takes_implicit says which path the op must take); one drawn among the exact geometries. K = Cin KH KW
    // reaches 1,000 here: that file bounded these by 1e-4 absolute + relative (fp32 accumulation); kTolConv is
    // stricter (2e-6 of max |want| <= 2.2 here).
    const struct {
        const char* name;
        int stride;
        ConvPath path;
        bool exact;
    } random_convs[] = {
        {"random shape 1, stride 1, im2col", 1, ConvPath::im2col, false},
        {"random shape 2, stride 2, im2col", 2, ConvPath::im2col, false},
        {"random shape 3, stride 3, im2col", 3, ConvPath::im2col, false},
        {"random shape 4, stride 1, implicit asked", 1, ConvPath::implicit, false},
        {"random shape 5, stride 2, implicit asked", 2, ConvPath::implicit, false},
        {"random exact geometry 6, stride 2, implicit", 2, ConvPath::implicit, true},
    };
    for (bool transposed : {false, true})
        for (const auto& m : random_convs)
            row(transposed ? "ConvTranspose2d::enqueue" : "Conv2d::enqueue", m.name, false, kTolConv,
                [m, transposed](Context& c, Size z, std::mt19937& rng) {
                    const GemmParams p = m.path == ConvPath::implicit ? implicit_gemm(c) : device_gemm(c);
                    const ConvShape k = random_conv(rng, transposed, m.stride, m.exact, p);
                    const bool implicit = m.path == ConvPath::implicit &&
                                          conv_takes_implicit(k.kh, k.kw, k.s, k.p, k.in_act, transposed, p);
                    return conv_case(c, p, z == Size::Perf ? perf_conv(k, transposed) : k, transposed, m.path, rng,
                                     implicit);
                });
    // The sweeps' fixed corners the rows above leave out: a 1 x 1 output, a 1 x 1 input, a stride-3 k5 transposed
    // convolution asked for the implicit path (not exact: im2col).
    const struct {
        const char* name;
        ConvShape test, perf;
        ConvPath path;
        bool transposed, implicit;
    } conv_corners[] = {
        {"2x2 -> 1x1, k4 s2 p1 implicit", {8, 2, 2, 9, 4, 4, 2, 1, 2, 3}, {64, 2, 2, 64, 4, 4, 2, 1, 2, 3},
         ConvPath::implicit, false, true},
        {"1x1 input, k3 s1 p1 im2col", {5, 1, 1, 7, 3, 3, 1, 1, 0, 4}, {256, 1, 1, 256, 3, 3, 1, 1, 0, 4},
         ConvPath::im2col, false, false},
        {"1x1 bottleneck -> 2x2, k4 s2 p1 implicit", {9, 1, 1, 5, 4, 4, 2, 1, 1, 2}, {256, 1, 1, 256, 4, 4, 2, 1, 1, 2},
         ConvPath::implicit, true, true},
        {"k5 s3 p2, implicit asked (im2col: not exact)", {3, 5, 4, 6, 5, 5, 3, 2, 2, 4},
         {32, 64, 128, 16, 5, 5, 3, 2, 2, 4}, ConvPath::implicit, true, false},
    };
    for (const auto& k : conv_corners)
        row(k.transposed ? "ConvTranspose2d::enqueue" : "Conv2d::enqueue", k.name, false, kTolConv,
            [k](Context& c, Size z, std::mt19937& rng) {
                const GemmParams p = k.path == ConvPath::implicit ? implicit_gemm(c) : device_gemm(c);
                return conv_case(c, p, z == Size::Perf ? k.perf : k.test, k.transposed, k.path, rng, k.implicit);
            });
    // tests/test_conv.cpp's implicit-GEMM geometries (ops/conv_implicit.hpp), each through im2col and the implicit
    // path with the implicit path's knob set (the device's set, KWG 0), as that file ran them: every stride that
    // divides the kernel, polyphase splits of 2, 3 and 4, 1 to 9 taps, odd sizes, spatial sizes below a tile (the
    // junk columns of one partial tile), a 1 x 1 input, channel counts below and above MR. That file bounded them
    // by 1e-4 absolute + relative; K = Cin KH KW <= 192 (kTolConv). Perf: each geometry over a U-Net-sized plane.
    const struct {
        const char* name;
        ConvShape test;
        bool transposed;
    } implicit_geometries[] = {
        {"the U-Net's first layer, shrunk", {12, 64, 128, 16, 4, 4, 2, 1, 0, 2}, false},
        {"odd sizes: the last row's polyphase planes short", {7, 13, 11, 9, 4, 4, 2, 1, 2, 0}, false},
        {"k2 s2 p0: one tap over 4 planes", {5, 9, 7, 10, 2, 2, 2, 0, 1, 1}, false},
        {"k6 s2 p2: 3 x 3 taps", {3, 10, 14, 8, 6, 6, 2, 2, 0, 3}, false},
        {"k3 s3: a 3 x 3 polyphase split, one tap", {4, 11, 13, 9, 3, 3, 3, 1, 1, 0}, false},
        {"k3 s1 p1: padding only", {6, 17, 9, 11, 3, 3, 1, 1, 2, 4}, false},
        {"k1: a plain copy as B", {9, 5, 3, 12, 1, 1, 1, 0, 1, 0}, false},
        {"2x2 -> 1x1", {5, 2, 2, 9, 4, 4, 2, 1, 2, 3}, false},
        {"1x1 input", {3, 1, 1, 8, 3, 3, 1, 1, 0, 0}, false},
        {"non-square kernel, Cout < MR", {2, 6, 10, 3, 4, 2, 2, 1, 0, 0}, false},
        {"the U-Net's up-convolution", {16, 4, 8, 12, 4, 4, 2, 1, 1, 0}, true},
        {"odd sizes", {7, 3, 5, 9, 4, 4, 2, 1, 0, 3}, true},
        {"1x1 bottleneck -> 2x2", {9, 1, 1, 10, 4, 4, 2, 1, 1, 2}, true},
        {"k2 s2 p0: one tap per phase, no padding", {5, 6, 7, 8, 2, 2, 2, 0, 2, 0}, true},
        {"k6 s2 p2: 3 x 3 taps per phase", {4, 5, 6, 9, 6, 6, 2, 2, 0, 1}, true},
        {"k8 s4 p2: 16 phases of 2 x 2 taps", {3, 4, 5, 8, 8, 8, 4, 2, 1, 0}, true},
        {"k3 s1 p1: one phase, a flipped 3 x 3 convolution", {6, 7, 3, 9, 3, 3, 1, 1, 0, 4}, true},
        {"k3 s3 p0: 9 phases of one tap", {5, 3, 4, 11, 3, 3, 3, 0, 1, 0}, true},
        {"Cout 3 < MR: tiles of 4 rows", {6, 5, 9, 3, 4, 4, 2, 1, 1, 3}, true},
    };
    for (const auto& g : implicit_geometries)
        for (const ConvPath path : {ConvPath::im2col, ConvPath::implicit})
            row(g.transposed ? "ConvTranspose2d::enqueue" : "Conv2d::enqueue",
                std::string("exact geometry, ") + g.name + (path == ConvPath::implicit ? ", implicit" : ", im2col"),
                false, kTolConv, [g, path](Context& c, Size z, std::mt19937& rng) {
                    const GemmParams p = implicit_gemm(c);
                    const ConvShape k = z == Size::Perf ? perf_conv(g.test, g.transposed) : g.test;
                    const bool implicit = path == ConvPath::implicit &&
                                          conv_takes_implicit(k.kh, k.kw, k.s, k.p, k.in_act, g.transposed, p);
                    return conv_case(c, p, k, g.transposed, path, rng, implicit);
                });

    // Dense layers over planar items: tiles of the device's set at odd sizes (n not a tile multiple, a row stride
    // beyond n), item-major output, a residual, fewer items than a tile; perf at seed 004's 128-wide layers.
    row("Dense::enqueue", "planar", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), pick(z, 37, 128), pick(z, 29, 128), pick(z, 203, 10000),
                          pick(z, 211, 10000), false, false, 3, rng);
    });
    row("Dense::enqueue", "item-major", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), pick(z, 37, 128), 27, pick(z, 203, 10000), pick(z, 203, 10000), true,
                          false, 0, rng);
    });
    row("Dense::enqueue", "residual", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), pick(z, 33, 128), pick(z, 33, 128), pick(z, 101, 10000),
                          pick(z, 101, 10000), false, true, 3, rng);
    });
    row("Dense::enqueue", "fewer items than a tile", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), pick(z, 19, 256), pick(z, 23, 128), 1, 1, false, false, 0, rng);
    });
    row("Dense::enqueue", "tiny", true, kTolGemm, [](Context& c, Size, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), 5, 7, 3, 3, true, true, 1, rng);
    });
    // tests/test_dense.cpp's random sweep: widths 1..70, 1..300 items, a row stride n + 0..9 (exactly n below a
    // tile), one row per activation, item-major output on rows 1, 4, 7, a residual on rows 2 and 6 (that file's
    // pattern over its trials); perf: the drawn options at 128 -> 128 over 10,000 items. That file bounded them by
    // 1e-5 absolute + relative (fp32 sums of <= 256 terms); kTolGemm is stricter where max |want| <= 5 (2.9 here).
    // (The exp row's outputs reach 8.9: 2e-6 of that would pass 1e-5 absolute, so it keeps 1e-6: worst 1.7e-7.)
    for (int a = 0; a <= int(Activation::Erf); ++a)
        row("Dense::enqueue", "random shape " + std::to_string(a) + ", " + to_string(Activation(a)), false,
            a == int(Activation::Exp) ? kTolDenseExp : kTolGemm,
            [a](Context& c, Size z, std::mt19937& rng) {
                const GemmParams p = implicit_gemm(c);
                const int in = draw(rng, 1, 70), out = draw(rng, 1, 70), n = draw(rng, 1, 300);
                const int ld = n < p.nr() ? n : n + draw(rng, 0, 9);
                const bool item_major = a % 3 == 1, residual = a % 4 == 2;
                if (z == Size::Perf) return dense_case(c, p, 128, 128, 10000, 10007, item_major, residual, a, rng);
                return dense_case(c, p, in, out, n, ld, item_major, residual, a, rng);
            });
    // Its fixed corners: exact tile multiples everywhere, and a voxel network's layer on one item.
    row("Dense::enqueue", "exact tile multiples, residual", false, kTolGemm, [](Context& c, Size z, std::mt19937& rng) {
        const GemmParams p = implicit_gemm(c);
        const int n = pick(z, 4, 2048) * p.nr();
        return dense_case(c, p, 128, 128, n, n, false, true, 3, rng);
    });
    row("Dense::enqueue", "256 -> 128, one item", false, kTolGemm, [](Context& c, Size, std::mt19937& rng) {
        return dense_case(c, implicit_gemm(c), 256, 128, 1, 1, false, false, 0, rng);
    });

    // Per-image batch norm: both reductions, in two launches and in one (the small-plane form; at perf size a
    // 64 x 32 plane, the N = 64 generators' largest normalized one); and one work-item per channel (the form of the
    // planes of a few values: 8 x 4 at perf size).
    using Form = BatchNormPerImage::Form;
    for (bool chunked : {true, false}) {
        const std::string name = chunked ? "chunked" : "interleaved";
        row("BatchNormPerImage::enqueue", name, false, kTolNorm, [chunked](Context& c, Size z, std::mt19937& rng) {
            return batch_norm_case(c, chunked, Form::two_pass, pick(z, 7, 64), pick(z, 37, 128), pick(z, 29, 256), rng);
        });
        row("BatchNormPerImage::enqueue", "tiny " + name, true, kTolNorm, [chunked](Context& c, Size, std::mt19937& rng) {
            return batch_norm_case(c, chunked, Form::two_pass, 3, 5, 3, rng);
        });
        row("BatchNormPerImage::enqueue", "one launch " + name, false, kTolNorm,
            [chunked](Context& c, Size z, std::mt19937& rng) {
                return batch_norm_case(c, chunked, Form::work_group, pick(z, 7, 64), pick(z, 37, 32), pick(z, 29, 64),
                                       rng);
            });
        row("BatchNormPerImage::enqueue", "tiny one launch " + name, true, kTolNorm,
            [chunked](Context& c, Size, std::mt19937& rng) {
                return batch_norm_case(c, chunked, Form::work_group, 3, 5, 3, rng);
            });
    }
    row("BatchNormPerImage::enqueue", "serial", false, kTolNorm, [](Context& c, Size z, std::mt19937& rng) {
        return batch_norm_case(c, true, Form::serial, pick(z, 7, 128), pick(z, 13, 8), pick(z, 11, 4), rng);
    });
    row("BatchNormPerImage::enqueue", "tiny serial", true, kTolNorm,
        [](Context& c, Size, std::mt19937& rng) { return batch_norm_case(c, true, Form::serial, 3, 5, 3, rng); });

    // Elementwise.
    for (int a = 0; a <= int(Activation::Erf); ++a)
        row("Elementwise::activate", to_string(Activation(a)), false, kTolActivate,
            [a](Context& c, Size z, std::mt19937& rng) { return activate_case(c, act_of(a), pick(z, 1031, 1 << 22), rng); });
    row("Elementwise::activate", "tiny tanh", true, kTolActivate,
        [](Context& c, Size, std::mt19937& rng) { return activate_case(c, Act::tanh(), 17, rng); });
    row("Elementwise::dropout", "p 0.3", false, kTolExactish,
        [](Context& c, Size z, std::mt19937& rng) { return dropout_case(c, pick(z, 1031, 1 << 22), rng); });
    row("Elementwise::dropout", "tiny", true, kTolExactish,
        [](Context& c, Size, std::mt19937& rng) { return dropout_case(c, 9, rng); });
    row("Elementwise::sanitize + sanitized_count", "[-1, 1]", false, kTolExact,
        [](Context& c, Size z, std::mt19937& rng) { return sanitize_case(c, pick(z, 1031, 1 << 22), rng); });
    row("Elementwise::sanitize + sanitized_count", "tiny", true, kTolExact,
        [](Context& c, Size, std::mt19937& rng) { return sanitize_case(c, 15, rng); });
    for (bool points : {true, false})
        row("Elementwise::channel_affine", points ? "points in" : "planar in", false, kTolExactish,
            [points](Context& c, Size z, std::mt19937& rng) {
                return channel_affine_case(c, points, 10, pick(z, 1001, 1 << 18), rng);
            });
    row("Elementwise::channel_affine", "tiny points in", true, kTolExactish,
        [](Context& c, Size, std::mt19937& rng) { return channel_affine_case(c, true, 3, 5, rng); });
    for (bool multiply : {false, true}) {
        const char* op = multiply ? "Elementwise::mul" : "Elementwise::add";
        row(op, "odd n", false, kTolExactish,
            [multiply](Context& c, Size z, std::mt19937& rng) { return binary_case(c, multiply, pick(z, 1031, 1 << 22), rng); });
        row(op, "tiny", true, kTolExactish,
            [multiply](Context& c, Size, std::mt19937& rng) { return binary_case(c, multiply, 15, rng); });
    }

    // MLPs. Static: no encoding, small enough for the shape-specialized kernel (one program per architecture: the
    // perf size changes the item count only). Generic: an encoding, so the generic fused kernel.
    const FrequencyEncoding none;
    const FrequencyEncoding band_major{3, -1, true, true, FrequencyEncoding::Order::BandMajor};
    const FrequencyEncoding component_major{2, 0, true, false, FrequencyEncoding::Order::ComponentMajor};
    row("FusedMlp::enqueue", "static architecture", false, kTolMlp, [none](Context& c, Size z, std::mt19937& rng) {
        const MlpSpec s = mlp_spec(5, none, {16, 8, 2}, Act::none(), rng);
        return fused_mlp_case(c, s, pick(z, 517, 1 << 18), true, rng);
    });
    row("FusedMlp::enqueue", "generic, band-major encoding", false, kTolMlp,
        [band_major](Context& c, Size z, std::mt19937& rng) {
            const MlpSpec s = mlp_spec(3, band_major, {21, 13, 3}, Act::exp(), rng);
            return fused_mlp_case(c, s, pick(z, 331, 1 << 18), false, rng);
        });
    row("FusedMlp::enqueue", "tiny", true, kTolMlp, [](Context& c, Size, std::mt19937& rng) {
        const MlpSpec s = mlp_spec(3, {2, -1, true, true, FrequencyEncoding::Order::BandMajor}, {7, 2}, Act::exp(), rng);
        return fused_mlp_case(c, s, 5, true, rng);
    });
    row("DenseMlp::enqueue", "component-major encoding", false, kTolMlp,
        [component_major](Context& c, Size z, std::mt19937& rng) {
            const MlpSpec s = mlp_spec(4, component_major, {37, 19, 3}, Act::none(), rng);
            return dense_mlp_case(c, s, pick(z, 403, 1 << 18), rng);
        });
    row("DenseMlp::enqueue", "tiny", true, kTolMlp, [band_major](Context& c, Size, std::mt19937& rng) {
        const MlpSpec s = mlp_spec(3, band_major, {7, 2}, Act::exp(), rng);
        return dense_mlp_case(c, s, 5, rng);
    });
    // tests/test_mlp.cpp's random architectures (random_mlp_spec), drawn by each row: the fused kernel with planar
    // input and point output and the reverse, the dense path (planar); one item on the first rows, else 1..700; the
    // last rows with the highest band the draw allows. Perf: the drawn network over 2^18 items. That file bounded them
    // by 1e-4 absolute + relative; kTolMlp is stricter (2e-6 of max |want| <= 7.9 here), kTolMlpTopBand too (above).
    for (int k = 1; k <= 6; ++k)
        row("FusedMlp::enqueue",
            "random architecture " + std::to_string(k) + (k % 2 ? ", planar in" : ", points in") +
                (k == 6 ? ", top band" : ""),
            false, k == 6 ? kTolMlpTopBand : kTolMlp, [k](Context& c, Size z, std::mt19937& rng) {
                const MlpSpec s = random_mlp_spec(rng, k == 6);
                const int n = k == 1 ? 1 : draw(rng, 1, 700);
                return fused_mlp_case(c, s, pick(z, n, 1 << 18), k % 2 == 1, rng);
            });
    for (int k = 1; k <= 3; ++k)
        row("DenseMlp::enqueue", "random architecture " + std::to_string(k) + (k == 3 ? ", top band" : ""), false,
            k == 3 ? kTolMlpTopBand : kTolMlp, [k](Context& c, Size z, std::mt19937& rng) {
                const MlpSpec s = random_mlp_spec(rng, k == 3);
                const int n = k == 1 ? 1 : draw(rng, 1, 700);
                return dense_mlp_case(c, s, pick(z, n, 1 << 18), rng);
            });
    row("FrequencyEncodePlanar::enqueue", "Eq. 3 style, 4 bands", false, kTolEncode, [](Context& c, Size z, std::mt19937& rng) {
        return frequency_encode_case(c, 3, {4, -1, true, true, FrequencyEncoding::Order::BandMajor}, pick(z, 517, 1 << 18), rng);
    });
    row("FrequencyEncodePlanar::enqueue", "tiny", true, kTolEncode, [component_major](Context& c, Size, std::mt19937& rng) {
        return frequency_encode_case(c, 2, component_major, 5, rng);
    });

    // JBU: a non-integer ratio, an integer one, tiny.
    const auto radius = [](int r) {
        JbuParams p;
        p.radius = r;
        return p;
    };
    row("JointBilateralUpsample::enqueue", "non-integer ratio, radius 2", false, kTolJbu,
        [radius](Context& c, Size z, std::mt19937& rng) {
            return jbu_case(c, pick(z, 13, 128), pick(z, 9, 64), pick(z, 41, 512), pick(z, 29, 256), 3, radius(2),
                            nullptr, rng);
        });
    row("JointBilateralUpsample::enqueue", "ratio 3, radius 3", false, kTolJbu,
        [radius](Context& c, Size z, std::mt19937& rng) {
            return jbu_case(c, pick(z, 11, 128), pick(z, 7, 64), pick(z, 33, 384), pick(z, 21, 192), 5, radius(3),
                            nullptr, rng);
        });
    row("JointBilateralUpsample::enqueue", "tiny", true, kTolJbu, [radius](Context& c, Size, std::mt19937& rng) {
        return jbu_case(c, 5, 3, 19, 11, 3, radius(2), nullptr, rng);
    });
    // A display view's ratio (~15x: an N = 64 lightmap shown at 960 x 960, the pixels of 1280 x 720; perf size exactly
    // that): jbu_upsample8 with its shared tap columns and with the per-lane gathers they replace, a random scene. On
    // devices that do not run the 8-pixel kernel by default both rows take the one-pixel kernel.
    for (bool shared : {true, false})
        row("JointBilateralUpsample::enqueue", std::string("display ratio 15, ") + (shared ? "shared columns" : "gathers"),
            false, kTolJbu, [shared](Context& c, Size z, std::mt19937& rng) {
                const test::jbu_scene::Scene scene = test::jbu_scene::random_scene(rng);
                JbuParams p;
                p.shared_columns = shared;
                return jbu_case(c, pick(z, 9, 64), pick(z, 7, 64), pick(z, 133, 960), pick(z, 101, 960), 3, p, &scene,
                                rng);
            });
    // tests/test_jbu.cpp's random sweep, its trials 0..7 as rows: a random scene (tests/jbu_scene.hpp: 1..4 random
    // planar rectangles, axis-aligned half of the time, sometimes a sky rectangle, over a random background plane),
    // low sizes 1..23 x 1..19; odd rows an integer ratio 1..5, even rows any output size 1..61 x 1..47 (smaller than
    // the input too); channels 1, 3, 5; radius 1..3; normal power 7.5 (pow, not squaring) on rows 1 and 5, 0 (the
    // normal term off) on rows 3 and 7; where Auto would pick the 8-pixel kernel (PoCL's CPUs, <= 4 channels) rows 0,
    // 1, 5, 6 force the one-pixel one (on Mesa's llvmpipe the 8-pixel kernel's build alone takes ~65 s: it runs
    // under oclgrind there). Perf: the drawn scene and options, 128 x 64 up by the ratio or to 501 x 247. That file
    // bounded them by 1e-4 of the value range 4 (observed < 1e-5); kTolJbu is stricter.
    for (int k = 0; k < 8; ++k)
        row("JointBilateralUpsample::enqueue", "random scene " + std::to_string(k), false, kTolJbu,
            [k](Context& c, Size z, std::mt19937& rng) {
                const test::jbu_scene::Scene scene = test::jbu_scene::random_scene(rng);
                int w = draw(rng, 1, 23), h = draw(rng, 1, 19), W, H;
                const int f = draw(rng, 1, 5);
                if (k % 2) {
                    W = w * f;
                    H = h * f;
                } else {
                    W = draw(rng, 1, 61);
                    H = draw(rng, 1, 47);
                }
                if (z == Size::Perf) {
                    w = 128;
                    h = 64;
                    W = k % 2 ? w * f : 501;
                    H = k % 2 ? h * f : 247;
                }
                const int channels = std::array<int, 3>{1, 3, 5}[k % 3];
                JbuParams p;
                p.radius = 1 + k % 3;
                if (k % 4 == 3) p.normal_power = 0.0f;
                if (k % 4 == 1) p.normal_power = 7.5f;
                if (channels <= kJbuVecMaxChannels && jbu_vector_device(c.info()))
                    p.kernel = k % 5 < 2 ? JbuParams::Kernel::OnePixel : JbuParams::Kernel::Rows8;
                return jbu_case(c, w, h, W, H, channels, p, &scene, rng);
            });

    // SH.
    for (bool irr : {false, true})
        row("ShEvaluate::enqueue", irr ? "irradiance" : "radiance", false, kTolSh,
            [irr](Context& c, Size z, std::mt19937& rng) { return sh_case(c, pick(z, 301, 1 << 18), 3, irr, rng); });
    row("ShEvaluate::enqueue", "tiny irradiance", true, kTolSh,
        [](Context& c, Size, std::mt19937& rng) { return sh_case(c, 3, 3, true, rng); });

    // Set pooling.
    for (PoolMode mode : {PoolMode::Max, PoolMode::Mean}) {
        const bool max = mode == PoolMode::Max;
        const double tol = max ? kTolExact : kTolPoolMean;
        row("SetPool::pool", max ? "max" : "mean", false, tol, [mode](Context& c, Size z, std::mt19937& rng) {
            return pool_case(c, mode, 17, 9, pick(z, 150, 20000), rng);
        });
        row("SetPool::pool_planar", max ? "max, split launches" : "mean, split launches", false, tol,
            [mode](Context& c, Size z, std::mt19937& rng) {
                const int ld = pick(z, 5000, 1 << 18);
                return pool_planar_case(c, mode, 7, ld, 3, ld - 2, pick(z, 640, 0), rng);
            });
        row("SetPool::pool_planar", max ? "max, one launch" : "mean, one launch", false, tol,
            [mode](Context& c, Size z, std::mt19937& rng) {
                return pool_planar_case(c, mode, 5, pick(z, 301, 1 << 18), 17, pick(z, 251, (1 << 18) - 1), 0, rng);
            });
    }
    row("SetPool::pool", "tiny mean", true, kTolPoolMean,
        [](Context& c, Size, std::mt19937& rng) { return pool_case(c, PoolMode::Mean, 2, 4, 2, rng); });
    row("SetPool::pool_planar", "tiny max, split", true, kTolExact,
        [](Context& c, Size, std::mt19937& rng) { return pool_planar_case(c, PoolMode::Max, 2, 70, 1, 69, 32, rng); });
    row("SetPool::broadcast_concat", "odd widths", false, kTolExact,
        [](Context& c, Size z, std::mt19937& rng) { return broadcast_case(c, 5, 17, 9, pick(z, 150, 20000), rng); });
    row("SetPool::broadcast_concat", "tiny", true, kTolExact,
        [](Context& c, Size, std::mt19937& rng) { return broadcast_case(c, 2, 3, 4, 2, rng); });

    // Max pooling (exact: every output is one of the inputs): odd sizes, asymmetric pads, stride above the kernel;
    // perf at U-Net-sized planes.
    const struct {
        const char* name;
        MaxPoolGeometry g;
        int c, h, w, perf_c, perf_h, perf_w;
        bool tiny;
    } max_pools[] = {
        {"k2 s2", {2, 2, 2, 2, 0, 0, 0, 0}, 7, 33, 47, 64, 256, 512, false},
        {"k3 s2 p1", {3, 3, 2, 2, 1, 1, 1, 1}, 13, 37, 29, 64, 256, 512, false},
        {"k5x3 s3x1, asymmetric pads", {5, 3, 3, 1, 4, 0, 1, 2}, 5, 23, 19, 32, 256, 256, false},
        {"k2 s3, stride above the kernel", {2, 2, 3, 3, 0, 1, 1, 0}, 3, 17, 31, 32, 256, 256, false},
        {"tiny k3 s2 p1", {3, 3, 2, 2, 1, 1, 1, 1}, 3, 5, 7, 0, 0, 0, true},
    };
    for (const auto& m : max_pools)
        row("MaxPool2d::enqueue", m.name, m.tiny, kTolExact, [m](Context& c, Size z, std::mt19937& rng) {
            const bool perf = z == Size::Perf && !m.tiny;
            return max_pool_case(c, m.g, perf ? m.perf_c : m.c, perf ? m.perf_h : m.h, perf ? m.perf_w : m.w, rng);
        });

    // Padding (exact: copies and the constant): each mode, odd sizes, asymmetric pads; perf at U-Net-sized planes.
    const struct {
        const char* name;
        PadGeometry g;
        int c, h, w, perf_c, perf_h, perf_w;
        bool tiny;
    } pads[] = {
        {"constant, asymmetric", {1, 2, 3, 0, PadMode::Constant, -0.5f}, 7, 33, 47, 64, 256, 512, false},
        {"reflect, largest pads", {12, 16, 12, 16, PadMode::Reflect, 0.0f}, 5, 13, 17, 32, 256, 256, false},
        {"edge, one side", {0, 0, 9, 4, PadMode::Edge, 0.0f}, 13, 29, 37, 64, 256, 512, false},
        {"tiny reflect", {2, 1, 1, 3, PadMode::Reflect, 0.0f}, 3, 5, 7, 0, 0, 0, true},
    };
    for (const auto& m : pads)
        row("Pad2d::enqueue", m.name, m.tiny, kTolExact, [m](Context& c, Size z, std::mt19937& rng) {
            const bool perf = z == Size::Perf && !m.tiny;
            return pad_case(c, m.g, perf ? m.perf_c : m.c, perf ? m.perf_h : m.h, perf ? m.perf_w : m.w, rng);
        });

    // Bilinear resize: each coordinate mode, up and down by non-integer factors, explicit scales; perf at a U-Net
    // decoder's x2.
    const struct {
        const char* name;
        ResizeGeometry g;
        int c, h, w;
        ResizeGeometry perf_g;
        int perf_c, perf_h, perf_w;
        bool tiny;
    } resizes[] = {
        {"half_pixel x2", {34, 46, 0, 0, ResizeCoord::HalfPixel}, 7, 17, 23,
         {256, 512, 0, 0, ResizeCoord::HalfPixel}, 64, 128, 256, false},
        {"align_corners 5 -> 7, 37 -> 11", {7, 11, 0, 0, ResizeCoord::AlignCorners}, 13, 5, 37,
         {256, 512, 0, 0, ResizeCoord::AlignCorners}, 64, 128, 256, false},
        {"asymmetric 7 -> 3, 9 -> 20", {3, 20, 0, 0, ResizeCoord::Asymmetric}, 5, 7, 9,
         {128, 256, 0, 0, ResizeCoord::Asymmetric}, 64, 256, 512, false},
        {"pytorch_half_pixel, explicit scales", {11, 6, 1.7f, 0.6f, ResizeCoord::PytorchHalfPixel}, 3, 7, 11,
         {435, 307, 1.7f, 0.6f, ResizeCoord::PytorchHalfPixel}, 32, 256, 512, false},
        {"tiny half_pixel 3x5 -> 5x2", {5, 2, 0, 0, ResizeCoord::HalfPixel}, 2, 3, 5, {}, 0, 0, 0, true},
    };
    for (const auto& m : resizes)
        row("ResizeBilinear::enqueue", m.name, m.tiny, kTolResize, [m](Context& c, Size z, std::mt19937& rng) {
            const bool perf = z == Size::Perf && !m.tiny;
            return resize_case(c, perf ? m.perf_g : m.g, perf ? m.perf_c : m.c, perf ? m.perf_h : m.h,
                               perf ? m.perf_w : m.w, rng);
        });

    // Image gathering: each format, interleaved and planar, both row orders.
    const struct {
        const char* name;
        PixelFormat format;
        int channels, need, n, perf_n;
        bool planar, bottom_up, scaled, tiny;
    } gathers[] = {
        {"F16 RGBA interleaved, bottom-up", PixelFormat::F16, 4, 3, 33, 1024, false, true, false, false},
        {"F32 depth, planar", PixelFormat::F32, 1, 1, 17, 1024, true, false, false, false},
        {"U8 sRGB planar, scale and bias", PixelFormat::U8Srgb, 3, 3, 13, 1024, true, true, true, false},
        {"U8 unorm interleaved", PixelFormat::U8Unorm, 4, 3, 29, 1024, false, false, false, false},
        {"tiny F16 interleaved", PixelFormat::F16, 4, 3, 3, 0, false, true, false, true},
        {"U16 unorm interleaved", PixelFormat::U16Unorm, 4, 3, 19, 1024, false, true, false, false},
        {"S16 snorm planar", PixelFormat::S16Snorm, 2, 2, 15, 1024, true, false, false, false},
        {"R11G11B10F packed, bottom-up", PixelFormat::R11G11B10F, 3, 3, 21, 1024, false, true, false, false},
        {"RGB10A2 packed, scale and bias", PixelFormat::RGB10A2Unorm, 4, 3, 11, 1024, false, false, true, false},
    };
    for (const auto& g : gathers)
        row("GatherImage::enqueue", g.name, g.tiny, kTolGather, [g](Context& c, Size z, std::mt19937& rng) {
            const int n = z == Size::Perf && !g.tiny ? g.perf_n : g.n;
            return gather_case(c, gather_layout(g.format, g.channels, n, g.planar, g.bottom_up, g.scaled), g.need, n, rng);
        });

    // Probe shading: both fields, odd n.
    for (bool sh : {true, false})
        row("ProbeShade::enqueue", sh ? "SH-27 field" : "per-voxel field", false, kTolProbe,
            [sh](Context& c, Size z, std::mt19937& rng) { return probe_case(c, pick(z, 37, 512), sh, rng); });
    row("ProbeShade::enqueue", "tiny SH-27", true, kTolProbe,
        [](Context& c, Size, std::mt19937& rng) { return probe_case(c, 3, true, rng); });
    // tests/test_probe_shade.cpp's random sweep (probe_random_scene: random cameras, NaN and Inf pixels, grids of
    // 4..10 blocks), odd and even faces, both fields; perf at n 512. That file bounded them by 1e-5 absolute +
    // relative; kTolProbe is stricter (1e-6 of max |want| <= 5 here).
    const std::pair<int, bool> random_probes[] = {{1, true},   {2, false},  {7, true},
                                                  {16, false}, {33, true}, {33, false}};
    for (const auto& probe_row : random_probes) {
        const int n = probe_row.first;  // copies: clang 15 cannot capture structured bindings in lambdas
        const bool sh = probe_row.second;
        row("ProbeShade::enqueue", "random camera, n " + std::to_string(n) + (sh ? ", SH-27" : ", per-voxel"), false,
            kTolProbe, [n, sh](Context& c, Size z, std::mt19937& rng) {
                return probe_case(c, pick(z, n, 512), sh, rng, true);
            });
    }

    // Light-transition function: each kernel shape, both variants, the visibility mask, a split of the senders.
    const struct {
        const char* name;
        LtfVariant variant;
        LtfKernelShape shape;
        bool mask;
        int split;
        int v;
        bool tiny;
    } ltfs[] = {
        {"physical, mask, plain", LtfVariant::Physical, LtfKernelShape::Plain, true, 0, 97, false},
        {"physical, mask, tiled", LtfVariant::Physical, LtfKernelShape::Tiled, true, 0, 97, false},
        {"physical, mask, vector, split senders", LtfVariant::Physical, LtfKernelShape::Vector, true, 40, 97, false},
        {"as written, vector", LtfVariant::AsWritten, LtfKernelShape::Vector, false, 0, 97, false},
        {"as written, tiled", LtfVariant::AsWritten, LtfKernelShape::Tiled, false, 0, 97, false},
        {"tiny physical, mask, vector", LtfVariant::Physical, LtfKernelShape::Vector, true, 3, 5, true},
        {"tiny as written, tiled", LtfVariant::AsWritten, LtfKernelShape::Tiled, false, 0, 5, true},
    };
    for (const auto& l : ltfs)
        row("VoxelLtf::run", l.name, l.tiny, kTolLtf, [l](Context& c, Size z, std::mt19937& rng) {
            const bool perf = z == Size::Perf && !l.tiny;
            return ltf_case(c, perf ? 4096 : l.v, perf ? 1 : 2, l.variant, l.shape, l.mask, perf ? 0 : l.split, rng);
        });
    return t;
}

}  // namespace

std::vector<GemmParams> gemm_variants() {
    DeviceInfo gpu, cpu;
    gpu.is_gpu = true;
    cpu.is_cpu = true;
    std::vector<GemmParams> sets;
    for (const DeviceInfo* info : {&gpu, &cpu})
        for (const GemmParams& p : gemm_fallback_chain(gemm_params_for(*info)))
            if (std::find(sets.begin(), sets.end(), p) == sets.end()) sets.push_back(p);
    return sets;
}

std::vector<GemmParams> gemm_extreme_variants() {
    // Small micro-kernels: unrolled bodies of hundreds of vector fmas take minutes to compile on Mesa, and the extreme
    // value is what a wrong index would break.
    std::vector<GemmParams> v;
    for (const char* k : {"16,1,1,1,1,2,1", "1,2,8,1,4,1,1", "1,1,1,16,1,1,1", "3,16,1,2,2,1,1", "5,8,1,3,3,1,0",
                          "2,4,2,2,4,4,1"})
        v.push_back(parse_gemm_params(k));
    return v;
}

std::vector<GemmParams> gemm_local_variants() {
    std::vector<GemmParams> v;
    for (const char* k : {"4,4,1,1,8,8,1,16", "2,2,2,1,4,16,1,8", "8,8,1,1,4,4,0,32", "3,4,2,2,2,8,1,12",
                          "4,4,1,1,16,16,1,16"})
        v.push_back(parse_gemm_params(k));
    return v;
}

bool conv_takes_implicit(int kh, int kw, int stride, int pad, int in_act, bool transposed, const GemmParams& gp) {
    if (gp.kwg > 0 || in_act > int(Activation::LeakyReLU) || kh % stride || kw % stride) return false;
    return !transposed || (kh - 2 * pad == stride && kw - 2 * pad == stride);
}

std::mt19937 case_rng(const OpCase& c) {
    std::uint32_t seed = 2166136261u;  // FNV-1a of the id
    for (char ch : c.id()) seed = (seed ^ std::uint8_t(ch)) * 16777619u;
    return std::mt19937(seed);
}

const std::vector<OpCase>& op_cases() {
    static const std::vector<OpCase> table = build_table();
    return table;
}

Outcome run_case(Context& ctx, const OpCase& c, Size size) {
    std::mt19937 rng = case_rng(c);  // the same data on every run and device, independent of the table's order
    Prepared p = c.prepare(ctx, size, rng);
    p.run(ctx);
    ctx.finish();
    Outcome o;
    o.shape = p.shape;
    for (const auto& b : p.buffers)
        if (std::string damaged = b->check(ctx, c.id()); !damaged.empty() && o.failure.empty()) o.failure = damaged;
    const Comparison cmp = p.compare(ctx);
    if (o.failure.empty() && !cmp.mismatch.empty()) o.failure = c.id() + ": " + cmp.mismatch;
    // The normalized error (op_cases.hpp): |got - want| over max |want|, infinite where got is not finite.
    const test::Comparison r =
        test::compare(cmp.got, cmp.want, test::Tol::scaled(c.tolerance, "the op's row, op_cases.cpp"), cmp.skip);
    o.error = !r.problem.empty() || r.nonfinite ? INFINITY : r.max_abs / r.scale;
    o.worst = r.report();
    return o;
}

}  // namespace ngi::harness

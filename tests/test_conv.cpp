// conv2d and conv_transpose2d (im2col / pack + packed GEMM + epilogue / col2im) against the naive reference,
// over random shapes: odd sizes, 1x1 spatial, channel counts and pixel counts that are not tile multiples.
#include <algorithm>
#include <catch2/catch.hpp>

#include "ops/conv.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

struct Case {
    int c, h, w, co, kh, kw, s, p, in_act, act;
};

std::vector<float> run_conv(const Case& k, const std::vector<float>& x, const std::vector<float>& w,
                            const ChannelAffine& aff, bool transposed, Shape& out, const GemmParams& gp) {
    auto& c = test::ctx();
    ConvSpec spec{k.c, k.co, {k.kh, k.kw, k.s, k.p}, {Activation(k.in_act), 0.2f}, {Activation(k.act), 0.2f}};
    Shape in{k.c, k.h, k.w};
    Buffer xb = test::upload(x);
    std::size_t scratch_n = 0;
    std::vector<float> y;
    auto go = [&](auto& op) {
        out = op.output_shape(in);
        scratch_n = op.scratch_floats(in);
        // Offsets inside bigger buffers: the planner places tensors at arbitrary offsets.
        Buffer yb = c.alloc((out.size() + 7) * sizeof(float), "y");
        Buffer sb = c.alloc((scratch_n + 5) * sizeof(float), "scratch");
        op.enqueue(c, View{xb.get(), 0, in}, View{yb.get(), 7, out}, sb.get(), 5);
        y = test::download(yb, out.size(), 7);
    };
    if (transposed) {
        ConvTranspose2d op(c, gp, spec, w.data(), aff);
        go(op);
    } else {
        Conv2d op(c, gp, spec, w.data(), aff);
        go(op);
    }
    return y;
}

void check_case(const Case& k, bool transposed, std::mt19937& rng, const GemmParams& gp) {
    auto x = test::random_vector(std::size_t(k.c) * k.h * k.w, rng);
    auto w = test::random_vector(std::size_t(k.c) * k.co * k.kh * k.kw, rng, -0.5f, 0.5f);
    ChannelAffine aff{test::random_vector(k.co, rng, 0.5f, 1.5f), test::random_vector(k.co, rng)};
    Shape out;
    auto y = run_conv(k, x, w, aff, transposed, out, gp);
    int oh = 0, ow = 0;
    auto ref = transposed ? ref::conv_transpose2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p, aff.scale, aff.shift,
                                                  k.in_act, k.act, 0.2, oh, ow)
                          : ref::conv2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p, aff.scale, aff.shift,
                                        k.in_act, k.act, 0.2, oh, ow);
    INFO((transposed ? "conv_transpose2d" : "conv2d") << " C" << k.c << " " << k.h << "x" << k.w << " -> Co" << k.co
                                                      << " k" << k.kh << "x" << k.kw << " s" << k.s << " p" << k.p
                                                      << " in_act " << k.in_act << " act " << k.act << " gemm "
                                                      << gp.to_string());
    REQUIRE(out.h == oh);
    REQUIRE(out.w == ow);
    // fp32 accumulation over K = C*KH*KW terms in a different order than the double reference:
    // observed error is ~1e-6 relative; 1e-4 leaves room without hiding an indexing bug (those are O(1)).
    CHECK(test::worst_ratio(y, ref, 1e-4, 1e-4) <= 1.0);
}

}  // namespace

TEST_CASE("conv2d matches the naive reference on random shapes", "[conv2d]") {
    std::mt19937 rng(42);
    const GemmParams gp = gemm_params_for(test::device().info());
    const std::vector<Case> fixed = {
        {12, 64, 128, 16, 4, 4, 2, 1, 0, 2},  // the U-Net's first layer, shrunk
        {3, 7, 9, 5, 3, 3, 1, 1, 0, 1},       // k3 s1 p1, odd sizes
        {13, 5, 3, 11, 1, 1, 1, 0, 1, 0},     // k1 s1 p0 with input ReLU
        {8, 2, 2, 9, 4, 4, 2, 1, 2, 3},       // 2x2 -> 1x1 spatial, tanh
        {5, 1, 1, 7, 3, 3, 1, 1, 0, 4},       // 1x1 input, sigmoid
        {4, 11, 6, 3, 5, 3, 3, 2, 0, 2},      // non-square kernel, stride 3
    };
    for (const auto& k : fixed) check_case(k, false, rng, gp);
    std::uniform_int_distribution<int> C(1, 40), S(1, 23), K(1, 5), ST(1, 3), A(0, 4);
    for (int i = 0; i < 12; ++i) {
        Case k{C(rng), S(rng), S(rng), C(rng), K(rng), K(rng), ST(rng), 0, A(rng) % 3, A(rng)};
        k.p = std::min(k.kh, k.kw) / 2;
        if (k.h + 2 * k.p < k.kh || k.w + 2 * k.p < k.kw) continue;
        check_case(k, false, rng, gp);
    }
}

TEST_CASE("conv_transpose2d matches the naive reference on random shapes", "[conv_transpose2d]") {
    std::mt19937 rng(7);
    const GemmParams gp = gemm_params_for(test::device().info());
    const std::vector<Case> fixed = {
        {16, 4, 8, 12, 4, 4, 2, 1, 1, 0},  // the U-Net's up-convolution: k4 s2 p1 with input ReLU
        {9, 1, 1, 5, 4, 4, 2, 1, 1, 2},    // 1x1 bottleneck -> 2x2
        {7, 3, 5, 3, 4, 4, 2, 1, 0, 3},    // odd sizes, tanh
        {5, 6, 7, 4, 3, 3, 2, 1, 0, 0},    // k3 s2 p1
        {3, 5, 4, 6, 5, 5, 3, 2, 2, 4},    // k5 s3 p2
        {6, 4, 4, 2, 3, 2, 1, 0, 0, 1},    // non-square kernel, stride 1
    };
    for (const auto& k : fixed) check_case(k, true, rng, gp);
    std::uniform_int_distribution<int> C(1, 40), S(1, 17), K(1, 5), ST(1, 3), A(0, 4);
    for (int i = 0; i < 12; ++i) {
        Case k{C(rng), S(rng), S(rng), C(rng), K(rng), K(rng), ST(rng), 0, A(rng) % 3, A(rng)};
        k.p = std::min(k.kh, k.kw) / 2;
        if ((k.h - 1) * k.s - 2 * k.p + k.kh < 1 || (k.w - 1) * k.s - 2 * k.p + k.kw < 1) continue;
        check_case(k, true, rng, gp);
    }
}

TEST_CASE("every GEMM parameter set in the tuning space gives the same convolution", "[gemm]") {
    std::mt19937 rng(3);
    const Case k{19, 9, 13, 21, 4, 4, 2, 1, 0, 2};
    // ... and gemm_local (KWG > 0, the GPU-shaped kernel) on the same packed layouts im2col_packed writes.
    for (const char* s : {"1,1,1,1,1,1", "4,4,1,1,4,4", "6,8,2,2,1,1", "8,16,2,1,1,1", "3,16,1,4,2,1", "16,4,3,1,1,2",
                          "4,4,1,1,8,8,1,16", "3,2,2,2,4,4,0,6"})
        for (bool t : {false, true}) check_case(k, t, rng, parse_gemm_params(s));
}

// Small enough for the oclgrind stage (tools/ci/oclgrind.sh): odd channel and pixel counts (C 5, 7x9) through the
// GEMM knob sets the table picks for a GPU and for a CPU, each with its fallback chain. Oclgrind presents one
// device (a GPU), so the CPU sets are chosen by describing a CPU to gemm_params_for, not by the device.
TEST_CASE("conv2d and conv_transpose2d at small odd shapes, GPU and CPU knob sets and their fallback chains",
          "[conv2d][conv_transpose2d][oclgrind]") {
    std::mt19937 rng(17);
    const std::vector<GemmParams> sets = test::gpu_and_cpu_gemm_variants();
    const Case conv[] = {{5, 7, 9, 6, 3, 3, 1, 1, 0, 2}, {5, 7, 9, 3, 4, 4, 2, 1, 2, 3}};
    const Case up[] = {{5, 7, 9, 3, 4, 4, 2, 1, 1, 0}, {5, 3, 5, 2, 3, 3, 2, 1, 0, 4}};
    for (const GemmParams& gp : sets) {
        for (const Case& k : conv) check_case(k, false, rng, gp);
        for (const Case& k : up) check_case(k, true, rng, gp);
    }
}

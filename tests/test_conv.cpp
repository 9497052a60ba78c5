// conv2d and conv_transpose2d (im2col / pack + packed GEMM + epilogue / col2im, and the implicit GEMM) against the
// naive reference: knob sets beyond the tuning table, the automatic choice of path, the implicit path's tilings and
// extremes.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded,
// random shapes among them (odd sizes, 1x1 spatial, channel and pixel counts that are not tile multiples, both paths);
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <catch2/catch.hpp>

#include "ops/conv.hpp"
#include "op_harness/op_cases.hpp"
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
                            const ChannelAffine& aff, bool transposed, Shape& out, const GemmParams& gp,
                            ConvPath path, bool* implicit) {
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
        *implicit = op.implicit();
    };
    if (transposed) {
        ConvTranspose2d op(c, gp, spec, w.data(), aff, path);
        go(op);
    } else {
        Conv2d op(c, gp, spec, w.data(), aff, path);
        go(op);
    }
    return y;
}

// The path a case takes when asked for the implicit one (the op harness's rule; the test shapes are far below any
// loop limit).
bool implicit_expected(const Case& k, bool transposed, const GemmParams& gp) {
    return harness::conv_takes_implicit(k.kh, k.kw, k.s, k.p, k.in_act, transposed, gp);
}

// Checks one case through one path; returns whether the op took the implicit path.
bool check_case(const Case& k, bool transposed, std::mt19937& rng, const GemmParams& gp,
                ConvPath path = ConvPath::automatic) {
    auto x = test::random_vector(std::size_t(k.c) * k.h * k.w, rng);
    auto w = test::random_vector(std::size_t(k.c) * k.co * k.kh * k.kw, rng, -0.5f, 0.5f);
    ChannelAffine aff{test::random_vector(k.co, rng, 0.5f, 1.5f), test::random_vector(k.co, rng)};
    Shape out;
    bool implicit = false;
    auto y = run_conv(k, x, w, aff, transposed, out, gp, path, &implicit);
    int oh = 0, ow = 0;
    auto ref = transposed ? ref::conv_transpose2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p, aff.scale, aff.shift,
                                                  k.in_act, k.act, 0.2, oh, ow)
                          : ref::conv2d(x, k.c, k.h, k.w, w, k.co, k.kh, k.kw, k.s, k.p, aff.scale, aff.shift,
                                        k.in_act, k.act, 0.2, oh, ow);
    INFO((transposed ? "conv_transpose2d" : "conv2d") << " C" << k.c << " " << k.h << "x" << k.w << " -> Co" << k.co
                                                      << " k" << k.kh << "x" << k.kw << " s" << k.s << " p" << k.p
                                                      << " in_act " << k.in_act << " act " << k.act << " gemm "
                                                      << gp.to_string() << (implicit ? " implicit" : " im2col"));
    REQUIRE(out.h == oh);
    REQUIRE(out.w == ow);
    // fp32 accumulation over K = C*KH*KW terms in a different order than the double reference: ~1e-6 relative.
    test::check_close(y, ref, test::tol::accumulation());
    if (path == ConvPath::im2col) CHECK_FALSE(implicit);
    if (path == ConvPath::implicit) CHECK(implicit == implicit_expected(k, transposed, gp));
    return implicit;
}

}  // namespace

// Outside the harness: knob sets beyond the tuning table through the convolution, left out on rusticl (tools/test.sh:
// a minute of llvmpipe compiling per program), which a harness row, run on every device, cannot be.
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
// Outside the harness: every table knob set through the convolutions under oclgrind (rows: device set).
TEST_CASE("conv2d and conv_transpose2d at small odd shapes, GPU and CPU knob sets and their fallback chains",
          "[conv2d][conv_transpose2d][oclgrind]") {
    std::mt19937 rng(17);
    // On Mesa's llvmpipe (the rusticl stage) the CPU sets are left out: each of their 6 x 32-tile programs took
    // ~30-60 s to build there (most of this case's 187 s), and the stage sets the test command's length
    // (docs/RELIABILITY.md). They run on PoCL, their own platform, and under oclgrind; the GPU sets run everywhere.
    const bool llvmpipe = test::device().info().name.rfind("llvmpipe", 0) == 0;
    DeviceInfo gpu, cpu;
    gpu.is_gpu = true;
    cpu.is_cpu = true;
    const std::vector<GemmParams> sets =
        llvmpipe ? detail::gemm_fallback_chain(gemm_params_for(gpu)) : test::gpu_and_cpu_gemm_variants();
    const Case conv[] = {{5, 7, 9, 6, 3, 3, 1, 1, 0, 2}, {5, 7, 9, 3, 4, 4, 2, 1, 2, 3}};
    const Case up[] = {{5, 7, 9, 3, 4, 4, 2, 1, 1, 0}, {5, 3, 5, 2, 3, 3, 2, 1, 0, 4}};
    for (const GemmParams& gp : sets) {
        for (const Case& k : conv) check_case(k, false, rng, gp, ConvPath::im2col);
        for (const Case& k : up) check_case(k, true, rng, gp, ConvPath::im2col);
    }
    // The implicit path with the sets it runs with: the CPU entry and the GPU entry's tiles on gemm_packed (it has
    // no local-memory form). Not every fallback: each is another program, and Mesa compiles them slowly.
    std::vector<GemmParams> implicit_sets = {gemm_params_for(gpu)};
    if (!llvmpipe) implicit_sets.push_back(gemm_params_for(cpu));
    for (GemmParams gp : implicit_sets) {
        gp.kwg = 0;
        for (const Case& k : conv) check_case(k, false, rng, gp, ConvPath::implicit);
        for (const Case& k : up) check_case(k, true, rng, gp, ConvPath::implicit);
    }
}

// The implicit GEMM's geometries (every stride that divides the kernel, polyphase splits, 1 to 9 taps, odd and
// sub-tile sizes, both paths) are op harness rows ("exact geometry, ..."). What stays here is the automatic choice
// of path: NGI_CONV (an environment knob the rows leave at its default) overrides it, so it is checked only when unset.
// Outside the harness: the automatic choice of path (ConvPath::automatic, NGI_CONV).
TEST_CASE("implicit-GEMM convolution: the automatic choice takes the implicit path where exact",
          "[conv2d][conv_transpose2d][implicit]") {
    if (std::getenv("NGI_CONV")) return;
    std::mt19937 rng(23);
    GemmParams gp = gemm_params_for(test::device().info());
    gp.kwg = 0;  // a gemm_local set (GPUs): its tiles on gemm_packed, the kernel family the implicit path uses
    // Implicit where exact, the 3-channel output layer too (tiles of 4 rows); k3 s2 transposed is not exact.
    CHECK(check_case({16, 4, 8, 12, 4, 4, 2, 1, 1, 0}, true, rng, gp));
    CHECK(check_case({6, 5, 9, 3, 4, 4, 2, 1, 1, 3}, true, rng, gp));
    CHECK_FALSE(check_case({5, 6, 7, 4, 3, 3, 2, 1, 0, 0}, true, rng, gp));
}

// Extremes through the implicit path: HDR inputs (>= 65504, the fp16 limit), a constant input, and a saturating
// output activation. The padded copy must not turn any of them into NaN, and the junk columns must stay out.
// Outside the harness: extremes (HDR and constant inputs, a saturating activation).
TEST_CASE("implicit-GEMM convolution: HDR and constant inputs stay finite and exact", "[conv2d][implicit]") {
    auto& c = test::ctx();
    GemmParams gp = gemm_params_for(test::device().info());
    gp.kwg = 0;  // as above
    const ConvSpec spec{3, 8, {4, 4, 2, 1}, {Activation::LeakyReLU, 0.2f}, {Activation::Tanh, 0.0f}};
    std::vector<float> w(3 * 8 * 16, 0.01f);
    Conv2d op(c, gp, spec, w.data(), {}, ConvPath::implicit);
    REQUIRE(op.implicit());
    const Shape in{3, 9, 11};
    for (float value : {70000.0f, -70000.0f, 1.0f}) {
        std::vector<float> x(in.size(), value);
        Buffer xb = test::upload(x);
        const Shape out = op.output_shape(in);
        Buffer yb = c.alloc(out.size() * sizeof(float), "y");
        Buffer sb = c.alloc(op.scratch_floats(in) * sizeof(float), "scratch");
        op.enqueue(c, View{xb.get(), 0, in}, View{yb.get(), 0, out}, sb.get(), 0);
        const auto y = test::download(yb, out.size(), 0);
        int oh = 0, ow = 0;
        const auto ref = ref::conv2d(x, 3, 9, 11, w, 8, 4, 4, 2, 1, std::vector<float>(8, 1.0f),
                                     std::vector<float>(8, 0.0f), 2, 3, 0.2, oh, ow);
        test::check_close(y, ref, test::tol::accumulation());  // a NaN or Inf in y fails it
    }
}

// Both tilings of gemm_conv (ops/conv_implicit.cpp): whole rows of tiles over a row-interleaved copy, and linear
// tiles over a planar one, forced through NGI_CONV_TILES at widths below, at and above a tile, so each tiling meets
// rows of one partial tile, exact multiples and a remainder (junk lanes read the neighbouring row or the slack).
// Small enough for the oclgrind stage with the GPU set (NR 4), which reports any read past the zeroed slack.
// Outside the harness: a knob (NGI_CONV_TILES) the rows leave at its default.
TEST_CASE("implicit-GEMM convolution: row and linear tilings agree with the reference",
          "[conv2d][conv_transpose2d][implicit][oclgrind]") {
    std::mt19937 rng(29);
    GemmParams gp = gemm_params_for(test::device().info());
    gp.kwg = 0;
    const int nr = gp.nr();
    const std::vector<Case> conv = {{5, 10, 2 * nr, 9, 4, 4, 2, 1, 2, 0},       // OW = nr: one exact tile a row
                                    {4, 7, 2 * nr + 6, 10, 4, 4, 2, 1, 0, 2},   // OW = nr + 3: a remainder
                                    {3, 9, 13, 9, 3, 3, 1, 1, 1, 0},            // OW = 13 < nr
                                    // conv_pad's 8-wide loops and their scalar tails: 18 / 19 source columns per
                                    // stride-2 phase, a LeakyReLU input through the vector select
                                    {2, 5, 37, 5, 4, 4, 2, 1, 2, 0}};
    const std::vector<Case> up = {{6, 5, nr, 9, 4, 4, 2, 1, 1, 0},              // each phase one tile a row
                                  {5, 3, nr + 5, 8, 4, 4, 2, 1, 1, 3},          // a remainder
                                  {4, 4, 7, 9, 2, 2, 2, 0, 0, 0},               // narrow
                                  {2, 3, 19, 5, 4, 4, 2, 1, 2, 0}};             // conv_pad's stride-1 8-wide loop
    for (const char* tiling : {"rows", "linear"}) {
        INFO("NGI_CONV_TILES=" << tiling);
        setenv("NGI_CONV_TILES", tiling, 1);
        for (const auto& k : conv) check_case(k, false, rng, gp, ConvPath::implicit);
        for (const auto& k : up) check_case(k, true, rng, gp, ConvPath::implicit);
    }
    unsetenv("NGI_CONV_TILES");
}

// PackB's values are x through one activation on the device and on the host (float(ref::activate)): tanh and
// sigmoid a few ulp apart (2^-24 = 6e-8 each), LeakyReLU 0.2f x against 0.2 x.
const test::Tol kActivationOnce = test::Tol::relative(1e-6, "one activation, a few ulp").or_absolute(1e-6);

// pack_panels (PackB): the B operand of 1 x 1 convolutions, the im2col path's transposed convolutions and dense
// layers, against the host pack with the activation applied, for every activation (the slope fast path and the
// general one), K and N that are not multiples of KU and NR, at an offset on both sides.
// Outside the harness: every activation, three knob sets (the PackB rows: the device set, ReLU, LeakyReLU).
TEST_CASE("pack_panels matches the host pack for every activation", "[conv_transpose2d][gemm][oclgrind]") {
    auto& c = test::ctx();
    std::mt19937 rng(31);
    for (const char* s : {"8,16,2,4,1,4,1", "4,4,1,1,16,16", "3,2,2,2,1,1"}) {
        const GemmParams gp = parse_gemm_params(s);
        PackB pack(c, gp);
        for (const auto& [K, N] : {std::pair{7, 45}, std::pair{1, 1}, std::pair{13, 2 * gp.nr() + 1}}) {
            const auto x = test::random_vector(std::size_t(K) * N, rng, -3.0f, 3.0f);
            for (int act = 0; act <= 4; ++act) {
                std::vector<float> activated(x.size());
                for (std::size_t i = 0; i < x.size(); ++i) activated[i] = float(ref::activate(x[i], act, 0.2));
                const auto want = pack_b(activated.data(), K, N, N, gp);
                Buffer xb = c.alloc((x.size() + 3) * sizeof(float), "x");
                c.write(xb, 3 * sizeof(float), x.size() * sizeof(float), x.data(), "x");
                Buffer bb = c.alloc((want.size() + 5) * sizeof(float), "bp");
                pack.enqueue(c, xb.get(), 3, K, N, bb.get(), 5, {Activation(act), 0.2f});
                const auto got = test::download(bb, want.size(), 5);
                INFO("knobs " << s << " K " << K << " N " << N << " act " << act);
                test::check_close(got, want, kActivationOnce);
            }
        }
    }
}

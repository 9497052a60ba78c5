// The dense layer over planar items (ops/dense.hpp: gemm_conv reading its input in place) against a naive double
// reference through every GPU and CPU knob set; guard words around each buffer stay untouched (the last tile is kept
// inside the input, nothing is written past the output).
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded:
// random widths and item counts (fewer than a tile, not a tile multiple, odd), a row stride beyond n, planar and
// item-major outputs, a residual, every activation, with the device's set;
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <catch2/catch.hpp>

#include "ops/dense.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

constexpr int kGuard = 37;          // floats before and after every buffer
constexpr float kGuardValue = -7.25f;

struct Case {
    int in, out, n, x_ld;
    bool item_major, residual;
    Act act;
};

std::vector<float> guarded(const std::vector<float>& v) {
    std::vector<float> g(v.size() + 2 * kGuard, kGuardValue);
    std::copy(v.begin(), v.end(), g.begin() + kGuard);
    return g;
}

void check_guards(const std::vector<float>& all, std::size_t n, const char* what) {
    for (int i = 0; i < kGuard; ++i) {
        INFO(what << " guard word " << i);
        CHECK(all[i] == kGuardValue);
        CHECK(all[kGuard + n + i] == kGuardValue);
    }
}

void run_case(const GemmParams& p, const Case& c, std::mt19937& rng) {
    auto& ctx = test::ctx();
    const auto w = test::random_vector(std::size_t(c.out) * c.in, rng, -0.5f, 0.5f);
    const auto x = test::random_vector(std::size_t(c.in) * c.x_ld, rng, -2.0f, 2.0f);
    const auto scale = test::random_vector(c.out, rng, 0.5f, 1.5f), shift = test::random_vector(c.out, rng);
    const std::size_t y_floats = std::size_t(c.out) * c.n;
    const auto res = test::random_vector(y_floats, rng);
    Dense dense(ctx, p, c.in, c.out, w.data());

    Buffer xb = test::upload(guarded(x)), sb = test::upload(scale), tb = test::upload(shift);
    Buffer rb = test::upload(guarded(res)), yb = test::upload(guarded(std::vector<float>(y_floats, 0.0f)));
    const std::size_t scratch = dense.scratch_floats(c.n);
    Buffer scr = ctx.alloc((scratch + 2 * kGuard) * sizeof(float), "dense scratch");
    const DenseOut out{yb.get(), kGuard, c.item_major ? 1 : c.n, c.item_major ? c.out : 1};
    dense.enqueue(ctx, xb.get(), kGuard, c.x_ld, c.n, out, sb.get(), tb.get(), c.act, c.residual ? rb.get() : nullptr,
                  kGuard, scr.get(), kGuard);

    const auto y_all = test::download(yb, y_floats + 2 * kGuard);
    check_guards(y_all, y_floats, "output");
    check_guards(test::download(xb, x.size() + 2 * kGuard), x.size(), "input");
    std::vector<double> want(y_floats);
    for (int o = 0; o < c.out; ++o)
        for (int i = 0; i < c.n; ++i) {
            double s = 0;
            for (int k = 0; k < c.in; ++k) s += double(w[std::size_t(o) * c.in + k]) * x[std::size_t(k) * c.x_ld + i];
            const std::size_t at = c.item_major ? std::size_t(i) * c.out + o : std::size_t(o) * c.n + i;
            want[at] = ref::activate(s * scale[o] + shift[o], int(c.act.kind), c.act.alpha) + (c.residual ? res[at] : 0.0);
        }
    INFO("in " << c.in << " out " << c.out << " n " << c.n << " ld " << c.x_ld << (c.item_major ? " item-major" : "")
               << (c.residual ? " residual" : "") << " act " << int(c.act.kind) << " params " << p.to_string());
    test::check_close(std::span<const float>(y_all).subspan(kGuard, y_floats), want, test::tol::short_sum());
}

}  // namespace

// Outside the harness: every table knob set (the Dense rows use the device set).
TEST_CASE("dense layer: every GPU and CPU knob set at small odd shapes", "[dense][oclgrind]") {
    std::mt19937 rng(31);
    for (const GemmParams& p : test::gpu_and_cpu_gemm_variants())
        for (const Case& c : {Case{5, 7, 3, 3, false, false, Act::relu()}, Case{9, 3, p.nr() + 5, p.nr() + 7, true,
                                                                                 false, Act::tanh()},
                              Case{6, 10, 2 * p.nr() + 1, 2 * p.nr() + 1, false, true, Act::leaky(0.2f)}})
            run_case(p, c, rng);
}

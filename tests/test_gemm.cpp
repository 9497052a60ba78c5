// The packed GEMM (kernels/gemm.cl) against a naive double-precision reference, for every knob set of the tuning
// space and the fallback chain, at random small shapes and at the shapes of the real generators (ngf 32-64: K up
// to 8192, M up to 4096); and the self-check that keeps a variant the device gets wrong from being used.
// The realistic shapes matter: on Mesa rusticl (llvmpipe) the loop form of the kernel is silently truncated
// beyond K ~ 1,000-3,000 (a 65,535-iteration loop limiter, docs/RELIABILITY.md), which shapes of a few dozen
// never showed.
#include <algorithm>
#include <cstdlib>
#include <string>
#include <catch2/catch.hpp>
#include <sstream>

#include "ops/gemm.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

// Runs C = act(scale * A B + shift) on the device, B read at an offset, C written at an offset with a row
// stride > N (the planner places tensors at arbitrary offsets inside the arena).
std::vector<float> run_gemm(const GemmParams& p, int M, int N, int K, const std::vector<float>& a,
                            const std::vector<float>& b, const std::vector<float>& scale,
                            const std::vector<float>& shift, int act) {
    auto& c = test::ctx();
    Gemm g(c, p);
    const int ldc = N + 3, c_off = 5, b_off = 11;
    auto ap = pack_a(a.data(), M, K, K, p);
    auto bp = pack_b(b.data(), K, N, N, p);
    bp.insert(bp.begin(), b_off, 0.0f);
    Buffer apb = test::upload(ap), bpb = test::upload(bp), sb = test::upload(scale), tb = test::upload(shift);
    Buffer cb = c.alloc((std::size_t(c_off) + std::size_t(M) * ldc) * sizeof(float), "C");
    c.fill_zero(cb, 0, (std::size_t(c_off) + std::size_t(M) * ldc) * sizeof(float), "C");
    g.enqueue(c, M, N, K, apb.get(), bpb.get(), b_off, cb.get(), c_off, ldc, sb.get(), tb.get(),
              {Activation(act), 0.2f});
    auto full = test::download(cb, std::size_t(M) * ldc, c_off);
    std::vector<float> out(std::size_t(M) * N);
    for (int m = 0; m < M; ++m)
        for (int n = 0; n < N; ++n) out[std::size_t(m) * N + n] = full[std::size_t(m) * ldc + n];
    return out;
}

std::vector<float> ref_gemm(int M, int N, int K, const std::vector<float>& a, const std::vector<float>& b,
                            const std::vector<float>& scale, const std::vector<float>& shift, int act) {
    std::vector<float> out(std::size_t(M) * N);
    std::vector<double> row(N);
    for (int m = 0; m < M; ++m) {
        std::fill(row.begin(), row.end(), 0.0);
        for (int k = 0; k < K; ++k) {
            const double av = a[std::size_t(m) * K + k];
            const float* br = &b[std::size_t(k) * N];
            for (int n = 0; n < N; ++n) row[n] += av * br[n];
        }
        for (int n = 0; n < N; ++n)
            out[std::size_t(m) * N + n] = float(ref::activate(row[n] * scale[m] + shift[m], act, 0.2));
    }
    return out;
}

// Largest error in tolerance units (<= 1 passes).
double gemm_error(const GemmParams& p, int M, int N, int K, int act, std::mt19937& rng) {
    // Values like the generators': weights ~ U(-1/sqrt(K), 1/sqrt(K)) keep outputs O(1) at any K.
    const float wa = 1.0f / std::sqrt(float(K));
    auto a = test::random_vector(std::size_t(M) * K, rng, -wa, wa);
    auto b = test::random_vector(std::size_t(K) * N, rng);
    auto scale = test::random_vector(M, rng, 0.5f, 1.5f), shift = test::random_vector(M, rng);
    auto y = run_gemm(p, M, N, K, a, b, scale, shift, act);
    auto r = ref_gemm(M, N, K, a, b, scale, shift, act);
    // fp32 fma accumulation of K products of size ~1/sqrt(K) against a double reference: the observed error is
    // ~1e-6 at K = 8192; 1e-4 abs + rel flags any indexing or miscompile error (those are O(0.1-1)).
    return test::worst_ratio(y, r, 1e-4, 1e-4);
}

// A variant may be wrong on a device only for a documented platform limit that the self-check catches:
// the loop form (UNROLL=0) on a driver with a loop limiter (llvmpipe). Anything else is a bug.
void expect_correct_or_known_limit(const GemmParams& p, double err, const std::string& shape) {
    const auto& info = test::device().info();
    INFO("GEMM " << shape << " knobs " << p.to_string() << " on " << info.name << " (" << info.platform_name
                 << "): error " << err << " tolerance units");
    if (err <= 1.0) return;
    const long limit = test::ctx().loop_limit();
    WARN("known platform limit: loop limiter of " << limit << " iterations");
    REQUIRE(limit > 0);
    REQUIRE(p.unroll == 0);
    const GemmVerdict v = check_gemm_variant(test::ctx(), p, gemm_check_problems());
    REQUIRE_FALSE(v.ok);  // the self-check catches it, so the library never uses it
}

// Every variant the library can select on this device (the fallback chain), the loop form, and a covering set of
// the tuning space: every knob at its extremes (MR 1..16, VW 1..16, NV 1..8, KU 1..16, work-groups 1..4 wide,
// both UNROLL forms). The tuner (perf/ngi_bench tune) runs the same self-check on each of its candidates
// before timing it, so no knob set reaches the tuning table without passing these problems on its device.
std::vector<GemmParams> test_variants() {
    const auto& info = test::device().info();
    std::vector<GemmParams> v = gemm_fallback_chain(gemm_params_for(info));
    GemmParams rolled = v.front();
    rolled.unroll = 0;
    v.push_back(rolled);
    // Small micro-kernels where a knob is at its extreme: unrolled bodies of hundreds of vector fmas take minutes
    // to compile on Mesa, and the extreme value is what a wrong index would break.
    for (const char* k : {"16,1,1,1,1,2,1", "1,2,8,1,4,1,1", "1,1,1,16,1,1,1", "3,16,1,2,2,1,1", "5,8,1,3,3,1,0",
                          "2,4,2,2,4,4,1"})
        v.push_back(parse_gemm_params(k));
    return v;
}

}  // namespace

TEST_CASE("GEMM: every knob set matches the reference on random small shapes", "[gemm][small]") {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> D(1, 70), A(0, 4);
    for (const auto& p : test_variants())
        for (int i = 0; i < 3; ++i) {
            const int M = D(rng), N = D(rng), K = D(rng);
            INFO("GEMM M" << M << " N" << N << " K" << K << " knobs " << p.to_string());
            CHECK(gemm_error(p, M, N, K, A(rng), rng) <= 1.0);
        }
}

TEST_CASE("GEMM: every knob set matches the reference at the generators' layer shapes", "[gemm][realistic]") {
    std::mt19937 rng(12);
    // (M, N, K) of the ngf 32 surround generator at 128x256 and of ngf 64 layers, cut in N so each stays fast:
    // conv k4 s2: M = Cout, K = 16 Cin; up-conv GEMM: M = 16 Cout, K = Cin.
    const int shapes[][3] = {
        {32, 1031, 192},   // first conv, 12 -> 32 (N not a tile multiple)
        {64, 517, 512},    // 32 -> 64
        {128, 130, 1024},  // 64 -> 128
        {256, 37, 4096},   // 256 -> 256, the deep layers of ngf 32
        {64, 9, 8192},     // 512 -> 512, the deep layers of ngf 64
        {4096, 3, 256},    // innermost up-conv, 256 -> 256, 1x1 input
        {1024, 65, 512},   // up-conv 512 -> 64 at ngf 64 (concat input)
        {48, 257, 64},     // outermost up-conv 64 -> 3
    };
    for (const auto& p : test_variants())
        for (const auto& s : shapes)
        {
            std::ostringstream shape;  // (not "M" + std::to_string: GCC 12 warns -Wrestrict on it, PR105329)
            shape << "M" << s[0] << " N" << s[1] << " K" << s[2];
            expect_correct_or_known_limit(p, gemm_error(p, s[0], s[1], s[2], 2, rng), shape.str());
        }
}

TEST_CASE("GEMM self-check: the device's selection passes, a rejected variant falls back down the chain",
          "[gemm][selfcheck]") {
    auto& c = test::ctx();
    const GemmSelection& sel = gemm_selection(c);
    INFO("selected " << sel.params.to_string() << " on " << c.info().name);
    CHECK(check_gemm_variant(c, sel.params, gemm_check_problems()).ok);

    // Fault injection: a checker that refuses the first two variants of the chain, as a miscompiling driver
    // would. The selection must be the third, and both refusals reported with their reasons.
    const auto chain = gemm_fallback_chain(gemm_params_for(c.info()));
    REQUIRE(chain.size() >= 3);
    int calls = 0;
    const GemmSelection fell = select_gemm(c, chain, [&](Context& ctx, const GemmParams& p) {
        ++calls;
        if (p == chain[0] || p == chain[1]) return GemmVerdict{false, 7081.0, "injected miscompile"};
        return check_gemm_variant(ctx, p, {{37, 101, 133}});
    });
    CHECK(calls == 3);
    CHECK(fell.params == chain[2]);
    REQUIRE(fell.rejected.size() == 2);
    CHECK(fell.rejected[0].second.reason == "injected miscompile");

    // Nothing passes: an error that names the device and every rejection, never a silent wrong variant.
    try {
        select_gemm(c, chain, [](Context&, const GemmParams&) { return GemmVerdict{false, 1e9, "always wrong"}; });
        FAIL("select_gemm accepted a chain of failing variants");
    } catch (const Error& e) {
        CHECK_THAT(e.what(), Catch::Contains("no GEMM variant") && Catch::Contains("always wrong") &&
                                 Catch::Contains(c.info().name));
    }

    // A work-group beyond what the kernel may run (2^20 work-items) is a performance knob, not a correctness one:
    // the launch shrinks it and the variant still computes the right result.
    GemmParams huge = chain.back();
    huge.local0 = huge.local1 = 1024;
    const GemmVerdict v = check_gemm_variant(c, huge, {{37, 101, 133}});
    CHECK(v.ok);
}

TEST_CASE("GEMM self-check: the loop form is rejected exactly where the driver limits loops", "[gemm][selfcheck]") {
    // Regression for issue 13 (the shipped model off by up to 0.25 on rusticl): the loop form of the kernel runs
    // 1 + NV + MR (1 + NV) loop iterations per k step; at K = 8192 that is far beyond llvmpipe's 65,535.
    GemmParams rolled = gemm_params_for(test::device().info());
    rolled.unroll = 0;
    const long limit = test::ctx().loop_limit();
    const GemmVerdict v = check_gemm_variant(test::ctx(), rolled, gemm_check_problems());
    INFO("loop limit " << limit << ", verdict " << v.ok << " " << v.reason);
    const long iterations = 8192L * (1 + rolled.nv + rolled.mr * (1 + rolled.nv));
    if (limit > 0 && iterations > limit) {
        CHECK_FALSE(v.ok);
        const GemmSelection& sel = gemm_selection(test::ctx());
        CHECK(sel.params.unroll == 1);
    } else {
        CHECK(v.ok);
    }
}

TEST_CASE("loop-limit probe: 0 on drivers without a limiter, the limit where there is one", "[runtime][oclgrind]") {
    const long limit = test::ctx().loop_limit();
    const auto& info = test::device().info();
    INFO(info.name << " (" << info.platform_name << "): loop limit " << limit);
    if (info.name.rfind("llvmpipe", 0) == 0) CHECK(limit == 65535);
    if (info.platform_name.find("Portable Computing Language") != std::string::npos) CHECK(limit == 0);
}

// Small enough for the oclgrind stage (tools/ci/oclgrind.sh): the GEMM at odd shapes that leave a remainder in
// every tile dimension, through the table's GPU and CPU knob sets and each one's fallback chain. Oclgrind
// presents one device (a GPU), so the CPU sets are chosen by describing a CPU to gemm_params_for.
TEST_CASE("GEMM: the GPU and CPU knob sets and their fallback chains at small odd shapes", "[gemm][oclgrind]") {
    std::mt19937 rng(19);
    const std::vector<GemmParams> sets = test::gpu_and_cpu_gemm_variants();
    REQUIRE(sets.size() >= 5);
    const int shapes[][3] = {{5, 63, 45}, {7, 9, 13}, {1, 1, 1}};
    for (const GemmParams& p : sets)
        for (const auto& s : shapes) {
            INFO("GEMM M" << s[0] << " N" << s[1] << " K" << s[2] << " knobs " << p.to_string());
            CHECK(gemm_error(p, s[0], s[1], s[2], 2, rng) <= 1.0);
        }
}

// NGI_SELFCHECK=small (simulators only) keeps just the first check problem; the default is every problem.
TEST_CASE("GEMM self-check: NGI_SELFCHECK chooses the full or the small problem set", "[gemm][selfcheck][oclgrind]") {
    const char* old = std::getenv("NGI_SELFCHECK");
    const std::string saved = old ? old : "";
    const auto& all = gemm_check_problems();
    REQUIRE(all.size() >= 3);
    ::unsetenv("NGI_SELFCHECK");
    CHECK_FALSE(gemm_selfcheck_is_small());
    CHECK(gemm_selfcheck_problems().size() == all.size());
    ::setenv("NGI_SELFCHECK", "full", 1);
    CHECK(gemm_selfcheck_problems().size() == all.size());
    ::setenv("NGI_SELFCHECK", "small", 1);
    CHECK(gemm_selfcheck_is_small());
    REQUIRE(gemm_selfcheck_problems().size() == 1);
    CHECK(gemm_selfcheck_problems()[0].k == all[0].k);
    ::setenv("NGI_SELFCHECK", "tiny", 1);
    CHECK_THROWS_WITH(gemm_selfcheck_problems(), Catch::Contains("NGI_SELFCHECK") && Catch::Contains("tiny"));
    if (old) ::setenv("NGI_SELFCHECK", saved.c_str(), 1);
    else ::unsetenv("NGI_SELFCHECK");
}

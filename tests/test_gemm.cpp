// The packed GEMM (kernels/gemm.cl) against a naive double-precision reference, for every knob set the library can
// select on the device and a covering set of the tuning space, at the shapes of the real generators (ngf 32-64: K up
// to 8192, M up to 4096); and the self-check that keeps a variant the device gets wrong from being used. The same
// knob sets at random small shapes (and gemm_local's at the edges of their blocks) are op harness rows.
// The realistic shapes matter: on Mesa rusticl (llvmpipe) the loop form of the kernel is silently truncated
// beyond K ~ 1,000-3,000 (a 65,535-iteration loop limiter, docs/RELIABILITY.md), which shapes of a few dozen
// never showed.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded;
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <algorithm>
#include <cstdlib>
#include <string>
#include <catch2/catch.hpp>
#include <sstream>

#include "op_harness/op_cases.hpp"
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

// The GEMM on data like the generators' against the float64 reference. The bound: for K <= 90, sum_of(K + 8) over
// |scale| sum|a b| + |shift| + |want| (K products and sums, the scale and the shift, and the activation's own error,
// <= 6.5 ulp of the output: OpenCL's exp 3 ulp, a division 2.5), which holds for any summation order; with this
// data (|a| <= 1/sqrt(K), |b| <= 1, scale <= 1.5, |shift| <= 1) it is at most 9e-5 + 6e-6 |want| there, under the
// accumulation bound's 1e-4 + 1e-4 |want|. Longer sums use the accumulation bound (sum_of would allow 5e-4 at K 8192).
test::Tol gemm_tol(int M, int N, int K, const std::vector<float>& a, const std::vector<float>& b,
                   const std::vector<float>& scale, const std::vector<float>& shift, const std::vector<float>& want) {
    if (K > 90) return test::tol::accumulation();
    auto absolute = [](std::vector<float> v) {
        for (float& x : v) x = std::abs(x);
        return v;
    };
    const std::vector<float> sums = ref::gemm(M, N, K, absolute(a), absolute(b), absolute(scale), absolute(shift), 0);
    std::vector<double> magnitude(sums.size());
    for (std::size_t i = 0; i < sums.size(); ++i) magnitude[i] = double(sums[i]) + std::abs(double(want[i]));
    return test::Tol::sum_of(K + 8, std::move(magnitude), "a GEMM, its epilogue and activation");
}

test::Comparison gemm_compare(const GemmParams& p, int M, int N, int K, int act, std::mt19937& rng) {
    // Values like the generators': weights ~ U(-1/sqrt(K), 1/sqrt(K)) keep outputs O(1) at any K.
    const float wa = 1.0f / std::sqrt(float(K));
    auto a = test::random_vector(std::size_t(M) * K, rng, -wa, wa);
    auto b = test::random_vector(std::size_t(K) * N, rng);
    auto scale = test::random_vector(M, rng, 0.5f, 1.5f), shift = test::random_vector(M, rng);
    auto y = run_gemm(p, M, N, K, a, b, scale, shift, act);
    auto r = ref::gemm(M, N, K, a, b, scale, shift, act);
    return test::compare(y, r, gemm_tol(M, N, K, a, b, scale, shift, r));
}

// A variant may be wrong on a device only for a documented platform limit that the self-check catches:
// the loop form (UNROLL=0) on a driver with a loop limiter (llvmpipe). Anything else is a bug.
void expect_correct_or_known_limit(const GemmParams& p, const test::Comparison& cmp, const std::string& shape) {
    const auto& info = test::device().info();
    INFO("GEMM " << shape << " knobs " << p.to_string() << " on " << info.name << " (" << info.platform_name
                 << "): " << cmp.report());
    if (cmp.ok) return;
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
    // Small micro-kernels where a knob is at its extreme (the op harness's; its rows run them at random small shapes).
    for (const GemmParams& p : harness::gemm_extreme_variants()) v.push_back(p);
    return v;
}

}  // namespace

// Outside the harness: K up to 8192, where loop limiters show (the rows' largest K is 512).
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
            expect_correct_or_known_limit(p, gemm_compare(p, s[0], s[1], s[2], 2, rng), shape.str());
        }
}

// Outside the harness: the self-check's selection and fallback (fault injection, refusal).
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

// Outside the harness: a driver's loop limit and the self-check's verdict on it.
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

// Outside the harness: a runtime probe, not an op.
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
// Outside the harness: every table knob set under oclgrind (the tiny rows hold two), M = N = K = 1.
TEST_CASE("GEMM: the GPU and CPU knob sets and their fallback chains at small odd shapes", "[gemm][oclgrind]") {
    std::mt19937 rng(19);
    const std::vector<GemmParams> sets = test::gpu_and_cpu_gemm_variants();
    REQUIRE(sets.size() >= 5);
    const int shapes[][3] = {{5, 63, 45}, {7, 9, 13}, {1, 1, 1}};
    for (const GemmParams& p : sets)
        for (const auto& s : shapes) {
            INFO("GEMM M" << s[0] << " N" << s[1] << " K" << s[2] << " knobs " << p.to_string());
            test::check_comparison(gemm_compare(p, s[0], s[1], s[2], 2, rng));
        }
}

// NGI_SELFCHECK=small (simulators only) keeps just the first check problem; the default is every problem.
// Outside the harness: an environment knob of the self-check.
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

// --- gemm_local: the GPU-shaped variant (KWG > 0): work-groups of exactly L0 x L1 work-items stage K chunks of their
// A and B panels in local memory (kernels/gemm.cl). Same packed layouts, same tolerance as gemm_packed: the sum is
// the same fma chain in the same k order, only read from local memory. Its knob sets beyond the table
// (harness::gemm_local_variants: square, tall and wide work-groups, VW 2..8, NV 1..2, KU 2, a KWG that is not a power
// of two, MR 3, both UNROLL forms) run as op harness rows at the edges of their blocks and at random shapes.

// Outside the harness: K up to 8192 through gemm_local knob sets beyond the table.
TEST_CASE("GEMM local-memory variant: the generators' layer shapes, K up to 8192", "[gemm][local][realistic]") {
    // K = 8192 is where a loop limiter shows (llvmpipe: 65,535 iterations per work-item; the UNROLL=1 kernel runs
    // ~10,000 there, kernels/gemm.cl); the UNROLL=0 set may exceed it, which the self-check must then catch.
    std::mt19937 rng(24);
    const int shapes[][3] = {{32, 1031, 192}, {256, 37, 4096}, {64, 9, 8192}, {1024, 65, 512}};
    for (const GemmParams& p : harness::gemm_local_variants())
        for (const auto& s : shapes) {
            std::ostringstream shape;
            shape << "M" << s[0] << " N" << s[1] << " K" << s[2];
            expect_correct_or_known_limit(p, gemm_compare(p, s[0], s[1], s[2], 2, rng), shape.str());
        }
}

// Outside the harness: parsing and refusals.
TEST_CASE("GEMM local-memory variant: knobs parse and print, sets the device cannot run are refused with numbers",
          "[gemm][local]") {
    const GemmParams p = parse_gemm_params("4,4,1,1,16,16,1,16");
    CHECK(p.kwg == 16);
    CHECK(p.to_string() == "4,4,1,1,16,16,1,16");
    CHECK(parse_gemm_params(p.to_string()) == p);
    CHECK(p.local_mem_bytes() == std::size_t(16 * 4 + 16 * 4) * 16 * 4);  // 8 KiB
    CHECK_THAT(p.defines(), Catch::Contains("-DKWG=16") && Catch::Contains("-DL0=16") && Catch::Contains("-DL1=16"));
    // KWG 0 (or left out) is gemm_packed, printed and built exactly as before the knob existed.
    const GemmParams q = parse_gemm_params("6,16,2,1,1,4");
    CHECK(q.kwg == 0);
    CHECK(q.local_mem_bytes() == 0);
    CHECK(q.to_string() == "6,16,2,1,1,4,1");
    CHECK(parse_gemm_params("6,16,2,1,1,4,1,0") == q);
    CHECK(q.defines() == "-DMR=6 -DVW=16 -DNV=2 -DKU=1 -DUNROLL=1");
    GemmParams r = p;
    r.kwg = 32;
    CHECK_FALSE(r == p);

    CHECK_THROWS_WITH(parse_gemm_params("4,4,1,4,8,8,1,10"), Catch::Contains("KWG 10 is not a multiple of KU 4"));
    CHECK_THROWS_AS(parse_gemm_params("4,4,1,1,8,8,1,-16"), InputError);
    CHECK_THROWS_AS(parse_gemm_params("4,4,1,1,8,8,1,16,2"), InputError);
    CHECK_THROWS_WITH(parse_gemm_params("4,4,1,1,64,32,1,16"), Catch::Contains("2048 work-items"));

    // Local memory beyond the device's: Gemm refuses it naming the numbers, and the self-check gives that as the
    // variant's reason (a variant the database or NGI_GEMM names can therefore never fail at launch).
    auto& c = test::ctx();
    const GemmParams big = parse_gemm_params("16,16,8,1,32,32,1,1024");  // (512 + 4096) x 1024 x 4 B = 18.9 MB
    const std::size_t have = c.info().local_mem_bytes;
    REQUIRE(big.local_mem_bytes() > have);
    CHECK_THROWS_WITH(Gemm(c, big), Catch::Contains("local memory") &&
                                        Catch::Contains(std::to_string(big.local_mem_bytes())) &&
                                        Catch::Contains(std::to_string(have)));
    const GemmVerdict v = check_gemm_variant(c, big, {{37, 101, 133}});
    CHECK_FALSE(v.ok);
    CHECK_THAT(v.reason, Catch::Contains("CL_DEVICE_LOCAL_MEM_SIZE"));
}

// Outside the harness: the tuning space and the fallback chain (no kernel runs).
TEST_CASE("GEMM local-memory variant: in the tuning space where it fits, the fallback chain ends on gemm_packed",
          "[gemm][local]") {
    const GemmParams pref = parse_gemm_params("4,4,1,1,16,16,0,16");
    const auto chain = gemm_fallback_chain(pref);
    REQUIRE(chain.size() >= 4);
    CHECK(chain[0] == pref);
    CHECK(chain[1] == parse_gemm_params("4,4,1,1,16,16,1,16"));
    CHECK(chain[2] == parse_gemm_params("4,4,1,1,16,16,1"));  // the same tiles without local memory or barriers
    CHECK(chain.back() == parse_gemm_params("1,1,1,1,1,1,1"));
    for (std::size_t i = 2; i < chain.size(); ++i) CHECK(chain[i].kwg == 0);

    DeviceInfo gpu;
    gpu.is_gpu = true;
    gpu.local_mem_bytes = 32768;
    gpu.max_work_group_size = 256;
    int local = 0;
    for (const GemmParams& p : gemm_tuning_space(gpu))
        if (p.kwg > 0) {
            ++local;
            CHECK(p.local_mem_bytes() <= gpu.local_mem_bytes);
            CHECK(p.local0 * p.local1 <= 256);
        }
    CHECK(local >= 8);
    // A device without local memory is never offered one, nor a CPU, whose "local" memory is ordinary memory
    // (CL_GLOBAL, as PoCL reports). The space's first entry is the database's current choice for the device type,
    // kept whatever it is so the tuner compares against it, with its loop form (the GPU entry uses local memory;
    // the self-check rejects it on such a device and falls back).
    gpu.local_mem_bytes = 0;
    const auto no_local = gemm_tuning_space(gpu);
    CHECK(no_local.front() == gemm_params_for(gpu));
    for (std::size_t i = 1; i < no_local.size(); ++i)
        if (no_local[i].kwg != 0) {  // only the current choice's own loop form (unroll 0) may keep local memory
            GemmParams q = no_local[i];
            q.unroll = no_local.front().unroll;
            CHECK(q == no_local.front());
        }
    DeviceInfo cpu;
    cpu.is_cpu = true;
    cpu.local_mem_bytes = 2 << 20;
    cpu.max_work_group_size = 4096;
    for (const GemmParams& p : gemm_tuning_space(cpu)) CHECK(p.kwg == 0);
}

// Outside the harness: a launch under a reported work-group limit below the kernel's fixed shape.
TEST_CASE("GEMM local-memory variant: a fixed-shape kernel, launched at L0 x L1 whatever limit is reported",
          "[gemm][local]") {
    // gemm_local's local arrays are sized for exactly L0 x L1 work-items (reqd_work_group_size), so Context::launch
    // must not halve its work-group as it does for gemm_packed when a driver reports a lower limit (rusticl
    // reports 32). A halved launch would fail (CL_INVALID_WORK_GROUP_SIZE) or leave slots uncopied.
    auto& c = test::ctx();
    const GemmParams p = parse_gemm_params("4,4,1,1,8,8,1,16");
    Kernel k = c.kernel("gemm", "gemm_local", gemm_kernel_defines(p));
    CHECK(k.fixed_local());
    k.limit_work_group(32);
    CHECK_FALSE(c.kernel("gemm", "gemm_packed", gemm_kernel_defines(parse_gemm_params("4,4,1,1,8,8,1"))).fixed_local());

    std::mt19937 rng(25);
    const int M = 45, N = 70, K = 37;
    auto a = test::random_vector(std::size_t(M) * K, rng, -0.2f, 0.2f);
    auto b = test::random_vector(std::size_t(K) * N, rng);
    auto scale = test::random_vector(M, rng, 0.5f, 1.5f), shift = test::random_vector(M, rng);
    Buffer ab = test::upload(pack_a(a.data(), M, K, K, p)), bb = test::upload(pack_b(b.data(), K, N, N, p));
    Buffer sb = test::upload(scale), tb = test::upload(shift), cb = c.alloc(std::size_t(M) * N * 4, "C");
    k.args(M, N, padded_k(K, p), ab, bb, 0, cb, 0, N, sb, tb, 0, 0.0f);
    const std::size_t global[2] = {std::size_t((M + 3) / 4), std::size_t((N + 3) / 4)}, wg[2] = {8, 8};
    c.launch(k, 2, global, wg);
    const std::vector<float> want = ref::gemm(M, N, K, a, b, scale, shift, 0);  // |a| <= 0.2: within sum_of's range
    test::check_close(test::download(cb, std::size_t(M) * N), want, gemm_tol(M, N, K, a, b, scale, shift, want));
}

// For the oclgrind stage (tools/ci/oclgrind.sh: --data-races --check-api --uninitialized): work-groups at the M and
// N edges (panels past the last one), a partial last K chunk and K = 1, through both UNROLL forms, KU 2 and the GPU
// starting set (16 x 16 work-items). Barrier divergence, a local-memory race between the copy and the micro-kernel,
// or a read of a local slot no work-item wrote are diagnostics there.
// Outside the harness: gemm_local's edge work-groups under oclgrind, knob sets beyond the table.
TEST_CASE("GEMM local-memory variant: edge work-groups and a partial K chunk at small shapes",
          "[gemm][local][oclgrind]") {
    std::mt19937 rng(26);
    struct Case {
        const char* knobs;
        int m, n, k;
    };
    // 2,2,2,1,4,4,1,8: blocks of 8 x 16; M 13 = 7 panels (2 groups, the last with one panel past the end), N 21 =
    // 6 panels (2 groups, two past), K 11 = a chunk of 8 and a partial one of 3. 3,2,1,2,4,2,0,4 (loops, KU 2):
    // M 14 = 5 panels in groups of 4, N 9 = 5 panels in groups of 2, Kpad 10 = chunks of 4, 4 and 2.
    const Case cases[] = {{"2,2,2,1,4,4,1,8", 13, 21, 11}, {"2,2,2,1,4,4,1,8", 1, 1, 1},
                          {"3,2,1,2,4,2,0,4", 14, 9, 9},     {"4,4,1,1,16,16,1,16", 5, 63, 45}};
    for (const Case& cs : cases) {
        const GemmParams p = parse_gemm_params(cs.knobs);
        INFO("GEMM M" << cs.m << " N" << cs.n << " K" << cs.k << " knobs " << p.to_string());
        test::check_comparison(gemm_compare(p, cs.m, cs.n, cs.k, 2, rng));
    }
}

#include "ops/gemm_selfcheck.hpp"
#include "ops/gemm_tuning.hpp"
#include "base/file_util.hpp"
#include "ngi/error.hpp"

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <random>
#include <sstream>
#include <utility>

namespace ngi::detail {
namespace {

// Bump when the problems or the tolerance change: old cached verdicts then no longer apply.
constexpr const char* kCheckVersion = "v1";

// |got - ref| / (atol + rtol |ref|) with atol = rtol = 1e-4: fp32 fma accumulation of K terms of size ~1/sqrt(K)
// against a double reference stays near 1e-6 at K = 8192 (tests/test_gemm.cpp); indexing errors, miscompiles
// and truncated loops are O(0.1-1).
constexpr double kTol = 1e-4;

GemmVerdict run_problem(Context& ctx, Gemm& gemm, const GemmProblem& pr, std::mt19937& rng) {
    const GemmParams& p = gemm.params();
    const int M = pr.m, N = pr.n, K = pr.k;
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const float wa = 1.0f / std::sqrt(float(K));
    std::vector<float> a(std::size_t(M) * K), b(std::size_t(K) * N), scale(M), shift(M);
    for (auto& x : a) x = wa * u(rng);
    for (auto& x : b) x = u(rng);
    for (auto& x : scale) x = 1.0f + 0.5f * u(rng);
    for (auto& x : shift) x = u(rng);
    const auto ap = pack_a(a.data(), M, K, K, p);
    const auto bp = pack_b(b.data(), K, N, N, p);
    auto upload = [&](const std::vector<float>& v, const char* what) {
        Buffer buf = ctx.alloc(v.size() * sizeof(float), what);
        ctx.write(buf, 0, v.size() * sizeof(float), v.data(), what);
        return buf;
    };
    Buffer apb = upload(ap, "self-check A"), bpb = upload(bp, "self-check B");
    Buffer sb = upload(scale, "self-check scale"), tb = upload(shift, "self-check shift");
    Buffer cb = ctx.alloc(std::size_t(M) * N * sizeof(float), "self-check C");
    ctx.fill_zero(cb, 0, std::size_t(M) * N * sizeof(float), "self-check C");
    gemm.enqueue(ctx, M, N, K, apb.get(), bpb.get(), 0, cb.get(), 0, N, sb.get(), tb.get(), Act::none());
    std::vector<float> c(std::size_t(M) * N);
    ctx.read(cb, 0, c.size() * sizeof(float), c.data(), "self-check C");

    GemmVerdict v{true, 0.0, ""};
    std::vector<double> row(N);
    for (int m = 0; m < M; ++m) {
        std::fill(row.begin(), row.end(), 0.0);
        for (int k = 0; k < K; ++k) {
            const double av = a[std::size_t(m) * K + k];
            const float* br = &b[std::size_t(k) * N];
            for (int n = 0; n < N; ++n) row[n] += av * br[n];
        }
        for (int n = 0; n < N; ++n) {
            const double ref = row[n] * scale[m] + shift[m], got = c[std::size_t(m) * N + n];
            const double r = std::isfinite(got) ? std::abs(got - ref) / (kTol + kTol * std::abs(ref)) : INFINITY;
            if (r > v.worst) v.worst = r;
        }
    }
    if (v.worst > 1.0) {
        v.ok = false;
        std::ostringstream s;
        s << "disagrees with the host reference at M " << M << " N " << N << " K " << K << " (worst error "
          << v.worst * kTol << " relative to 1e-4 tolerance units " << v.worst << ")";
        v.reason = s.str();
    }
    return v;
}

std::filesystem::path verdict_path(Context& ctx, const GemmParams& p) {
    // A verdict on the small set is kept apart: it must never stand in for the full check.
    const std::string set = gemm_selfcheck_is_small() ? "-small" : "";
    return cache_dir() / ("gemmcheck-" + std::string(kCheckVersion) + set + "-" + ctx.variant_key("gemm", gemm_kernel_defines(p)) +
                          "-" + std::to_string(p.local0) + "x" + std::to_string(p.local1) + ".txt");
}

}  // namespace

const std::vector<GemmProblem>& gemm_check_problems() {
    static const std::vector<GemmProblem> problems = {
        {37, 101, 133},  // no dimension a tile multiple
        {64, 37, 8192},  // the deepest K of the generators (ngf 64, 512 channels x 4 x 4)
        {1024, 9, 1024}, // an up-convolution: tall M (Cout x 16), K = Cin
    };
    return problems;
}

bool gemm_selfcheck_is_small() {
    const char* e = std::getenv("NGI_SELFCHECK");
    if (!e || !*e || std::string(e) == "full") return false;
    if (std::string(e) == "small") return true;
    throw InputError(std::string("NGI_SELFCHECK: expected 'full' or 'small', got '") + e + "'");
}

std::vector<GemmProblem> gemm_selfcheck_problems() {
    const auto& all = gemm_check_problems();
    if (gemm_selfcheck_is_small()) return {all.front()};
    return all;
}

GemmVerdict check_gemm_variant(Context& ctx, const GemmParams& p, const std::vector<GemmProblem>& problems) {
    try {
        Gemm gemm(ctx, p);
        std::mt19937 rng(20261123);
        GemmVerdict worst{true, 0.0, ""};
        for (const auto& pr : problems) {
            GemmVerdict v = run_problem(ctx, gemm, pr, rng);
            if (!v.ok) return v;
            worst.worst = std::max(worst.worst, v.worst);
        }
        return worst;
    } catch (const Error& e) {  // build or launch failure: this variant cannot run here
        return {false, INFINITY, e.what()};
    }
}

std::vector<GemmParams> gemm_fallback_chain(const GemmParams& preferred) {
    std::vector<GemmParams> chain;
    auto add = [&](GemmParams p) {
        for (const auto& q : chain) if (q == p) return;
        chain.push_back(p);
    };
    add(preferred);
    GemmParams p = preferred;
    p.unroll = 1;
    add(p);
    while (p.vw > 4) {  // narrower vectors, same NR while NV allows it
        p.vw /= 2;
        p.nv = std::min(8, p.nv * 2);
        add(p);
    }
    if (preferred.kwg > 0) {  // gemm_local refused (local memory, barriers, a driver): its tiles from global memory
        GemmParams g = preferred;
        g.unroll = 1;
        g.kwg = 0;
        add(g);
    }
    add({4, 4, 1, 1, preferred.local0, preferred.local1, 1});
    add({4, 4, 1, 1, 1, 1, 1});
    add({1, 1, 1, 1, 1, 1, 1});  // the scalar kernel: one output per work-item
    return chain;
}

std::vector<GemmParams> gemm_tuning_space(const DeviceInfo& info) {
    std::vector<GemmParams> space = {gemm_params_for(info)};
    auto add = [&](GemmParams p) {
        for (const auto& q : space) if (q == p) return;
        space.push_back(p);
    };
    if (info.is_gpu) {  // GPUs need full work-groups
        for (int mr : {2, 4, 8})
            for (int vw : {1, 4})
                for (int l : {8, 16}) add({mr, vw, 1, 1, l, l, 1});
    } else {
        for (int mr : {4, 6, 8, 12, 16})
            for (int vw : {8, 16})
                for (int nv : {1, 2})
                    for (int ku : {1, 4}) add({mr, vw, nv, ku, 1, mr <= 8 ? 4 : 1, 1});
    }
    // The GPU-shaped kernel gemm_local: (l MR) x (l NR) blocks of C per work-group, K chunks of KWG staged in local
    // memory, where that memory is the device's own (GPUs; CPUs report CL_GLOBAL: there it is ordinary memory plus
    // barriers, 9-30x slower on PoCL, docs/PERFORMANCE.md) and the set fits it and the fixed work-group shape.
    if (info.is_gpu || info.local_mem_is_dedicated)
        for (int mr : {2, 4, 8})
            for (const auto& [vw, nv] : {std::pair{2, 1}, std::pair{4, 1}, std::pair{4, 2}})
                for (int l : {8, 16})
                    for (int kwg : {16, 32}) {
                        const GemmParams p{mr, vw, nv, 1, l, l, 1, kwg};
                        if (p.local_mem_bytes() <= info.local_mem_bytes &&
                            std::size_t(l) * std::size_t(l) <= info.max_work_group_size)
                            add(p);
                    }
    for (const auto& p : gemm_fallback_chain(space.front())) add(p);
    GemmParams rolled = space.front();
    rolled.unroll = 0;  // the loop-and-pragma form, kept as a knob (and as the rusticl loop-limiter regression)
    add(rolled);
    return space;
}

GemmSelection select_gemm(Context& ctx, const std::vector<GemmParams>& chain, const GemmChecker& checker) {
    GemmSelection sel;
    for (const auto& p : chain) {
        GemmVerdict v = checker(ctx, p);
        if (v.ok) {
            sel.params = p;
            return sel;
        }
        sel.rejected.emplace_back(p, v);
    }
    std::string why;
    for (const auto& [p, v] : sel.rejected) why += "\n  " + p.to_string() + ": " + v.reason;
    throw Error("GEMM self-check on " + ctx.info().name + " (" + ctx.info().platform_name + ", driver " +
                ctx.info().driver_version + "): no GEMM variant reproduces the host reference; this OpenCL "
                "implementation computes wrong results:" + why);
}

GemmVerdict cached_check(Context& ctx, const GemmParams& p) {
    const auto path = verdict_path(ctx, p);
    std::string text;  // ngi's file rule (read_file): a FIFO or device here is a cache miss, never a blocked open
    try {
        text = read_file(path.string(), "read GEMM self-check cache", 4096);
    } catch (const InputError&) {
        text.clear();
    }
    if (!text.empty()) {
        std::istringstream in(text);
        std::string status;
        GemmVerdict v;
        if (in >> status >> v.worst && (status == "ok" || status == "fail")) {
            v.ok = status == "ok";
            in.ignore(1);
            std::getline(in, v.reason);
            return v;
        }
    }
    GemmVerdict v = check_gemm_variant(ctx, p, gemm_selfcheck_problems());
    std::ostringstream s;
    s << (v.ok ? "ok " : "fail ") << v.worst << "\n" << v.reason << "\n";
    write_cache_file(path, s.str());
    return v;
}

const GemmSelection& gemm_selection(Context& ctx) {
    return ctx.attached<GemmSelection>("gemm-selection", [&ctx] {
        GemmSelection sel = select_gemm(ctx, gemm_fallback_chain(gemm_params_for(ctx.info())), cached_check);
        for (const auto& [p, v] : sel.rejected)
            std::fprintf(stderr, "ngi: %s: GEMM variant %s rejected by the self-check: %s; using %s\n",
                         ctx.info().name.c_str(), p.to_string().c_str(), v.reason.c_str(),
                         sel.params.to_string().c_str());
        // The convolution's own knob set runs the same micro-kernel (gemm_conv shares gemm_packed's macros), so
        // the same check vets its tile shape on this device; a rejected set falls back to the GEMM's.
        sel.conv_params = conv_params_for(ctx.info(), sel.params);
        if (sel.conv_params && !(*sel.conv_params == sel.params)) {
            if (const GemmVerdict v = cached_check(ctx, *sel.conv_params); !v.ok) {
                std::fprintf(stderr, "ngi: %s: convolution knob set %s rejected by the self-check: %s; using %s\n",
                             ctx.info().name.c_str(), sel.conv_params->to_string().c_str(), v.reason.c_str(),
                             sel.params.to_string().c_str());
                sel.rejected.emplace_back(*sel.conv_params, v);
                sel.conv_params = sel.params;
            }
        }
        return sel;
    });
}

}  // namespace ngi::detail

namespace ngi {

SelfCheckReport self_check(const Device& device) {
    auto& ctx = ngi::detail::context_of(device);
    const auto& sel = detail::gemm_selection(ctx);
    SelfCheckReport r;
    r.gemm_variant = sel.params.to_string();
    for (const auto& [p, v] : sel.rejected) r.rejected.push_back(p.to_string() + ": " + v.reason);
    r.loop_limit = ctx.loop_limit();
    return r;
}

}  // namespace ngi

// Spherical harmonics (ops/sh.*) against the associated-Legendre definition and a numerical cosine-lobe integral,
// and set pooling with broadcast (ops/set_pool.*) against straight loops.
#include <cmath>

#include "ops/gemm_selfcheck.hpp"
#include "ops/mlp.hpp"
#include "ops/set_pool.hpp"
#include "ops/sh.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

TEST_CASE("SH bands 0-2: basis = the Legendre definition, irradiance = the integral of the cosine lobe", "[sh]") {
    std::mt19937 rng(21);
    auto& ctx = test::ctx();
    ShEvaluate sh(ctx);
    const int n = 301, channels = 3;
    std::vector<float> dir(3 * std::size_t(n));
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (auto& v : dir) v = g(rng) * 3.0f;  // not unit length: the kernel normalizes
    dir[0] = dir[1] = dir[2] = 0.0f;        // a zero direction: band 0 only
    const std::vector<float> coef = test::random_vector(std::size_t(n) * channels * 9, rng, -1.0f, 1.0f);
    const Buffer cb = test::upload(coef), db = test::upload(dir);
    Buffer ob = ctx.alloc(std::size_t(n) * channels * sizeof(float), "test out");
    for (int irradiance = 0; irradiance < 2; ++irradiance) {
        sh.enqueue(ctx, cb.get(), db.get(), n, channels, irradiance, ob.get());
        const std::vector<float> out = test::download(ob, std::size_t(n) * channels);
        std::vector<float> want(out.size());
        const double lobe[3] = {M_PI, 2 * M_PI / 3, M_PI / 4};
        for (int i = 0; i < n; ++i) {
            double x = dir[3 * i], y = dir[3 * i + 1], z = dir[3 * i + 2];
            const double len = std::sqrt(x * x + y * y + z * z);
            for (int c = 0; c < channels; ++c) {
                double s = 0;
                for (int l = 0; l <= 2; ++l)
                    for (int m = -l; m <= l; ++m) {
                        const double Y = len > 0 ? ref::sh_basis(l, m, x / len, y / len, z / len) : (l == 0 ? ref::sh_basis(0, 0, 0, 0, 1) : 0.0);
                        s += coef[(std::size_t(i) * channels + c) * 9 + l * (l + 1) + m] * (irradiance ? lobe[l] : 1.0) * Y;
                    }
                want[std::size_t(i) * channels + c] = float(s);
            }
        }
        CAPTURE(irradiance);
        test::require_close(out, want, test::Tol::relative(1e-5, "9 products after a normalization").or_absolute(2e-5));
    }

    // Irradiance against the integral itself: E(n) = int L(w) max(0, n.w) dw for a band-limited L (exact for
    // bands 0-2), midpoint rule on a 400 x 800 (theta, phi) grid in double.
    const float c9[9] = {0.9f, -0.3f, 0.5f, 0.2f, 0.1f, -0.25f, 0.15f, 0.05f, -0.1f};
    const float nrm[3] = {0.3f, -0.5f, 0.81f};
    const Buffer c1 = test::upload(std::vector<float>(c9, c9 + 9)), d1 = test::upload(std::vector<float>(nrm, nrm + 3));
    Buffer o1 = ctx.alloc(sizeof(float), "test out");
    sh.enqueue(ctx, c1.get(), d1.get(), 1, 1, true, o1.get());
    const float got = test::download(o1, 1)[0];
    const double nl = std::sqrt(0.3 * 0.3 + 0.25 + 0.81 * 0.81);
    const double nx = 0.3 / nl, ny = -0.5 / nl, nz = 0.81 / nl;
    double E = 0;
    const int T = 400, P = 800;
    for (int a = 0; a < T; ++a)
        for (int b = 0; b < P; ++b) {
            const double th = (a + 0.5) * M_PI / T, ph = (b + 0.5) * 2 * M_PI / P;
            const double x = std::sin(th) * std::cos(ph), y = std::sin(th) * std::sin(ph), z = std::cos(th);
            double L = 0;
            for (int l = 0; l <= 2; ++l)
                for (int m = -l; m <= l; ++m) L += c9[l * (l + 1) + m] * ref::sh_basis(l, m, x, y, z);
            E += L * std::max(0.0, nx * x + ny * y + nz * z) * std::sin(th) * (M_PI / T) * (2 * M_PI / P);
        }
    // The midpoint rule's own error on a 400 x 800 grid with the kink of max(0, n.w): ~1e-4 of E.
    test::check_value(got, E, test::Tol::relative(1e-3, "the numerical integral's error"));
}

TEST_CASE("set pooling: max and mean per set (empty sets included), broadcast back", "[pool]") {
    std::mt19937 rng(22);
    auto& ctx = test::ctx();
    SetPool pool(ctx);
    for (int channels : {1, 5, 17}) {
        std::vector<int> first = {0};
        for (int s = 0; s < 9; ++s) first.push_back(first.back() + (s == 3 ? 0 : int(rng() % 300)));
        const int sets = int(first.size()) - 1, n = first.back();
        const std::vector<float> x = test::random_vector(std::size_t(n) * channels, rng, -5.0f, 5.0f);
        const Buffer xb = test::upload(x);
        Buffer fb = ctx.alloc(first.size() * sizeof(int), "test sets");
        ctx.write(fb, 0, first.size() * sizeof(int), first.data(), "test sets");
        Buffer pb = ctx.alloc(std::size_t(sets) * channels * sizeof(float), "test pooled");
        for (PoolMode mode : {PoolMode::Max, PoolMode::Mean}) {
            pool.pool(ctx, xb.get(), channels, fb.get(), sets, mode, pb.get());
            const std::vector<float> got = test::download(pb, std::size_t(sets) * channels);
            const std::vector<double> r = ref::set_pool(x, channels, 1, channels, first, mode == PoolMode::Max);
            const std::vector<float> want(r.begin(), r.end());
            CAPTURE(channels, int(mode));
            test::require_close(got, want, test::tol::short_sum());
        }
        // Broadcast the (mean-)pooled features back after each item's own.
        std::vector<int> set_of(n);
        for (int s = 0; s < sets; ++s)
            for (int i = first[s]; i < first[s + 1]; ++i) set_of[i] = s;
        Buffer sb = ctx.alloc(std::max<std::size_t>(1, set_of.size()) * sizeof(int), "test set_of");
        ctx.write(sb, 0, set_of.size() * sizeof(int), set_of.data(), "test set_of");
        Buffer yb = ctx.alloc(std::size_t(n) * 2 * channels * sizeof(float), "test y");
        pool.broadcast_concat(ctx, xb.get(), channels, pb.get(), channels, sb.get(), n, yb.get());
        const std::vector<float> y = test::download(yb, std::size_t(n) * 2 * channels);
        const std::vector<float> pooled = test::download(pb, std::size_t(sets) * channels);
        for (int i = 0; i < n; i += 7)
            for (int c = 0; c < channels; ++c) {
                REQUIRE(y[std::size_t(i) * 2 * channels + c] == x[std::size_t(i) * channels + c]);
                REQUIRE(y[std::size_t(i) * 2 * channels + channels + c] == pooled[std::size_t(set_of[i]) * channels + c]);
            }
    }
}

TEST_CASE("MLP, SH and set-pooling kernels at small shapes (oclgrind: bounds, races, uninitialized reads)",
          "[oclgrind][mlp][sh][pool]") {
    std::mt19937 rng(23);
    auto& ctx = test::ctx();
    // Fused MLP: 3 inputs, band-major encoding with the raw input (15 wide), 7 -> 2, 5 items.
    MlpSpec s;
    s.inputs = 3;
    s.encoding = FrequencyEncoding{2, -1, true, true, FrequencyEncoding::Order::BandMajor};
    const int widths[2] = {7, 2};
    int in = s.encoding.width(3);
    for (int w : widths) {
        DenseSpec d;
        d.in = in;
        d.out = w;
        d.act = w == 2 ? Act::exp() : Act::leaky(0.1f);
        d.weight = test::random_vector(std::size_t(in) * w, rng, -0.5f, 0.5f);
        d.bias = test::random_vector(w, rng, -0.1f, 0.1f);
        s.layers.push_back(d);
        in = w;
    }
    const int n = 5;
    const Buffer xb = test::upload(test::random_vector(std::size_t(n) * 3, rng));
    Buffer yb = ctx.alloc(std::size_t(n) * 2 * sizeof(float), "test y");
    FusedMlp fused(ctx, s);
    fused.enqueue(ctx, xb.get(), 0, ItemLayout::planar(n), n, yb.get(), 0, ItemLayout::points(2));
    DenseMlp dense(ctx, gemm_selection(ctx).params, s);
    Buffer scratch = ctx.alloc(dense.scratch_floats(n) * sizeof(float), "test scratch");
    Buffer yd = ctx.alloc(std::size_t(n) * 2 * sizeof(float), "test y dense");
    dense.enqueue(ctx, View{xb.get(), 0, Shape{3, 1, n}}, View{yd.get(), 0, Shape{2, 1, n}}, scratch.get());
    const std::vector<float> a = test::download(yb, std::size_t(n) * 2), b = test::download(yd, std::size_t(n) * 2);
    for (int i = 0; i < n; ++i)
        for (int o = 0; o < 2; ++o)
            test::require_value(a[std::size_t(i) * 2 + o], b[std::size_t(o) * n + i],
                                test::Tol::relative(1e-4, "the fused and the dense path's different sums"));

    // SH on 3 items, pooling over 3 sets (one empty) of 2 channels.
    ShEvaluate sh(ctx);
    const Buffer cb = test::upload(test::random_vector(3 * 3 * 9, rng)), db = test::upload(test::random_vector(9, rng));
    Buffer ob = ctx.alloc(9 * sizeof(float), "test sh");
    sh.enqueue(ctx, cb.get(), db.get(), 3, 3, true, ob.get());
    CHECK(test::all_finite(test::download(ob, 9)));
    SetPool pool(ctx);
    const std::vector<int> first = {0, 2, 2, 5}, set_of = {0, 0, 2, 2, 2};
    Buffer fb = ctx.alloc(first.size() * sizeof(int), "test first"), sb = ctx.alloc(set_of.size() * sizeof(int), "test set_of");
    ctx.write(fb, 0, first.size() * sizeof(int), first.data(), "test first");
    ctx.write(sb, 0, set_of.size() * sizeof(int), set_of.data(), "test set_of");
    const Buffer pxb = test::upload(test::random_vector(5 * 2, rng));
    Buffer pb = ctx.alloc(3 * 2 * sizeof(float), "test pooled"), cat = ctx.alloc(5 * 4 * sizeof(float), "test cat");
    pool.pool(ctx, pxb.get(), 2, fb.get(), 3, PoolMode::Mean, pb.get());
    pool.broadcast_concat(ctx, pxb.get(), 2, pb.get(), 2, sb.get(), 5, cat.get());
    const std::vector<float> pooled = test::download(pb, 6);
    CHECK(pooled[2] == 0.0f);
    CHECK(pooled[3] == 0.0f);  // the empty set
    CHECK(test::all_finite(test::download(cat, 20)));
}

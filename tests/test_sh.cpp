// Spherical harmonics (ops/sh.*): the irradiance of a band-limited radiance against the integral of the cosine lobe.
// The op against the Legendre definition (radiance and irradiance, odd item counts, a zero direction) is the op
// harness's (ShEvaluate::enqueue rows, tests/op_harness/op_cases.cpp).
#include <algorithm>
#include <cmath>

#include "ops/sh.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

// Outside the harness: an independent oracle, the integral itself (the harness's reference uses the lobe constants
// pi, 2 pi / 3, pi / 4 that the kernel uses; this checks them).
TEST_CASE("SH irradiance = the integral of the cosine lobe over a band-limited radiance", "[sh]") {
    auto& ctx = test::ctx();
    ShEvaluate sh(ctx);
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
    // The midpoint rule's own error on this grid, with the kink of max(0, n.w): 8e-6 of E; float32 adds ~1e-7.
    test::check_value(got, E, test::Tol::relative(1e-3, "the numerical integral's error, 8e-6 here"));
}

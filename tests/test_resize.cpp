// Bilinear resize (ops/resize.hpp) against the naive double reference: edge shapes in every coordinate
// transformation mode, with sizes or with explicit scales; fixed vectors from PyTorch and from ONNX's own numpy
// reference; NaN and infinities where PyTorch puts them; HDR values; 1 x 1 inputs; and the geometries and shapes the
// op refuses.
//
// Tolerance: |got - want| <= kTolResize * max |x| (over the input's finite values; an interpolation's output lies
// within them). The source positions are exact (kernels/resize.cl); what rounds is each axis' weight lambda = r / d
// (OpenCL C allows 2.5 ulp for a float division: up to 1.5e-7 absolute), 1 - lambda, and the three lerps' products
// and sums (0.5 ulp each). A weight error e moves a lerp by e |x1 - x0| <= 2 e max |x|, so the bound is about
// 2 (2 x 1.5e-7) + 6 x 3e-8 = 8e-7 of max |x| with a 2.5-ulp division, 3e-7 with a correctly rounded one.
// Worst observed over this file's cases: 2.3e-7 on PoCL (CPU) and on Mesa rusticl (llvmpipe). Float source
// positions (s = o / scale - ... in float) would give up to 5.2e-6 at these sizes: hence the exact positions.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded;
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ops/resize.hpp"
#include "reference.hpp"
#include "guarded_op.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;
using Catch::Matchers::Contains;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
constexpr double kTolResize = 1e-6;

constexpr ResizeCoord kModes[] = {ResizeCoord::HalfPixel, ResizeCoord::PytorchHalfPixel, ResizeCoord::AlignCorners,
                                  ResizeCoord::Asymmetric};

struct Case {
    int c, h, w;
    ResizeGeometry g;
};

std::string describe(const Case& k) {
    const ResizeGeometry& g = k.g;
    std::ostringstream s;
    s.precision(9);
    s << "C" << k.c << " " << k.h << "x" << k.w << " -> " << g.out_h << "x" << g.out_w << " scales " << g.scale_h
      << " x " << g.scale_w << " " << resize_coord_name(g.mode);
    return s.str();
}

// Runs the op on x between guards (tests/guarded_op.hpp); returns y.
std::vector<float> run_resize(const Case& k, const std::vector<float>& x) {
    ResizeBilinear op(test::ctx(), k.g);
    const Shape in{k.c, k.h, k.w};
    const Shape out = op.output_shape(in);
    REQUIRE(out == Shape{k.c, k.g.out_h, k.g.out_w});
    return test::run_guarded(x, in, out, [&](Context& c, const View& xv, const View& yv) { op.enqueue(c, xv, yv); });
}

// max |x| over the finite values of x (1e-30 when none).
double finite_max(const std::vector<float>& x) {
    double m = 1e-30;
    for (float v : x)
        if (std::isfinite(v)) m = std::max(m, double(std::abs(v)));
    return m;
}

// The file's tolerance (its derivation above), NaN where the reference is NaN, the same infinity where it is
// infinite; scaled by max |x| with .of().
const test::Tol kResize = test::Tol::scaled(kTolResize, "the weights' rounding, derived above").nan_where_want_nan();

// The op against ref::resize_bilinear on x; returns y.
std::vector<float> check_case(const Case& k, const std::vector<float>& x) {
    INFO(describe(k));
    const std::vector<float> y = run_resize(k, x);
    const ResizeGeometry& g = k.g;
    const std::vector<double> want =
        ref::resize_bilinear(x, k.c, k.h, k.w, g.out_h, g.out_w, g.scale_h, g.scale_w, int(g.mode));
    test::check_close(y, want, kResize.of(finite_max(x)));
    return y;
}

std::vector<float> check_random(const Case& k, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
    return check_case(k, test::random_vector(std::size_t(k.c) * k.h * k.w, rng, lo, hi));
}

// x[i] = ((i * 7919) mod 23) / 8 - 1.375: exact floats, the input of the fixed vectors below (tools: PyTorch
// 1.13's F.interpolate and ONNX 1.12's numpy reference, onnx.backend.test.case.node.resize.interpolate_nd).
std::vector<float> fixed_input(int n) {
    std::vector<float> x(std::size_t(n), 0.0f);
    for (int i = 0; i < n; ++i) x[std::size_t(i)] = float((i * 7919) % 23) / 8.0f - 1.375f;
    return x;
}

void check_fixed(const Case& k, const std::vector<float>& want) {
    INFO(describe(k) << " against the fixed vector");
    const std::vector<float> x = fixed_input(k.c * k.h * k.w);
    const std::vector<float> y = run_resize(k, x);
    test::check_close(y, want, kResize.of(finite_max(x)));
    check_case(k, x);
}

}  // namespace

// Outside the harness: edge shapes in every mode (1x1, an unchanged axis, a copy, a row to a column, the largest
// factors). Up and down by odd, non-integer factors in each mode are the harness's ResizeBilinear rows.
TEST_CASE("resize_bilinear at edge shapes in every mode: one value, an unchanged axis, a row to a column",
          "[resize]") {
    std::mt19937 rng(107);
    for (ResizeCoord mode : kModes) {
        INFO(resize_coord_name(mode));
        const std::vector<Case> edges = {
            {1, 1, 1, {1, 1, 0, 0, mode}},      // one value to one value
            {6, 13, 11, {13, 29, 0, 0, mode}},  // H unchanged, W up
            {6, 13, 11, {5, 11, 0, 0, mode}},   // W unchanged, H down
            {20, 37, 37, {37, 37, 0, 0, mode}}, // unchanged: a copy
            {7, 1, 37, {37, 1, 0, 0, mode}},    // one row to one column
            {9, 37, 1, {1, 37, 0, 0, mode}},    // and back
            {2, 2, 2, {37, 36, 0, 0, mode}},    // the largest factors up
            {2, 37, 36, {2, 1, 0, 0, mode}},    // and down
        };
        for (const Case& k : edges) check_random(k, rng);
    }
}

// Outside the harness: explicit scales (ONNX 'scales') in every mode at their edges; one row holds pytorch's.
TEST_CASE("resize_bilinear with explicit scales, as ONNX Resize given 'scales'", "[resize]") {
    std::mt19937 rng(109);
    for (ResizeCoord mode : kModes) {
        INFO(resize_coord_name(mode));
        // Coordinates with the float scale as it is: scales that are not out / in with a size that is unchanged (the
        // scale still moves the positions), scale 1 with an unchanged size (a copy), non-dyadic floats.
        check_random({3, 9, 9, {9, 9, 1.1f, 0.9f, mode}}, rng);
        check_random({3, 9, 9, {9, 9, 1.0f, 1.0f, mode}}, rng);
        check_random({2, 5, 4, {3, 6, 0.6f, 1.7f, mode}}, rng);
        check_random({2, 4, 5, {6, 3, 1.7f, 0.6f, mode}}, rng);
        check_random({2, 3, 7, {10, 3, 3.3333333f, 0.42857143f, mode}}, rng);
    }
    // Scale 1 on an unchanged axis copies it exactly (weights 1 and 0 on one pixel).
    const std::vector<float> x = test::random_vector(3 * 6 * 5, rng, -2.0f, 2.0f);
    for (ResizeCoord mode : kModes) {
        test::check_close(run_resize({3, 6, 5, {6, 5, 1.0f, 1.0f, mode}}, x), x, test::Tol::exact());
        test::check_close(run_resize({3, 6, 5, {6, 5, 0.0f, 0.0f, mode}}, x), x, test::Tol::exact());
    }
}

// Outside the harness: external oracles (PyTorch's F.interpolate, ONNX's numpy reference).
TEST_CASE("resize_bilinear agrees with PyTorch's F.interpolate and ONNX's numpy reference", "[resize]") {
    // PyTorch 1.13, F.interpolate(x, size=(OH, OW), mode='bilinear', align_corners=False: half_pixel / True).
    check_fixed({2, 5, 7, {7, 3, 0, 0, ResizeCoord::HalfPixel}},
                {-0.791666687f, 1.24999988f,  0.416666508f, -0.577380955f, -0.178571403f, 0.630952239f,
                 -0.309523821f, -1.14285684f, 0.625f,       -0.0416666791f, -0.874999762f, 0.20833376f,
                 0.226190463f,  -0.607142866f, 0.476190895f, 0.494047612f,  -0.339285791f, -0.0773809403f,
                 0.708333313f,  -0.125000104f, -0.958333492f, 1.08333325f,  0.249999896f,  -0.583333492f,
                 0.20238094f,   0.464285612f,  -0.369047791f, -0.351190388f, 0.732142746f,  -0.101190634f,
                 -0.0833332911f, 0.999999881f, 0.166666523f,  -0.50000006f,  1.26785719f,   0.434523672f,
                 -0.505952358f, 0.303571284f,  0.291666687f,  -0.291666687f, -1.12499976f,  -0.0416662842f});
    check_fixed({1, 3, 4, {5, 9, 0, 0, ResizeCoord::AlignCorners}},
                {-1.375f,   -1.046875f, -0.71875f, -0.390625f,  -0.0625f,    0.265625f,   0.59375f,   0.921875f,
                 1.25f,     -1.0625f,   -0.734375f, -0.40625f,  -0.078125f,  0.25f,       0.578125f,  0.546875f,
                 0.3359375f, 0.125f,    -0.75f,    -0.421875f,  -0.09375f,   0.234375f,   0.5625f,    0.890625f,
                 0.5f,      -0.25f,     -1.0f,     -0.4375f,    -0.109375f,  0.21875f,    0.3671875f, 0.15625f,
                 -0.0546875f, -0.265625f, -0.4765625f, -0.6875f, -0.125f,    0.203125f,   0.53125f,   0.5f,
                 -0.25f,    -1.0f,      -1.03125f, -0.703125f,  -0.375f});
    check_fixed({1, 4, 4, {2, 6, 0, 0, ResizeCoord::HalfPixel}},
                {-1.0625f, -0.625f, -0.0416666195f, 0.541666687f, 0.40624994f, 0.125f, 0.1875f, 0.625f,
                 0.729166508f, -0.604166746f, -0.499999881f, -0.0625f});
    check_fixed({1, 7, 5, {3, 7, 0, 0, ResizeCoord::AlignCorners}},
                {-1.375f, -0.791666627f, -0.208333299f, 0.37500006f, 0.958333373f, 0.583333135f, -0.75f,
                 0.25f, 0.833333373f, 0.458333254f, -0.87499994f, -0.291666597f, 0.291666746f, 0.875f,
                 -1.0f, -0.416666657f, 0.166666701f, 0.749999881f, -0.583333492f, -0.958333254f, -0.375f});
    // ONNX 1.12's numpy reference (interpolate_nd with linear_coeffs), given sizes or float32 scales.
    check_fixed({1, 5, 7, {8, 4, 0, 0, ResizeCoord::Asymmetric}},
                {-1.375f, 0.15625f, 0.25f, 0.34375f, -1.140625f, 0.390625f, -0.4140625f, 0.578125f, -0.90625f,
                 0.625f, -0.71875f, 0.6328125f, -0.671875f, 0.859375f, -0.484375f, 0.41796875f, -0.4375f,
                 0.015625f, -0.25f, 0.5625f, -0.203125f, -0.828125f, -0.015625f, 0.52734375f, 0.03125f,
                 -0.59375f, 0.21875f, -0.5859375f, 0.125f, -0.5f, 0.3125f, -1.03125f});
    check_fixed({1, 6, 5, {1, 9, 0, 0, ResizeCoord::PytorchHalfPixel}},
                {-1.375f, -1.08333333f, -0.597222222f, -0.111111111f, 0.375f, 0.861111111f, 1.02777778f,
                 -0.0833333333f, -0.75f});
    check_fixed({1, 4, 8, {6, 6, 1.5f, 0.75f, ResizeCoord::HalfPixel}},
                {-1.22916667f, -0.0625f, 1.10416667f, -0.604166667f, 0.5625f, -0.666666667f, -0.604166667f,
                 -0.15625f, 0.291666667f, 0.0208333333f, 0.46875f, -0.28125f, 0.149305556f, -0.28125f, -0.3125f,
                 0.375f, 0.34375f, -0.0868055556f, 0.663194444f, -0.40625f, 0.520833333f, -0.708333333f,
                 0.21875f, -0.850694444f, 0.21875f, 0.1875f, 0.15625f, -0.354166667f, 0.09375f, -0.65625f,
                 -0.354166667f, 0.8125f, -0.416666667f, 0.270833333f, 0.0f, -0.270833333f});
    check_fixed({1, 5, 4, {3, 6, 0.6f, 1.7f, ResizeCoord::Asymmetric}},
                {-1.375f, -0.860294132f, -0.345588264f, 0.169117604f, 0.683823472f, 1.19852934f, -0.333333375f,
                 0.181372493f, 0.357843164f, -0.254901805f, -0.529411677f, -0.578431396f, 0.708333251f,
                 0.659313868f, 0.441176736f, -0.171568569f, -0.107843278f, 0.40686259f});
    check_fixed({1, 4, 5, {6, 3, 1.7f, 0.6f, ResizeCoord::HalfPixel}},
                {-1.08333336f, 0.374999913f, -0.0833330022f, -0.509803988f, -0.150735238f, 0.123774646f,
                 0.372548929f, -0.959558577f, 0.442401808f, -0.351715636f, -0.161764753f, 0.225490341f,
                 -0.737745238f, 0.297794175f, 0.12132375f, 0.144607678f, -0.511029164f, 0.439950912f});
}

// Outside the harness: extremes (NaN and Inf where PyTorch puts them).
TEST_CASE("resize_bilinear propagates NaN from every tap it multiplies, as PyTorch", "[resize][extremes]") {
    // PyTorch 1.13's F.interpolate on these planes (NaN and Inf outputs exactly where it puts them): every one of
    // the 2 x 2 taps is multiplied, weight 0 included, so 0 * NaN = NaN and 0 * Inf = NaN; an unchanged axis reads
    // one row; past the last pixel the tap is the last pixel twice.
    auto same = [](const std::vector<float>& got, const std::vector<float>& want) {
        test::check_close(got, want, kResize.of(9.0));  // the inputs' largest |x| is at most 9
    };
    const std::vector<float> center = {1, 2, 3, 4, kNaN, 6, 7, 8, 9};
    same(run_resize({1, 3, 3, {3, 4, 0, 0, ResizeCoord::AlignCorners}}, center),
         {1.0f, 1.6666667f, 2.3333335f, 3.0f, kNaN, kNaN, kNaN, 6.0f, 7.0f, 7.6666665f, 8.333333f, 9.0f});
    check_case({1, 3, 3, {3, 4, 0, 0, ResizeCoord::AlignCorners}}, center);
    const std::vector<float> corner = {1, 2, kNaN, 4};
    same(run_resize({1, 2, 2, {2, 3, 0, 0, ResizeCoord::AlignCorners}}, corner), {1.0f, 1.5f, 2.0f, kNaN, kNaN, 4.0f});
    same(run_resize({1, 1, 3, {1, 5, 0, 0, ResizeCoord::AlignCorners}}, {1, 2, kNaN}), {1.0f, 1.5f, kNaN, kNaN, kNaN});
    same(run_resize({1, 1, 3, {1, 6, 0, 0, ResizeCoord::HalfPixel}}, {1, 2, kNaN}),
         {1.0f, 1.25f, 1.75f, kNaN, kNaN, kNaN});
    same(run_resize({1, 1, 3, {1, 3, 0, 0, ResizeCoord::HalfPixel}}, {1, kNaN, 3}), {1.0f, kNaN, 3.0f});
    same(run_resize({1, 1, 2, {1, 4, 0, 0, ResizeCoord::HalfPixel}}, {1, kNaN}), {kNaN, kNaN, kNaN, kNaN});
    // Infinities: [1, Inf] and [Inf, 1] to 2 x 4 (one row up to two), [Inf] to 1 x 4, [1, 2, 3, Inf] unchanged.
    same(run_resize({1, 1, 2, {2, 4, 0, 0, ResizeCoord::HalfPixel}}, {1, kInf}),
         {kNaN, kNaN, kNaN, kNaN, kNaN, kInf, kInf, kInf});
    same(run_resize({1, 1, 2, {2, 4, 0, 0, ResizeCoord::HalfPixel}}, {kInf, 1}),
         {kNaN, kNaN, kNaN, 1.0f, kInf, kInf, kInf, 1.0f});
    same(run_resize({1, 1, 1, {1, 4, 0, 0, ResizeCoord::HalfPixel}}, {kInf}), {kNaN, kNaN, kNaN, kNaN});
    same(run_resize({1, 1, 4, {1, 4, 0, 0, ResizeCoord::HalfPixel}}, {1, 2, 3, kInf}), {1.0f, 2.0f, 3.0f, kNaN});
    for (const std::vector<float>& v : {std::vector<float>{1, kInf}, std::vector<float>{kInf, 1}})
        check_case({1, 1, 2, {2, 4, 0, 0, ResizeCoord::HalfPixel}}, v);

    // NaNs scattered over random planes, every mode, up and down: exactly the outputs the reference makes NaN are
    // NaN, the others within the tolerance.
    std::mt19937 rng(113);
    for (ResizeCoord mode : kModes)
        for (const Case& r : {Case{3, 11, 13, {17, 7, 0, 0, mode}}, Case{5, 8, 9, {8, 20, 0, 0, mode}},
                              Case{2, 17, 5, {6, 5, 0, 0, mode}}, Case{2, 6, 6, {12, 12, 0, 0, mode}}}) {
            std::vector<float> v = test::random_vector(std::size_t(r.c) * r.h * r.w, rng, -3.0f, 3.0f);
            std::uniform_int_distribution<std::size_t> at(0, v.size() - 1);
            for (int n = 0; n < 3; ++n) v[at(rng)] = kNaN;
            v[0] = kNaN;             // the first cell (under the clamped border)
            v[v.size() - 1] = kNaN;  // the last
            const std::vector<float> out = check_case(r, v);
            CHECK(std::any_of(out.begin(), out.end(), [](float f) { return std::isnan(f); }));
            CHECK(std::any_of(out.begin(), out.end(), [](float f) { return !std::isnan(f); }));
        }
}

// Outside the harness: extremes (infinities, HDR values).
TEST_CASE("resize_bilinear with infinities and HDR values", "[resize][extremes]") {
    std::mt19937 rng(127);
    const float values[] = {kInf, -kInf, 65504.0f, std::nextafter(65504.0f, kInf), -65504.0f, 70000.0f, 1.0e7f,
                            1.0e30f, -1.0e30f, 0.0f, 1.0f, -1.0f};
    std::uniform_int_distribution<int> pick(0, int(std::size(values)) - 1);
    for (ResizeCoord mode : kModes)
        for (const Case& k : {Case{4, 9, 11, {13, 5, 0, 0, mode}}, Case{3, 6, 7, {6, 14, 0, 0, mode}},
                              Case{2, 13, 3, {4, 7, 1.5f, 2.5f, mode}}}) {
            std::vector<float> x(std::size_t(k.c) * k.h * k.w);
            for (float& v : x) v = values[pick(rng)];
            check_case(k, x);
        }
    // 65504 (the fp16 limit) everywhere stays 65504 within the tolerance; a plane of +Inf is +Inf only where no
    // weight is 0 (0 * Inf = NaN elsewhere), as the reference says.
    for (ResizeCoord mode : kModes) {
        const std::vector<float> y = check_case({2, 5, 7, {9, 4, 0, 0, mode}}, std::vector<float>(70, 65504.0f));
        test::check_close(y, std::vector<float>(y.size(), 65504.0f), kResize.of(65504.0));
        check_case({2, 5, 7, {9, 4, 0, 0, mode}}, std::vector<float>(70, kInf));
        // HDR planes with smooth content: radiance up to 1e4 next to 1e-3.
        check_random({3, 11, 9, {7, 17, 0, 0, mode}}, rng, 1.0e-3f, 1.0e4f);
    }
}

// Outside the harness: an edge shape (1x1).
TEST_CASE("resize_bilinear on a 1x1 spatial input gives the value everywhere", "[resize]") {
    std::mt19937 rng(131);
    const std::vector<float> x = test::random_vector(7, rng, -2.0f, 2.0f);
    for (ResizeCoord mode : kModes)
        for (const ResizeGeometry& g : {ResizeGeometry{1, 1, 0, 0, mode}, ResizeGeometry{4, 4, 0, 0, mode},
                                        ResizeGeometry{3, 17, 0, 0, mode}, ResizeGeometry{5, 2, 2.5f, 0.3f, mode}}) {
            const Case k{7, 1, 1, g};
            INFO(describe(k));
            const std::vector<float> y = check_case(k, x);
            std::vector<float> everywhere;
            for (int c = 0; c < 7; ++c) everywhere.insert(everywhere.end(), std::size_t(g.out_h) * g.out_w, x[c]);
            test::check_close(y, everywhere, kResize.of(2.0));  // |x| < 2
        }
}

// Outside the harness: refusals.
TEST_CASE("resize_bilinear refuses bad geometry and shapes with errors naming the op", "[resize]") {
    auto& c = test::ctx();
    SECTION("a zero or negative output size") {
        CHECK_THROWS_WITH(ResizeBilinear(c, {0, 4, 0, 0, ResizeCoord::HalfPixel}),
                          Contains("resize_bilinear") && Contains("output 0x4") && Contains(">= 1"));
        CHECK_THROWS_WITH(ResizeBilinear(c, {3, -2, 0, 0, ResizeCoord::AlignCorners}),
                          Contains("resize_bilinear") && Contains("output 3x-2"));
        CHECK_THROWS_AS(ResizeBilinear(c, {0, 0, 0, 0, ResizeCoord::Asymmetric}), InputError);
    }
    SECTION("a negative, NaN or infinite scale") {
        CHECK_THROWS_WITH(ResizeBilinear(c, {4, 4, -2.0f, 0, ResizeCoord::HalfPixel}),
                          Contains("resize_bilinear") && Contains("scales -2 x 0") && Contains("height scale"));
        CHECK_THROWS_WITH(ResizeBilinear(c, {4, 4, 1.0f, kNaN, ResizeCoord::Asymmetric}),
                          Contains("resize_bilinear") && Contains("nan") && Contains("width scale"));
        CHECK_THROWS_WITH(ResizeBilinear(c, {4, 4, kInf, 1.0f, ResizeCoord::HalfPixel}),
                          Contains("resize_bilinear") && Contains("inf") && Contains("height scale"));
        CHECK_THROWS_AS(ResizeBilinear(c, {4, 4, 1.0f, -kInf, ResizeCoord::PytorchHalfPixel}), InputError);
        CHECK_THROWS_AS(ResizeBilinear(c, {4, 4, -0.5f, 1.0f, ResizeCoord::AlignCorners}), InputError);
    }
    SECTION("an unknown mode") {
        CHECK_THROWS_WITH(ResizeBilinear(c, {4, 4, 0, 0, ResizeCoord(9)}),
                          Contains("resize_bilinear") && Contains("unknown coordinate transformation mode 9"));
    }
    SECTION("a scale too far from output / input for the kernel's integers") {
        ResizeBilinear tiny(c, {5, 4, 1e-30f, 0, ResizeCoord::HalfPixel});
        CHECK_THROWS_WITH(tiny.output_shape({1, 3, 3}), Contains("resize_bilinear") && Contains("height scale 1e-30") &&
                                                            Contains("input height 3") && Contains("output height 5"));
        ResizeBilinear small(c, {4000, 4, std::ldexp(1.0f, -50), 0, ResizeCoord::Asymmetric});
        CHECK_THROWS_WITH(small.output_shape({1, 3, 3}), Contains("resize_bilinear") && Contains("64-bit"));
        // align_corners does not use the scale.
        CHECK(ResizeBilinear(c, {5, 4, 1e-30f, 0, ResizeCoord::AlignCorners}).output_shape({1, 3, 3}) == Shape{1, 5, 4});
    }
    SECTION("an empty input, an output view of the wrong shape, a null buffer") {
        ResizeBilinear op(c, {6, 8, 0, 0, ResizeCoord::HalfPixel});
        CHECK_THROWS_WITH(op.output_shape({0, 4, 4}), Contains("resize_bilinear") && Contains("empty input"));
        CHECK_THROWS_AS(op.output_shape({3, 4, 0}), InputError);
        CHECK_THROWS_WITH(ResizeBilinear(c, {1 << 16, 1 << 15, 0, 0, ResizeCoord::HalfPixel}).output_shape({1, 2, 2}),
                          Contains("resize_bilinear") && Contains("2^31"));
        Buffer xb = test::upload(std::vector<float>(3 * 4 * 4, 1.0f));
        Buffer yb = test::upload(std::vector<float>(3 * 6 * 8, 0.0f));
        CHECK_THROWS_WITH(op.enqueue(c, View{xb.get(), 0, {3, 4, 4}}, View{yb.get(), 0, {3, 8, 6}}),
                          Contains("resize_bilinear") && Contains("resizes to 3x6x8"));
        CHECK_THROWS_WITH(op.enqueue(c, View{xb.get(), 0, {3, 4, 4}}, View{nullptr, 0, {3, 6, 8}}),
                          Contains("resize_bilinear") && Contains("output buffer is null"));
    }
}

// Small enough for the oclgrind stage (tools/ci/oclgrind.sh): odd sizes up and down in every mode, an explicit
// scale, NaN and +-Inf among the values, outputs between sentinels at offsets.
// Outside the harness: NaN and infinities among the inputs under oclgrind (the rows draw finite ones).
TEST_CASE("resize_bilinear at small odd shapes with NaN and infinities", "[resize][oclgrind]") {
    std::mt19937 rng(137);
    for (ResizeCoord mode : kModes)
        for (const Case& k : {Case{3, 5, 3, {7, 2, 0, 0, mode}}, Case{2, 3, 7, {2, 5, 1.7f, 0.6f, mode}},
                              Case{1, 1, 1, {3, 2, 0, 0, mode}}}) {
            std::vector<float> x = test::random_vector(std::size_t(k.c) * k.h * k.w, rng, -4.0f, 4.0f);
            if (x.size() > 4) {
                x[1] = kNaN;
                x[2] = kInf;
                x[x.size() - 2] = -kInf;
            }
            check_case(k, x);
        }
}

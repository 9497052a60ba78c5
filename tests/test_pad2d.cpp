// 2D padding (ops/pad2d.hpp) against the naive reference, exactly (every output is an input or the constant): edge
// shapes in each mode, negative pads, PyTorch's F.pad on a fixed plane, NaN, infinities and HDR values copied bit for
// bit, 1 x 1 inputs, and the geometries and shapes the op refuses.
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

#include "ops/pad2d.hpp"
#include "reference.hpp"
#include "guarded_op.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;
using Catch::Matchers::Contains;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

struct Case {
    int c, h, w;
    PadGeometry g;
};

std::string describe(const Case& k) {
    const PadGeometry& g = k.g;
    std::ostringstream s;
    s << "C" << k.c << " " << k.h << "x" << k.w << " pads t" << g.top << " l" << g.left << " b" << g.bottom << " r"
      << g.right << " " << pad_mode_name(g.mode) << " " << g.value;
    return s.str();
}

// Runs the op on x between guards (tests/guarded_op.hpp); returns y.
std::vector<float> run_pad(const Case& k, const std::vector<float>& x, Shape& out) {
    Pad2d op(test::ctx(), k.g);
    const Shape in{k.c, k.h, k.w};
    out = op.output_shape(in);
    return test::run_guarded(x, in, out, [&](Context& c, const View& xv, const View& yv) { op.enqueue(c, xv, yv); });
}

// The op against ref::pad2d on x; returns y.
std::vector<float> check_case(const Case& k, const std::vector<float>& x) {
    INFO(describe(k));
    Shape out;
    const std::vector<float> y = run_pad(k, x, out);
    const PadGeometry& g = k.g;
    REQUIRE(out == Shape{k.c, k.h + g.top + g.bottom, k.w + g.left + g.right});
    // A copy keeps every bit: NaN payloads, the sign of zero.
    test::check_close(y, ref::pad2d(x, k.c, k.h, k.w, g.top, g.left, g.bottom, g.right, int(g.mode), g.value),
                      test::Tol::bits());
    return y;
}

std::vector<float> check_random(const Case& k, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
    return check_case(k, test::random_vector(std::size_t(k.c) * k.h * k.w, rng, lo, hi));
}

// Random pads 0..max_pad each (reflect: also below the axis' size), mode as given, a random constant.
PadGeometry random_geometry(std::mt19937& rng, PadMode mode, int h, int w, int max_pad) {
    auto pad = [&rng, mode, max_pad](int n) {
        const int hi = mode == PadMode::Reflect ? std::min(max_pad, n - 1) : max_pad;
        return std::uniform_int_distribution<int>(0, hi)(rng);
    };
    PadGeometry g;
    g.top = pad(h);
    g.left = pad(w);
    g.bottom = pad(h);
    g.right = pad(w);
    g.mode = mode;
    g.value = std::uniform_real_distribution<float>(-3.0f, 3.0f)(rng);
    return g;
}

const PadMode kModes[] = {PadMode::Constant, PadMode::Reflect, PadMode::Edge};

}  // namespace

// Outside the harness: edge shapes in every mode (one value, a row, a column, no padding, pads far beyond the input).
// Odd sizes with asymmetric pads, one-sided and the largest reflect pads are the harness's Pad2d rows.
TEST_CASE("pad2d at edge shapes in every mode: one value, a row, a column, no padding, pads beyond the input",
          "[pad2d]") {
    std::mt19937 rng(89);
    for (PadMode mode : kModes) {
        std::vector<Case> edges = {
            {1, 1, 1, {0, 0, 0, 0, mode, 0.0f}},     // identity on one value
            {4, 6, 10, {5, 9, 5, 9, mode, 0.0f}},    // the largest reflect pads: size - 1 on every side
            {17, 1, 37, {0, 36, 0, 36, mode, 7.0f}}, // one row (reflect: no padding across H possible)
            {9, 29, 1, {28, 0, 28, 0, mode, 0.5f}},  // one column
            {20, 37, 37, {0, 0, 0, 0, mode, 0.0f}},  // no padding at all: a copy
        };
        if (mode != PadMode::Reflect) edges.push_back({3, 5, 4, {40, 37, 50, 33, mode, 1.5f}});  // pads >> the input
        for (const Case& k : edges) check_random(k, rng);
    }
}

// Outside the harness: negative pads (crops), which no row takes.
TEST_CASE("pad2d with negative pads crops, alone and beside padding, in every mode", "[pad2d]") {
    // ONNX Pad allows negative pads (a crop); ConvTranspose's output_padding is mapped to a top-left crop.
    std::mt19937 rng(90);
    for (PadMode mode : kModes) {
        check_random({3, 9, 7, {-1, -1, 0, 0, mode, 0.0f}}, rng);      // output_padding 1's crop
        check_random({2, 11, 13, {-3, 2, 4, -5, mode, 1.5f}}, rng);    // crop and pad on each axis
        check_random({5, 6, 6, {-2, -2, -3, -3, mode, 0.0f}}, rng);    // a 1 x 1 window
        std::uniform_int_distribution<int> C(1, 8), S(2, 29);
        for (int n = 0; n < 10; ++n) {
            const int h = S(rng), w = S(rng);
            PadGeometry g = random_geometry(rng, mode, h, w, 6);
            g.top -= std::uniform_int_distribution<int>(0, h - 1)(rng);   // may go negative, never the whole axis
            g.left -= std::uniform_int_distribution<int>(0, w - 1)(rng);
            if (h + g.top + g.bottom < 1 || w + g.left + g.right < 1) continue;
            check_random({C(rng), h, w, g}, rng);
        }
    }
}

// Outside the harness: an external oracle (PyTorch's F.pad output).
TEST_CASE("pad2d agrees with PyTorch's F.pad on a fixed plane", "[pad2d]") {
    // F.pad(torch.arange(12.).reshape(1, 1, 3, 4), (3, 2, 2, 1), mode=m): pads left 3, right 2, top 2, bottom 1,
    // computed with PyTorch 1.13 (constant value 0; 'replicate' is ONNX's edge).
    const std::vector<float> x = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    const std::vector<float> reflect = {
        11, 10, 9, 8, 9, 10, 11, 10, 9,  7, 6, 5, 4, 5, 6, 7, 6, 5,  3, 2, 1, 0, 1, 2, 3, 2, 1,
        7,  6,  5, 4, 5, 6,  7,  6,  5,  11, 10, 9, 8, 9, 10, 11, 10, 9, 7, 6, 5, 4, 5, 6, 7, 6, 5};
    const std::vector<float> edge = {
        0, 0, 0, 0, 1, 2, 3, 3, 3,  0, 0, 0, 0, 1, 2, 3, 3, 3,  0, 0, 0, 0, 1, 2, 3, 3, 3,
        4, 4, 4, 4, 5, 6, 7, 7, 7,  8, 8, 8, 8, 9, 10, 11, 11, 11, 8, 8, 8, 8, 9, 10, 11, 11, 11};
    const std::vector<float> constant = {
        0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0, 0, 1, 2, 3, 0, 0,
        0, 0, 0, 4, 5, 6, 7, 0, 0,  0, 0, 0, 8, 9, 10, 11, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    Shape out;
    test::check_close(run_pad({1, 3, 4, {2, 3, 1, 2, PadMode::Reflect, 0.0f}}, x, out), reflect, test::Tol::bits());
    CHECK(out == Shape{1, 6, 9});
    test::check_close(run_pad({1, 3, 4, {2, 3, 1, 2, PadMode::Edge, 0.0f}}, x, out), edge, test::Tol::bits());
    test::check_close(run_pad({1, 3, 4, {2, 3, 1, 2, PadMode::Constant, 0.0f}}, x, out), constant, test::Tol::bits());
    for (PadMode mode : kModes) check_case({1, 3, 4, {2, 3, 1, 2, mode, 0.0f}}, x);
}

// Outside the harness: extremes (NaN, infinities, HDR values, -0 and NaN constants), bit for bit.
TEST_CASE("pad2d copies NaN, infinities, HDR values and the constant bit for bit", "[pad2d][extremes]") {
    std::mt19937 rng(97);
    const float big = std::numeric_limits<float>::max();
    const float values[] = {kNaN, kInf, -kInf, 65504.0f, std::nextafter(65504.0f, kInf), -65504.0f, big, -big,
                            0.0f, -0.0f, 1.0e-45f, 1.0f};
    std::uniform_int_distribution<int> pick(0, int(std::size(values)) - 1);
    for (PadMode mode : kModes)
        for (const Case& k : {Case{4, 9, 11, {2, 3, 4, 1, mode, 0.0f}}, Case{3, 6, 7, {5, 6, 5, 6, mode, -0.0f}},
                              Case{2, 13, 3, {1, 2, 12, 0, mode, 65504.0f}}}) {
            std::vector<float> x(std::size_t(k.c) * k.h * k.w);
            for (float& v : x) v = values[pick(rng)];
            check_case(k, x);
        }
    // Constants NaN, +-Inf, -0 and 65504 fill the border exactly.
    for (float value : {kNaN, kInf, -kInf, -0.0f, 65504.0f}) {
        const Case k{2, 3, 2, {1, 2, 1, 0, PadMode::Constant, value}};
        const std::vector<float> y = check_case(k, test::random_vector(12, rng));
        test::check_close(std::span<const float>(y).first(1), std::span<const float>(&value, 1), test::Tol::bits());
    }
}

// Outside the harness: an edge shape (1x1).
TEST_CASE("pad2d on a 1x1 spatial input", "[pad2d]") {
    std::mt19937 rng(101);
    const std::vector<float> x = test::random_vector(7, rng, -2.0f, 2.0f);
    Shape out;
    // Edge: every cell of the padded plane is the one input value.
    const std::vector<float> y = run_pad({7, 1, 1, {3, 2, 1, 4, PadMode::Edge, 0.0f}}, x, out);
    REQUIRE(out == Shape{7, 5, 7});
    std::vector<float> everywhere;
    for (int c = 0; c < 7; ++c) everywhere.insert(everywhere.end(), 35, x[c]);
    test::check_close(y, everywhere, test::Tol::bits());
    check_case({7, 1, 1, {3, 2, 1, 4, PadMode::Constant, 9.0f}}, x);
    // Reflect allows no padding at all on a 1 x 1 plane: a copy.
    test::check_close(run_pad({7, 1, 1, {0, 0, 0, 0, PadMode::Reflect, 0.0f}}, x, out), x, test::Tol::bits());
}

// Outside the harness: refusals.
TEST_CASE("pad2d refuses bad geometry and shapes with errors naming the op", "[pad2d]") {
    auto& c = test::ctx();
    SECTION("a crop of the whole input, an unknown mode") {
        // Negative pads crop (ONNX Pad; ConvTranspose's output_padding maps to one), but not everything.
        CHECK_THROWS_WITH(Pad2d(c, {-2, 0, -1, 0, PadMode::Constant, 0.0f}).output_shape({1, 3, 4}),
                          Contains("pad2d") && Contains("top -2") && Contains("crops the whole input"));
        CHECK_THROWS_WITH(Pad2d(c, {0, 0, 0, -3, PadMode::Edge, 0.0f}).output_shape({1, 3, 3}),
                          Contains("pad2d") && Contains("right -3"));
        CHECK_THROWS_WITH(Pad2d(c, {1, 1, 1, 1, PadMode(7), 0.0f}), Contains("pad2d") && Contains("unknown mode 7"));
    }
    SECTION("a reflect pad not below its axis' size") {
        Pad2d op(c, {3, 1, 0, 2, PadMode::Reflect, 0.0f});
        CHECK(op.output_shape({2, 4, 3}) == Shape{2, 7, 6});
        CHECK_THROWS_WITH(op.output_shape({2, 3, 5}), Contains("pad2d") && Contains("reflect top padding 3") &&
                                                          Contains("input height 3"));
        CHECK_THROWS_WITH(op.output_shape({2, 4, 2}), Contains("pad2d") && Contains("reflect right padding 2") &&
                                                          Contains("input width 2"));
        Pad2d one(c, {0, 1, 0, 0, PadMode::Reflect, 0.0f});
        CHECK_THROWS_WITH(one.output_shape({1, 5, 1}), Contains("reflect left padding 1") && Contains("input width 1"));
        Pad2d bottom(c, {0, 0, 6, 0, PadMode::Reflect, 0.0f});
        CHECK_THROWS_AS(bottom.output_shape({1, 6, 9}), InputError);
        // The same pads are fine in the other modes.
        CHECK(Pad2d(c, {3, 1, 0, 2, PadMode::Edge, 0.0f}).output_shape({2, 3, 2}) == Shape{2, 6, 5});
        CHECK(Pad2d(c, {0, 0, 6, 0, PadMode::Constant, 0.0f}).output_shape({1, 6, 9}) == Shape{1, 12, 9});
    }
    SECTION("an empty input, an output of 2^31 floats") {
        Pad2d op(c, {1, 1, 1, 1, PadMode::Constant, 0.0f});
        CHECK_THROWS_WITH(op.output_shape({0, 4, 4}), Contains("pad2d") && Contains("empty input"));
        CHECK_THROWS_AS(op.output_shape({3, 4, 0}), InputError);
        CHECK_THROWS_WITH(op.output_shape({1 << 12, 1 << 10, (1 << 9) - 2}), Contains("pad2d") && Contains("2^31"));
    }
    SECTION("an output view of the wrong shape, a null buffer") {
        Pad2d op(c, {1, 2, 1, 2, PadMode::Edge, 0.0f});
        Buffer xb = test::upload(std::vector<float>(3 * 4 * 4, 1.0f));
        Buffer yb = test::upload(std::vector<float>(3 * 6 * 8, 0.0f));
        CHECK_THROWS_WITH(op.enqueue(c, View{xb.get(), 0, {3, 4, 4}}, View{yb.get(), 0, {3, 6, 7}}),
                          Contains("pad2d") && Contains("pads to 3x6x8"));
        CHECK_THROWS_WITH(op.enqueue(c, View{nullptr, 0, {3, 4, 4}}, View{yb.get(), 0, {3, 6, 8}}),
                          Contains("pad2d") && Contains("input buffer is null"));
    }
}

// Small enough for the oclgrind stage (tools/ci/oclgrind.sh): odd sizes, asymmetric pads, every mode, NaN and
// +-Inf among the values, outputs between sentinels at offsets.
// Outside the harness: NaN and infinities among the inputs under oclgrind (the rows draw finite ones).
TEST_CASE("pad2d at small odd shapes in every mode with NaN and infinities", "[pad2d][oclgrind]") {
    std::mt19937 rng(103);
    for (PadMode mode : kModes)
        for (const Case& k : {Case{3, 5, 7, {2, 1, 4, 3, mode, -1.5f}}, Case{2, 1, 3, {0, 2, 0, 2, mode, 0.0f}},
                              Case{1, 1, 1, {0, 0, 0, 0, mode, 0.0f}}}) {
            std::vector<float> x = test::random_vector(std::size_t(k.c) * k.h * k.w, rng, -4.0f, 4.0f);
            if (x.size() > 4) {
                x[1] = kNaN;
                x[2] = kInf;
                x[x.size() - 2] = -kInf;
            }
            check_case(k, x);
        }
}

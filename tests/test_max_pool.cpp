// 2D max pooling (ops/max_pool.hpp) against the naive reference, exactly (every output is one of the inputs): edge
// shapes, padding that never wins, NaN propagation, infinities and HDR values, a 1 x 1 spatial input, and the
// geometries and shapes the op refuses.
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

#include "ops/max_pool.hpp"
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
    MaxPoolGeometry g;
};

std::string describe(const Case& k) {
    const MaxPoolGeometry& g = k.g;
    std::ostringstream s;
    s << "C" << k.c << " " << k.h << "x" << k.w << " kernel " << g.kh << "x" << g.kw << " stride " << g.stride_h << "x"
      << g.stride_w << " pads t" << g.pad_top << " l" << g.pad_left << " b" << g.pad_bottom << " r" << g.pad_right;
    return s.str();
}

// Runs the op on x between guards (tests/guarded_op.hpp); returns y.
std::vector<float> run_pool(const Case& k, const std::vector<float>& x, Shape& out) {
    MaxPool2d op(test::ctx(), k.g);
    const Shape in{k.c, k.h, k.w};
    out = op.output_shape(in);
    return test::run_guarded(x, in, out, [&](Context& c, const View& xv, const View& yv) { op.enqueue(c, xv, yv); });
}

// Every output is one of the inputs: exact, and NaN wherever the reference's window holds one.
const test::Tol kPoolExact = test::Tol::exact().nan_where_want_nan();

// The op against ref::max_pool2d on x; returns y.
std::vector<float> check_case(const Case& k, const std::vector<float>& x) {
    INFO(describe(k));
    Shape out;
    const std::vector<float> y = run_pool(k, x, out);
    int oh = 0, ow = 0;
    const MaxPoolGeometry& g = k.g;
    const std::vector<float> want = ref::max_pool2d(x, k.c, k.h, k.w, g.kh, g.kw, g.stride_h, g.stride_w, g.pad_top,
                                                    g.pad_left, g.pad_bottom, g.pad_right, oh, ow);
    REQUIRE(out == Shape{k.c, oh, ow});
    test::check_close(y, want, kPoolExact);
    return y;
}

std::vector<float> check_random(const Case& k, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
    return check_case(k, test::random_vector(std::size_t(k.c) * k.h * k.w, rng, lo, hi));
}

}  // namespace

// Outside the harness: edge shapes (one value, a row, a column, the whole plane, the largest pads). Common geometries
// at odd sizes (k2 s2, k3 s2 p1, asymmetric pads, a stride above the kernel) are the harness's MaxPool2d rows.
TEST_CASE("max_pool2d at edge shapes: one value, a row, a column, the whole plane, the largest pads", "[max_pool]") {
    std::mt19937 rng(61);
    const std::vector<Case> edges = {
        {1, 1, 1, {1, 1, 1, 1, 0, 0, 0, 0}},    // identity on one value
        {3, 5, 7, {5, 7, 1, 1, 0, 0, 0, 0}},    // the kernel is the whole plane: global max pooling
        {6, 9, 4, {2, 3, 2, 3, 0, 2, 1, 0}},    // pads on one side only
        {20, 37, 37, {5, 5, 3, 3, 4, 0, 0, 4}}, // the largest pads a k5 allows, on opposite corners
        {17, 1, 37, {1, 5, 1, 2, 0, 4, 0, 3}},  // one row
        {9, 29, 1, {4, 1, 3, 1, 3, 0, 2, 0}},   // one column
    };
    for (const Case& k : edges) check_random(k, rng);
}

// Outside the harness: extremes (all-negative and all -Inf inputs: padding must never win).
TEST_CASE("max_pool2d padding counts as -Inf and never wins", "[max_pool]") {
    std::mt19937 rng(67);
    // All inputs negative: zero padding would win at every border window; -Inf padding never does.
    for (const Case& k : {Case{4, 9, 7, {3, 3, 1, 1, 1, 1, 1, 1}}, Case{3, 5, 6, {4, 2, 2, 2, 3, 1, 2, 0}},
                          Case{2, 1, 1, {3, 3, 1, 1, 2, 1, 0, 1}}}) {
        const std::vector<float> y = check_random(k, rng, -5.0f, -1.0f);
        for (float v : y) CHECK(v <= -1.0f);
    }
    // A plane of -Inf pools to -Inf everywhere, padded windows included.
    const Case k{2, 5, 5, {3, 3, 2, 2, 1, 1, 2, 2}};
    const std::vector<float> y = check_case(k, std::vector<float>(2 * 5 * 5, -kInf));
    for (float v : y) CHECK(v == -kInf);
}

// Outside the harness: extremes (NaN anywhere in a window); the rows draw finite inputs.
TEST_CASE("max_pool2d propagates NaN from anywhere in the window", "[max_pool][extremes]") {
    // By hand, one 1 x 3 window per plane: a NaN first, between larger values, last, next to +-Inf, everywhere;
    // and two planes without NaN.
    const std::vector<float> x = {kNaN, 5.0f, 1.0f,  5.0f, kNaN, 1.0f,  1.0f,  5.0f, kNaN,  kInf, kNaN, -kInf,
                                  kNaN, kNaN, kNaN,  -kInf, 2.0f, kInf, -kInf, -kInf, -kInf};
    const Case k{7, 1, 3, {1, 3, 1, 3, 0, 0, 0, 0}};
    const std::vector<float> y = check_case(k, x);
    REQUIRE(y.size() == 7);
    for (int c = 0; c < 5; ++c) CHECK(std::isnan(y[c]));
    CHECK(y[5] == kInf);
    CHECK(y[6] == -kInf);

    // NaNs scattered over random planes, overlapping windows and padded borders: exactly the windows that hold one
    // are NaN (the reference), the others exact.
    std::mt19937 rng(71);
    for (const Case& r : {Case{3, 11, 13, {3, 3, 2, 2, 1, 1, 1, 1}}, Case{5, 8, 9, {2, 4, 1, 3, 0, 3, 1, 2}},
                          Case{2, 17, 5, {5, 2, 2, 1, 4, 1, 2, 0}}}) {
        std::vector<float> v = test::random_vector(std::size_t(r.c) * r.h * r.w, rng, -3.0f, 3.0f);
        std::uniform_int_distribution<std::size_t> at(0, v.size() - 1);
        for (int n = 0; n < 4; ++n) v[at(rng)] = kNaN;
        v[0] = kNaN;             // the first cell (a corner under padding)
        v[v.size() - 1] = kNaN;  // the last
        const std::vector<float> out = check_case(r, v);
        CHECK(std::any_of(out.begin(), out.end(), [](float f) { return std::isnan(f); }));
        CHECK(std::any_of(out.begin(), out.end(), [](float f) { return !std::isnan(f); }));
    }
}

// Outside the harness: extremes (infinities, FLT_MAX, 65504 and its next float).
TEST_CASE("max_pool2d keeps infinities and HDR values exactly", "[max_pool][extremes]") {
    std::mt19937 rng(73);
    const float big = std::numeric_limits<float>::max();
    const float values[] = {kInf, -kInf, 65504.0f, std::nextafter(65504.0f, kInf), 70000.0f, 1.0e7f, big, -big,
                            -65504.0f, 0.0f, 1.0f, -1.0f};
    std::uniform_int_distribution<int> pick(0, int(std::size(values)) - 1);
    for (const Case& k : {Case{4, 9, 11, {3, 3, 2, 2, 1, 1, 1, 1}}, Case{3, 6, 7, {2, 2, 1, 1, 0, 1, 1, 0}},
                          Case{2, 13, 3, {4, 3, 3, 1, 1, 2, 3, 0}}}) {
        std::vector<float> x(std::size_t(k.c) * k.h * k.w);
        for (float& v : x) v = values[pick(rng)];
        check_case(k, x);
    }
    // 65504 (the fp16 limit) and its next float, and FLT_MAX next to +-Inf, come out unrounded.
    const std::vector<float> y =
        check_case({3, 1, 2, {1, 2, 1, 2, 0, 0, 0, 0}}, {65504.0f, std::nextafter(65504.0f, kInf), -kInf, big, -big, -kInf});
    test::check_close(y, std::vector<float>{std::nextafter(65504.0f, kInf), big, -big}, test::Tol::exact());
}

// Outside the harness: an edge shape (1x1) under five geometries, the input back bit for bit.
TEST_CASE("max_pool2d on a 1x1 spatial input gives the input back", "[max_pool]") {
    std::mt19937 rng(79);
    const std::vector<float> x = test::random_vector(7, rng, -2.0f, 2.0f);
    for (const MaxPoolGeometry& g : {MaxPoolGeometry{1, 1, 1, 1, 0, 0, 0, 0}, MaxPoolGeometry{3, 3, 1, 1, 1, 1, 1, 1},
                                     MaxPoolGeometry{2, 2, 2, 2, 1, 0, 0, 1}, MaxPoolGeometry{2, 3, 1, 3, 0, 1, 1, 1},
                                     MaxPoolGeometry{5, 5, 3, 2, 4, 4, 0, 0}}) {
        const Case k{7, 1, 1, g};
        Shape out;
        INFO(describe(k));
        test::check_close(run_pool(k, x, out), x, test::Tol::exact());
        CHECK(out == Shape{7, 1, 1});
        check_case(k, x);
    }
}

// Outside the harness: refusals.
TEST_CASE("max_pool2d refuses bad geometry and shapes with errors naming the op", "[max_pool]") {
    auto& c = test::ctx();
    SECTION("a pad not below its kernel side") {
        CHECK_THROWS_WITH(MaxPool2d(c, {3, 3, 1, 1, 3, 0, 0, 0}),
                          Contains("max_pool2d") && Contains("top padding 3") && Contains("kernel height 3"));
        CHECK_THROWS_WITH(MaxPool2d(c, {3, 2, 1, 1, 0, 0, 4, 0}),
                          Contains("max_pool2d") && Contains("bottom padding 4") && Contains("kernel height 3"));
        CHECK_THROWS_WITH(MaxPool2d(c, {3, 2, 1, 1, 0, 2, 0, 0}),
                          Contains("max_pool2d") && Contains("left padding 2") && Contains("kernel width 2"));
        CHECK_THROWS_WITH(MaxPool2d(c, {1, 1, 1, 1, 0, 0, 0, 1}),
                          Contains("max_pool2d") && Contains("right padding 1") && Contains("kernel width 1"));
        CHECK_THROWS_AS(MaxPool2d(c, {3, 3, 1, 1, 3, 0, 0, 0}), InputError);
    }
    SECTION("a zero stride, a zero kernel, a negative pad") {
        CHECK_THROWS_WITH(MaxPool2d(c, {2, 2, 0, 1, 0, 0, 0, 0}), Contains("max_pool2d") && Contains("stride 0x1"));
        CHECK_THROWS_WITH(MaxPool2d(c, {2, 2, 2, 0, 0, 0, 0, 0}), Contains("max_pool2d") && Contains("stride 2x0"));
        CHECK_THROWS_WITH(MaxPool2d(c, {0, 2, 1, 1, 0, 0, 0, 0}), Contains("max_pool2d") && Contains("kernel 0x2"));
        CHECK_THROWS_WITH(MaxPool2d(c, {2, 2, 1, 1, 0, -1, 0, 0}), Contains("max_pool2d") && Contains("left -1"));
        CHECK_THROWS_AS(MaxPool2d(c, {2, 2, 0, 0, 0, 0, 0, 0}), InputError);
    }
    SECTION("a kernel larger than the padded input, an empty input") {
        MaxPool2d op(c, {5, 3, 1, 1, 1, 1, 1, 1});
        CHECK_THROWS_WITH(op.output_shape({1, 2, 9}), Contains("max_pool2d") && Contains("input height 2 (padded 4)") &&
                                                          Contains("kernel height 5"));
        CHECK(op.output_shape({1, 3, 9}) == Shape{1, 1, 9});  // padded 5: one row of windows
        MaxPool2d wide(c, {1, 6, 1, 1, 0, 0, 0, 1});
        CHECK_THROWS_WITH(wide.output_shape({2, 7, 4}),
                          Contains("max_pool2d") && Contains("input width 4 (padded 5)") && Contains("kernel width 6"));
        CHECK_THROWS_WITH(op.output_shape({0, 4, 4}), Contains("max_pool2d") && Contains("empty input"));
        CHECK_THROWS_AS(op.output_shape({3, 4, 0}), InputError);
    }
    SECTION("an output view of the wrong shape") {
        MaxPool2d op(c, {2, 2, 2, 2, 0, 0, 0, 0});
        Buffer xb = test::upload(std::vector<float>(3 * 6 * 6, 1.0f));
        Buffer yb = test::upload(std::vector<float>(3 * 3 * 3, 0.0f));
        CHECK_THROWS_WITH(op.enqueue(c, View{xb.get(), 0, {3, 6, 6}}, View{yb.get(), 0, {3, 3, 2}}),
                          Contains("max_pool2d") && Contains("pools to 3x3x3"));
        CHECK_THROWS_WITH(op.enqueue(c, View{xb.get(), 0, {3, 6, 6}}, View{nullptr, 0, {3, 3, 3}}),
                          Contains("max_pool2d") && Contains("output buffer is null"));
    }
}

// Small enough for the oclgrind stage (tools/ci/oclgrind.sh): odd sizes, asymmetric padding, stride above the
// kernel, NaN and +-Inf among the values, outputs between sentinels at offsets.
// Outside the harness: NaN and infinities among the inputs under oclgrind (the rows draw finite ones).
TEST_CASE("max_pool2d at small odd shapes with padding, NaN and infinities", "[max_pool][oclgrind]") {
    std::mt19937 rng(83);
    const std::vector<Case> cases = {{3, 5, 7, {3, 3, 2, 2, 1, 1, 1, 1}},
                                     {2, 7, 5, {2, 3, 3, 1, 0, 2, 1, 0}},
                                     {5, 3, 3, {1, 1, 1, 1, 0, 0, 0, 0}},
                                     {1, 1, 1, {3, 3, 1, 1, 1, 1, 1, 1}}};
    for (const Case& k : cases) {
        std::vector<float> x = test::random_vector(std::size_t(k.c) * k.h * k.w, rng, -4.0f, 4.0f);
        if (x.size() > 4) {
            x[1] = kNaN;
            x[2] = kInf;
            x[x.size() - 2] = -kInf;
        }
        check_case(k, x);
    }
}

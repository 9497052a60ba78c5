// The comparison every op test uses (tests/compare.hpp): each tolerance kind passes at its bound and fails just
// beyond it, the NaN / Inf rules, skipped elements, and what a failure reports.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "compare.hpp"

using namespace ngi::test;
using Catch::Matchers::Contains;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

float next_up(float v, int ulps = 1) {
    for (int i = 0; i < ulps; ++i) v = std::nextafter(v, kInf);
    return v;
}

bool passes(std::vector<float> got, std::vector<double> want, const Tol& tol) { return compare(got, want, tol).ok; }

}  // namespace

TEST_CASE("compare: exact and bits", "[compare]") {
    CHECK(passes({1.0f, -2.5f, 0.0f}, {1.0, -2.5, -0.0}, Tol::exact()));  // -0 == +0
    CHECK_FALSE(passes({1.0f, next_up(-2.5f)}, {1.0, -2.5}, Tol::exact()));
    CHECK_FALSE(compare(std::vector<float>{0.0f}, std::vector<float>{-0.0f}, Tol::bits()).ok);
    CHECK(compare(std::vector<float>{kNaN, -0.0f}, std::vector<float>{kNaN, -0.0f}, Tol::bits()).ok);
    const float other_nan = std::nanf("7");
    CHECK_FALSE(compare(std::vector<float>{kNaN}, std::vector<float>{other_nan}, Tol::bits()).ok);  // the payload
}

TEST_CASE("compare: NaN and infinities follow the stated rules", "[compare]") {
    // want NaN: equal only where the Tol says NaN propagates, and then only to a NaN.
    CHECK_FALSE(passes({kNaN}, {NAN}, Tol::exact()));
    CHECK(passes({kNaN}, {NAN}, Tol::exact().nan_where_want_nan()));
    CHECK_FALSE(passes({1.0f}, {NAN}, Tol::absolute(1e30, "x").nan_where_want_nan()));
    // want +-Inf: the same infinity, whatever the bound.
    CHECK(passes({kInf, -kInf}, {INFINITY, -INFINITY}, Tol::relative(0.5, "x")));
    CHECK_FALSE(passes({3.4e38f}, {INFINITY}, Tol::relative(0.5, "x")));
    CHECK_FALSE(passes({-kInf}, {INFINITY}, Tol::absolute(1e30, "x")));
    // got non-finite where want is finite: never within any bound.
    const Comparison r = compare(std::vector<float>{1.0f, kNaN}, std::vector<double>{1.0, 2.0}, Tol::absolute(1e30, "x"));
    CHECK_FALSE(r.ok);
    CHECK(r.nonfinite);
    CHECK(r.worst == 1);
    CHECK_FALSE(passes({kInf}, {1.0}, Tol::scaled(1e30, "x")));
}

TEST_CASE("compare: each bounded kind passes at its bound and fails beyond it", "[compare]") {
    // ulp: 2 ulp of float(want) pass, 3 do not.
    CHECK(passes({next_up(1.5f, 2)}, {1.5}, Tol::ulp(2, "x")));
    CHECK_FALSE(passes({next_up(1.5f, 3)}, {1.5}, Tol::ulp(2, "x")));
    // relative / absolute / their combination (the larger bound).
    CHECK(passes({1.0f + 1e-4f}, {1.0}, Tol::relative(2e-4, "x")));
    CHECK_FALSE(passes({1.0f + 1e-3f}, {1.0}, Tol::relative(2e-4, "x")));
    CHECK(passes({1e-4f}, {0.0}, Tol::relative(1e-3, "x").or_absolute(2e-4)));
    CHECK_FALSE(passes({1e-4f}, {0.0}, Tol::relative(1e-3, "x")));
    CHECK_FALSE(passes({0.5f}, {0.0}, Tol::absolute(0.25, "x")));
    // scaled: of max |want| by default, of a given scale with of().
    CHECK(passes({10.0f, 0.0f + 0.009f}, {10.0, 0.0}, Tol::scaled(1e-3, "x")));
    CHECK_FALSE(passes({10.0f, 0.0f + 0.011f}, {10.0, 0.0}, Tol::scaled(1e-3, "x")));
    CHECK_FALSE(passes({10.0f, 0.009f}, {10.0, 0.0}, Tol::scaled(1e-3, "x").of(1.0)));
    // sum_of(k): gamma_k times each element's sum of |terms|.
    const double g = 4 * kUnitRoundoff / (1 - 4 * kUnitRoundoff);
    CHECK(passes({float(1.0 + 0.9 * g * 8)}, {1.0}, Tol::sum_of(4, {8.0})));
    CHECK_FALSE(passes({float(1.0 + 1.2 * g * 8)}, {1.0}, Tol::sum_of(4, {8.0})));
    CHECK_FALSE(compare(std::vector<float>{1.0f, 1.0f}, std::vector<double>{1.0, 1.0}, Tol::sum_of(4, {8.0})).ok);
}

TEST_CASE("compare: skipped elements, sizes, and the report of the worst element", "[compare]") {
    const std::vector<float> got = {1.0f, 5.0f, 2.0f, 3.5f};
    const std::vector<double> want = {1.0, 2.0, 2.0, 3.0};
    const Tol tol = Tol::absolute(0.25, "the reason");
    const std::vector<char> skip = {0, 1, 0, 1};
    CHECK(compare(got, want, tol, skip).ok);
    const Comparison r = compare(got, want, tol);
    CHECK_FALSE(r.ok);
    CHECK(r.outside == 2);
    CHECK(r.worst == 1);  // |d| 3 there, 0.5 at element 3
    CHECK(r.got == 5.0);
    CHECK(r.want == 2.0);
    CHECK(r.bound == 0.25);
    CHECK_THAT(r.report(), Contains("element 1 of 4") && Contains("got 5") && Contains("want 2") &&
                               Contains("bound 0.25") && Contains("2 element(s) outside") &&
                               Contains("absolute 0.25 (the reason)"));
    CHECK_FALSE(compare(std::vector<float>{1.0f}, want, tol).ok);
    CHECK_THAT(compare(std::vector<float>{1.0f}, want, tol).report(), Contains("sizes differ"));
    // Within the bound: the worst element is still reported (its ratio, for the measured margin).
    const Comparison in = compare(std::vector<float>{1.0f, 2.125f}, std::vector<double>{1.0, 2.0}, tol);
    CHECK(in.ok);
    CHECK(in.worst == 1);
    CHECK(in.ratio == 0.5);
    CHECK(in.max_abs == 0.125);
}

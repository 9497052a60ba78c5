// One comparison for the tests and the op harness: a result `got` (float32, from a device) against a reference `want`
// (float64 or float32) under a named tolerance kind, Tol. Every bound a test uses is one of the kinds below, built
// with the reason it is that large (the `why`, printed on failure); shared ones are named in namespace tol. The Catch2
// checks over it are test::check_close / require_close (tests/test_support.hpp); the op harness
// (tests/op_harness/op_cases.cpp, no Catch2: perf/op_bench links it) calls compare() itself.
//
// The kinds, per element i (d = |got_i - want_i|, u = 2^-24 = float32's unit roundoff: the relative error of one
// correctly rounded operation; ulp(w) = the spacing of float32 at |float(w)|):
// - exact():       got == want (0 ulp; -0 == +0). Ops whose every output is one of the inputs, a constant or the same
//                  arithmetic in the same order (max pooling, sanitizing, two launch forms of one reduction).
// - bits():        the same 32 bits: NaN payloads and the sign of zero too. Copies (padding, a split of the senders).
// - ulp(n, why):   d <= n ulp(want): an elementary function's own error (tanh: OpenCL allows the built-in 5 ulp).
// - sum_of(k, S):  d <= gamma_k S_i, gamma_k = k u / (1 - k u), S_i = the sum of |terms| of element i (the reference
//                  evaluated on absolute values): the worst case of a float32 sum of k rounded terms in any order,
//                  fma or not (Higham, "Accuracy and Stability of Numerical Algorithms", 2nd ed., eq. 3.5 and
//                  lemma 3.1). k counts every rounding on the way to the element (the products' and sums', and an
//                  epilogue's). It holds on every device whatever its summation order; it is loose for long sums
//                  (k = 8192 allows 5e-4 of S), where the tests use relative/absolute bounds with their reasons.
// - relative(r, why):  d <= r |want_i|.    absolute(a, why):  d <= a.
// - scaled(r, why):    d <= r S, S = max over the compared elements of the finite |want_j| (1e-30 if none), or the
//                  scale given with .of(S) (e.g. max |x| of the input of an interpolation): the op harness's
//                  normalized error (op_cases.hpp). Unit-free, and an indexing bug damages elements by O(S).
// Kinds combine with .or_absolute(a) / .or_relative(r) / .or_scaled(r): an element passes within any of the bounds
// (Catch's Approx(w).epsilon(r).margin(a) is relative(r).or_absolute(a)), so the bound is their maximum.
//
// Non-finite values, explicitly: where want is +-Inf, got must be the same infinity (every kind). Where want is NaN,
// got must be NaN for a Tol made .nan_where_want_nan() (ops that propagate NaN by specification: max pooling,
// resizing) and the element fails otherwise. A NaN or an infinity in got where want is finite fails. bits() compares
// the bits, NaN payloads included. Elements the caller marks in `skip` are not compared (e.g. JBU pixels whose
// fallback decision is within rounding of the threshold).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace ngi::test {

inline constexpr double kUnitRoundoff = 0x1p-24;  // float32: 2^-24 = 5.96e-8

// The spacing of float32 at |float(w)| (the smallest subnormal at 0).
inline double ulp32(double w) {
    const float a = std::abs(float(w));
    if (!std::isfinite(a)) return INFINITY;
    return double(std::nextafter(a, std::numeric_limits<float>::infinity())) - double(a);
}

inline std::string format_number(double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.9g", v);
    return s;
}

class Tol {
public:
    static Tol exact() { return Tol(Kind::exact, "exact (0 ulp)"); }
    static Tol bits() { return Tol(Kind::bits, "bit for bit"); }
    static Tol ulp(double n, std::string why) {
        Tol t(Kind::bounded, std::move(why));
        t.ulps_ = n;
        return t;
    }
    // k: the roundings counted (see above); magnitude: sum |terms| per element, as many as the elements compared.
    static Tol sum_of(int k, std::vector<double> magnitude, std::string why = {}) {
        Tol t(Kind::bounded, std::move(why));
        t.sum_k_ = k;
        t.magnitude_ = std::move(magnitude);
        return t;
    }
    static Tol relative(double r, std::string why) {
        Tol t(Kind::bounded, std::move(why));
        t.rel_ = r;
        return t;
    }
    static Tol absolute(double a, std::string why) {
        Tol t(Kind::bounded, std::move(why));
        t.abs_ = a;
        return t;
    }
    static Tol scaled(double r, std::string why) {
        Tol t(Kind::bounded, std::move(why));
        t.scaled_ = r;
        return t;
    }
    Tol or_absolute(double a) const { Tol t = *this; t.to_bounded(); t.abs_ = a; return t; }
    Tol or_relative(double r) const { Tol t = *this; t.to_bounded(); t.rel_ = r; return t; }
    Tol or_scaled(double r) const { Tol t = *this; t.to_bounded(); t.scaled_ = r; return t; }
    // The scale S of the scaled bound (default: max |want| over the compared elements).
    Tol of(double scale) const { Tol t = *this; t.scale_ = scale; return t; }
    Tol nan_where_want_nan() const { Tol t = *this; t.nan_equal_ = true; return t; }

    bool is_bits() const { return kind_ == Kind::bits; }
    bool nan_equal() const { return nan_equal_; }
    bool uses_scale() const { return scaled_ > 0; }
    double given_scale() const { return scale_; }  // < 0: max |want|
    std::size_t magnitudes() const { return magnitude_.size(); }
    bool uses_magnitude() const { return sum_k_ > 0; }

    // The bound of element i whose reference is w, under scale S (the scaled kind's).
    double bound(std::size_t i, double w, double S) const {
        double b = std::max(abs_, rel_ * std::abs(w));
        if (ulps_ > 0) b = std::max(b, ulps_ * ulp32(w));
        if (scaled_ > 0) b = std::max(b, scaled_ * S);
        if (sum_k_ > 0) {
            const double ku = sum_k_ * kUnitRoundoff;
            b = std::max(b, ku / (1.0 - ku) * (i < magnitude_.size() ? magnitude_[i] : INFINITY));
        }
        return b;
    }

    // "relative 0.0001 or absolute 0.0001 (fp32 accumulation ...)".
    std::string name() const {
        if (kind_ != Kind::bounded) return why_;
        std::string s;
        auto part = [&s](const std::string& p) { s += (s.empty() ? "" : " or ") + p; };
        if (sum_k_ > 0) part("sum_of(k " + format_number(sum_k_) + "): gamma_k sum|terms|");
        if (ulps_ > 0) part(format_number(ulps_) + " ulp");
        if (rel_ > 0) part("relative " + format_number(rel_));
        if (scaled_ > 0)
            part("scaled " + format_number(scaled_) + " of " + (scale_ >= 0 ? format_number(scale_) : "max |want|"));
        if (abs_ > 0) part("absolute " + format_number(abs_));
        if (s.empty()) s = "exact (0 ulp)";
        if (nan_equal_) s += ", NaN where want is NaN";
        return why_.empty() ? s : s + " (" + why_ + ")";
    }

private:
    enum class Kind { exact, bits, bounded };
    Tol(Kind k, std::string why) : kind_(k), why_(std::move(why)) {}
    void to_bounded() {
        if (kind_ == Kind::exact) { kind_ = Kind::bounded; why_.clear(); }
    }
    Kind kind_;
    std::string why_;
    double abs_ = 0, rel_ = 0, ulps_ = 0, scaled_ = 0, sum_k_ = 0, scale_ = -1;
    std::vector<double> magnitude_;
    bool nan_equal_ = false;
};

// What compare() found. `worst` is the element with the largest d / bound (the first of those outside the bound when
// any is): its values and bound are reported. `max_abs` is the largest d over the finite compared elements, `scale`
// the scaled kind's S (max |want| when none is given): max_abs / scale is the op harness's normalized error.
struct Comparison {
    static constexpr std::size_t none = std::size_t(-1);
    bool ok = true;
    std::size_t size = 0, compared = 0, outside = 0, worst = none;
    double got = 0, want = 0, bound = 0, ratio = 0;  // at `worst`; ratio = d / bound (inf: non-finite or bound 0)
    double max_abs = 0, scale = 0;
    bool nonfinite = false;  // got non-finite where want is finite
    std::string tolerance, problem;  // problem: sizes that differ, magnitudes missing

    // "element 12 of 300: got 0.25, want 0.2500004 (|d| 4e-07), bound 1e-07; 3 elements outside [tolerance]".
    std::string report() const {
        std::string s;
        if (!problem.empty()) s = problem + "; ";
        if (worst != none)
            s += "element " + std::to_string(worst) + " of " + std::to_string(size) + ": got " + format_number(got) +
                 ", want " + format_number(want) + " (|d| " + format_number(std::abs(got - want)) + "), bound " +
                 format_number(bound) + "; ";
        s += ok ? "within" : std::to_string(outside) + " element(s) outside";
        return s + " [" + tolerance + "]";
    }
};

namespace detail_compare {

// The float32 bits of a value as stored (a float's own bits: a signalling NaN stays one), or of float(value).
template <class T>
std::uint32_t float_bits(T v) {
    const float f = float(v);
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

}  // namespace detail_compare

// got against want under tol; skip (empty, or one flag per element): elements not compared. Ranges: std::vector,
// std::span, std::array of float or double.
template <class Got, class Want>
Comparison compare(const Got& got_range, const Want& want_range, const Tol& tol, std::span<const char> skip = {}) {
    Comparison r;
    r.tolerance = tol.name();
    const auto* got = std::data(got_range);
    const auto* want = std::data(want_range);
    const std::size_t n = std::size(want_range);
    r.size = n;
    if (std::size(got_range) != n) {
        r.ok = false;
        r.problem = "sizes differ: got " + std::to_string(std::size(got_range)) + ", want " + std::to_string(n);
        return r;
    }
    if (!skip.empty() && skip.size() != n) {
        r.ok = false;
        r.problem = "skip flags for " + std::to_string(skip.size()) + " of " + std::to_string(n) + " elements";
        return r;
    }
    if (tol.uses_magnitude() && tol.magnitudes() != n) {
        r.ok = false;
        r.problem = "sum_of: " + std::to_string(tol.magnitudes()) + " magnitudes for " + std::to_string(n) + " elements";
        return r;
    }
    auto skipped = [&](std::size_t i) { return !skip.empty() && skip[i]; };
    double S = tol.given_scale();
    if (S < 0) {
        S = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (!skipped(i) && std::isfinite(double(want[i]))) S = std::max(S, std::abs(double(want[i])));
    }
    r.scale = S = std::max(S, 1e-30);
    bool worst_outside = false;
    for (std::size_t i = 0; i < n; ++i) {
        if (skipped(i)) continue;
        ++r.compared;
        const double g = double(got[i]), w = double(want[i]);
        double bound = 0, ratio = 0;
        bool inside;
        if (tol.is_bits()) {
            inside = detail_compare::float_bits(got[i]) == detail_compare::float_bits(want[i]);
            ratio = inside ? 0.0 : INFINITY;
        } else if (std::isnan(w)) {
            inside = tol.nan_equal() && std::isnan(g);
            ratio = inside ? 0.0 : INFINITY;
        } else if (std::isinf(w)) {
            inside = g == w;
            ratio = inside ? 0.0 : INFINITY;
        } else if (!std::isfinite(g)) {
            inside = false;
            ratio = INFINITY;
            r.nonfinite = true;
        } else {
            const double d = std::abs(g - w);
            bound = tol.bound(i, w, S);
            inside = d <= bound;
            ratio = d == 0 ? 0.0 : bound > 0 ? d / bound : INFINITY;
            r.max_abs = std::max(r.max_abs, d);
        }
        if (!inside) {
            ++r.outside;
            r.ok = false;
        }
        // The worst: outside elements before inside ones, then the largest ratio (the first of equals).
        const bool better = r.worst == Comparison::none || (!inside && !worst_outside) ||
                            (!inside == worst_outside && ratio > r.ratio);
        if (better) {
            r.worst = i;
            r.got = g;
            r.want = w;
            r.bound = bound;
            r.ratio = ratio;
            worst_outside = !inside;
        }
    }
    return r;
}

// One value against its reference.
inline Comparison compare_value(double got, double want, const Tol& tol) {
    return compare(std::span<const double>(&got, 1), std::span<const double>(&want, 1), tol);
}

// Shared tolerances: each a named kind with the reason it is that large. A test's own tolerance, used in one file,
// is named there the same way.
namespace tol {

// A float32 sum of up to ~10^4 products (GEMM, convolutions, MLP layers) in another order than the float64
// reference: the observed error is ~1e-6 of the output at K = 8192 (docs/RELIABILITY.md); what these tests exist to
// catch, an index, a tile remainder, a miscompiled variant, damages outputs by O(0.1-1).
inline Tol accumulation() {
    return Tol::relative(1e-4, "fp32 accumulation in another order; indexing errors are O(0.1-1)").or_absolute(1e-4);
}

// A float32 sum of at most a few hundred terms (batch-norm statistics over a plane, a dense layer of <= 256 inputs,
// a set's mean over <= 600 items, SH-27 shading): observed <= 1e-6 of the output.
inline Tol short_sum() {
    return Tol::relative(1e-5, "fp32 sums of at most a few hundred terms").or_absolute(1e-5);
}

// The kernels' own tanh (kernels/activation.cl and mlp.cl's vector form: exp and a polynomial): 1.51 ulp at worst
// on PoCL; OpenCL 1.2 allows the built-in 5. 2 ulp flags a wrong coefficient or branch limit.
inline Tol tanh_ulp() { return Tol::ulp(2, "the kernels' tanh, 1.51 ulp measured"); }

}  // namespace tol

}  // namespace ngi::test

// Elementwise ops (ops/elementwise.hpp) beyond the op harness's rows (every activation, dropout, sanitize, affine,
// add and mul at odd sizes): activations and sanitizing at the numerical extremes, the dropout hash's test vectors,
// and the kernels' tanh to the ulp.
#include <algorithm>
#include <catch2/catch.hpp>

#include "ops/elementwise.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

// Outside the harness: extremes (+-0, +-88.8, +-1e30, +-FLT_MAX, +-1e-30); the rows draw from [-6, 6].
TEST_CASE("activations match the reference and saturate without NaN", "[elementwise][extremes][oclgrind]") {
    auto& c = test::ctx();
    Elementwise ew(c);
    std::vector<float> x = {0.0f, -0.0f, 1.0f, -1.0f, 20.0f, -20.0f, 88.8f, -88.8f, 1e30f, -1e30f, 65504.0f,
                            -65504.0f, 3.4e38f, -3.4e38f, 1e-30f, -1e-30f, 0.5f};
    // softplus and erf (ONNX Softplus, GELU's Erf): the built-in erf is allowed 16 ulp by OpenCL 1.2, softplus is
    // max(x, 0) + log1p(e^-|x|) (a few ulp); both within the same 2e-6 relative bound.
    const test::Tol builtin = test::Tol::relative(2e-6, "OpenCL 1.2 allows erf 16 ulp (1.9e-6)").or_absolute(1e-7);
    for (Act act : {Act::none(), Act::relu(), Act::leaky(0.2f), Act::tanh(), Act::sigmoid(), Act::softplus(),
                    Act::erf()}) {
        Buffer b = test::upload(x);
        ew.activate(c, View{b.get(), 0, {1, 1, int(x.size())}}, act);
        auto y = test::download(b, x.size());
        INFO("activation " << to_string(act.kind));
        std::vector<double> want;
        for (float v : x) want.push_back(ref::activate(v, int(act.kind), 0.2));
        test::check_close(y, want, builtin);  // a NaN or Inf in y fails it
    }
}

// Outside the harness: docs/MODEL_FORMAT.md's hash test vectors and the keep rate's statistics.
TEST_CASE("seeded dropout reproduces docs/MODEL_FORMAT.md's hash test vectors", "[elementwise][dropout][oclgrind]") {
    auto& c = test::ctx();
    Elementwise ew(c);
    struct Vec { std::uint32_t seed, site; int keep[4]; };
    for (const Vec& v : {Vec{0, 0, {1, 1, 0, 0}}, Vec{1234, 0, {0, 1, 0, 1}}, Vec{7, 2, {1, 0, 0, 1}}}) {
        Buffer b = test::upload({1.0f, 2.0f, 3.0f, 4.0f});
        ew.dropout(c, View{b.get(), 0, {1, 1, 4}}, v.seed, v.site, 0.5f);
        auto y = test::download(b, 4);
        for (int i = 0; i < 4; ++i) CHECK(y[i] == (v.keep[i] ? 2.0f * float(i + 1) : 0.0f));
    }
    // Over many elements the keep rate is 1-p and the mean is preserved (inverted dropout).
    std::vector<float> ones(100000, 1.0f);
    Buffer b = test::upload(ones);
    ew.dropout(c, View{b.get(), 0, {1, 1, int(ones.size())}}, 99, 0, 0.3f);
    auto y = test::download(b, ones.size());
    double sum = 0;
    int kept = 0;
    for (float v : y) { sum += v; kept += v != 0.0f; }
    // Binomial: 100,000 draws at keep rate 0.7 have sigma 0.00145 (the mean, each kept value 1/0.7: 0.0021).
    test::check_value(kept / 100000.0, 0.7, test::Tol::absolute(0.01, "7 sigma of the keep rate"));
    test::check_value(sum / 100000.0, 1.0, test::Tol::absolute(0.015, "7 sigma of the mean"));
}

// Outside the harness: specific values at the margin, the vector form's lanes at an offset, one count over 100k.
TEST_CASE("sanitize replaces NaN, Inf and far out-of-range values and counts them", "[elementwise][extremes][oclgrind]") {
    auto& c = test::ctx();
    Elementwise ew(c);
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    const float big = std::numeric_limits<float>::max();
    // Range [-1, 1]: the margin is 2/1024 = 0.00195 on each side; beyond it values go to the nearer end.
    Buffer b = test::upload({1.0f, nan, inf, -inf, 65504.0f, -2.0f, nan, 1.0019f, -1.0019f, 1.0021f, -1.0021f, big,
                             -3.4e38f, 0.5f});
    ew.sanitize(c, View{b.get(), 0, {1, 1, 14}}, -1.0f, 1.0f);
    CHECK(ew.sanitized_count(c) == 10);
    CHECK(test::download(b, 14) == std::vector<float>{1.0f, 0.0f, 1.0f, -1.0f, 1.0f, -1.0f, 0.0f, 1.0019f, -1.0019f,
                                                       1.0f, -1.0f, 1.0f, -1.0f, 0.5f});

    // Without limits (a graph with no input range: +-FLT_MAX) only NaN and Inf are replaced.
    Buffer u = test::upload({big, -big, inf, -inf, nan, 3.0f});
    ew.sanitize(c, View{u.get(), 0, {1, 1, 6}}, -big, big);
    CHECK(ew.sanitized_count(c) == 3);
    CHECK(test::download(u, 6) == std::vector<float>{big, -big, big, -big, 0.0f, 3.0f});

    // The vector form (16 values per work-item) with replaced and clean lanes mixed, whole vectors and a tail, at
    // an offset that is no multiple of 16: every lane's own verdict, the clean vectors left as they were.
    {
        std::mt19937 rng(41);
        std::vector<float> v = test::random_vector(3 * 16 + 7, rng, -0.9f, 0.9f), want = v;
        const float bad[] = {nan, inf, -inf, 2.0f, -5.0f, big};
        const float fixed[] = {0.0f, 1.0f, -1.0f, 1.0f, -1.0f, 1.0f};
        int replaced = 0;
        for (std::size_t i = 1; i < v.size(); i += 5) {  // vectors 0 and 2 and the tail get some; lanes vary
            if (i >= 16 && i < 32) continue;             // vector 1 stays clean (not rewritten)
            v[i] = bad[i % 6];
            want[i] = fixed[i % 6];
            ++replaced;
        }
        std::vector<float> padded(v.size() + 3, 7.0f);
        std::copy(v.begin(), v.end(), padded.begin() + 3);
        Buffer m = test::upload(padded);
        ew.sanitize(c, View{m.get(), 3, {1, 1, int(v.size())}}, -1.0f, 1.0f);
        CHECK(ew.sanitized_count(c) == replaced);
        const auto got = test::download(m, padded.size());
        CHECK(std::vector<float>(got.begin(), got.begin() + 3) == std::vector<float>(3, 7.0f));
        CHECK(std::vector<float>(got.begin() + 3, got.end()) == want);
    }

    // Many work-groups: the atomic count covers every element.
    std::vector<float> huge(100003, 3.4e38f);
    Buffer h = test::upload(huge);
    ew.sanitize(c, View{h.get(), 0, {1, 1, int(huge.size())}}, -1.0f, 1.0f);
    CHECK(ew.sanitized_count(c) == int(huge.size()));
    const auto y = test::download(h, huge.size());
    CHECK(std::all_of(y.begin(), y.end(), [](float v) { return v == 1.0f; }));
}

namespace {

// Inputs for tanh: a dense sweep of [-10, 10], the polynomial's edge at 0.55 from both sides, tiny and huge values.
std::vector<float> tanh_inputs() {
    std::vector<float> x;
    for (int i = -200000; i <= 200000; ++i) x.push_back(float(i) * 5e-5f);
    for (float e : {0.55f, -0.55f}) {
        float v = e;
        for (int k = 0; k < 64; ++k) x.push_back(v = std::nextafter(v, 0.0f));
        v = e;
        for (int k = 0; k < 64; ++k) x.push_back(v = std::nextafter(v, 2.0f * e));
    }
    for (float v : {1e-3f, 1e-8f, 1e-30f, 1e-38f, 1e-45f, 9.0f, 20.0f, 88.8f, 1e30f, 3.4e38f})
        for (float s : {1.0f, -1.0f}) x.push_back(s * v);
    return x;
}

}  // namespace

// Outside the harness: an ulp bound over a dense sweep, signs and saturation.
TEST_CASE("tanh (activation.cl's exp + polynomial form) is within 2 ulp of float64 and saturates to exactly 1",
          "[elementwise][extremes]") {
    // The kernels' own tanh (PoCL's built-in ran one value at a time, ~9x slower in the GEMM epilogue). Measured on
    // PoCL: 1.51 ulp at worst; OpenCL 1.2 allows the built-in 5. 2 ulp flags a wrong coefficient or branch limit.
    auto& c = test::ctx();
    Elementwise ew(c);
    const std::vector<float> x = tanh_inputs();
    Buffer b = test::upload(x);
    ew.activate(c, View{b.get(), 0, {1, 1, int(x.size())}}, Act::tanh());
    const std::vector<float> y = test::download(b, x.size());
    std::vector<double> want(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        INFO("tanh(" << x[i] << ") = " << y[i]);
        want[i] = std::tanh(double(x[i]));
        REQUIRE(std::abs(y[i]) <= 1.0f);
        if (x[i] != 0.0f) CHECK(std::signbit(y[i]) == std::signbit(x[i]));
    }
    const double worst = test::check_close(y, want, test::tol::tanh_ulp()).ratio * 2.0;
    const float inf = std::numeric_limits<float>::infinity();
    Buffer s = test::upload({inf, -inf, std::numeric_limits<float>::quiet_NaN(), 0.0f, -0.0f, 3.4e38f});
    ew.activate(c, View{s.get(), 0, {1, 1, 6}}, Act::tanh());
    const std::vector<float> z = test::download(s, 6);
    CHECK(z[0] == 1.0f);
    CHECK(z[1] == -1.0f);
    CHECK(std::isnan(z[2]));
    CHECK((z[3] == 0.0f && !std::signbit(z[3])));
    CHECK((z[4] == 0.0f && std::signbit(z[4])));
    CHECK(z[5] == 1.0f);
    WARN("tanh: worst " << worst << " ulp over " << x.size() << " values");
}

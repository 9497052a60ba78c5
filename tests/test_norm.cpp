// Per-image batch norm (ops/norm.hpp) beyond the op harness's rows (BatchNormPerImage::enqueue, every form at odd
// sizes against the two-pass double reference): the launch forms against each other, and the numerical extremes
// (zero variance, 1x1 spatial, large offsets, HDR values).
#include <algorithm>
#include <catch2/catch.hpp>

#include "ops/norm.hpp"
#include "reference.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

// A constant channel (zero variance) normalizes to beta: its float mean is the value itself (64 equal values sum
// exactly; one value is its own mean), so x - mean is 0 and gamma * 0 * rstd + beta = beta.
const test::Tol kConstantChannel = test::Tol::absolute(1e-6, "(x - mean) rstd gamma + beta with x = mean");

// Runs both reductions (contiguous and interleaved work-item ranges), each in two launches and in one
// (channel_norm), and the one-work-item-per-channel form; requires the reductions to agree, the one-launch form to
// give the same values exactly and the serial form to agree within rounding.
using Form = BatchNormPerImage::Form;
std::vector<float> run_bn_with(bool chunked, Form form, const std::vector<float>& x, int C, int H, int W,
                               const std::vector<float>& g, const std::vector<float>& b, Act act) {
    auto& c = test::ctx();
    BatchNormPerImage bn(c, C, g, b, 1e-5f, act, chunked, form);
    Buffer xb = c.alloc((x.size() + 3) * sizeof(float), "x");
    c.write(xb, 3 * sizeof(float), x.size() * sizeof(float), x.data(), "x");
    Buffer sb = c.alloc((3 * C + 9) * sizeof(float), "stats");
    bn.enqueue(c, View{xb.get(), 3, {C, H, W}}, sb.get(), 9);
    return test::download(xb, x.size(), 3);
}

std::vector<float> run_bn(const std::vector<float>& x, int C, int H, int W, const std::vector<float>& g,
                          const std::vector<float>& b, Act act) {
    auto chunked = run_bn_with(true, Form::two_pass, x, C, H, W, g, b, act);
    auto interleaved = run_bn_with(false, Form::two_pass, x, C, H, W, g, b, act);
    test::check_close(chunked, interleaved, test::tol::short_sum());
    test::check_close(run_bn_with(true, Form::work_group, x, C, H, W, g, b, act), chunked, test::Tol::exact());
    test::check_close(run_bn_with(false, Form::work_group, x, C, H, W, g, b, act), interleaved, test::Tol::exact());
    test::check_close(run_bn_with(true, Form::serial, x, C, H, W, g, b, act), chunked, test::tol::short_sum());
    return chunked;
}

}  // namespace

// Outside the harness: the launch forms against each other bit for bit, and no activation.
TEST_CASE("per-image batch norm matches a two-pass double reference", "[norm][oclgrind]") {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> C(1, 9), S(1, 37);
    for (int trial = 0; trial < 15; ++trial) {
        const int c = C(rng), h = S(rng), w = S(rng);
        auto x = test::random_vector(std::size_t(c) * h * w, rng, -3.0f, 5.0f);
        auto g = test::random_vector(c, rng, 0.5f, 1.5f), b = test::random_vector(c, rng);
        const Act act = trial % 2 ? Act::leaky(0.2f) : Act::none();
        auto y = run_bn(x, c, h, w, g, b, act);
        auto r = ref::batch_norm_per_image(x, c, h * w, g, b, 1e-5, int(act.kind), 0.2);
        INFO("C" << c << " " << h << "x" << w);
        test::check_close(y, r, test::tol::short_sum());
    }
}

// Outside the harness: extremes (zero variance, 1x1 planes, large offsets, HDR values).
TEST_CASE("per-image batch norm at the extremes stays finite and accurate", "[norm][extremes][oclgrind]") {
    std::mt19937 rng(9);
    const std::vector<float> g = {1.3f, 0.7f, 1.0f}, b = {0.25f, -0.5f, 0.1f};
    SECTION("zero variance: a constant channel normalizes to beta, not NaN") {
        std::vector<float> x(3 * 64, 0.0f);
        for (int i = 0; i < 64; ++i) { x[i] = 7.5f; x[64 + i] = -65504.0f; x[128 + i] = 0.0f; }
        auto y = run_bn(x, 3, 8, 8, g, b, Act::none());
        std::vector<float> beta(3 * 64);
        for (int i = 0; i < 64; ++i) { beta[i] = b[0]; beta[64 + i] = b[1]; beta[128 + i] = b[2]; }
        test::check_close(y, beta, kConstantChannel);
    }
    SECTION("1x1 spatial (the U-Net's innermost level at 256x256)") {
        std::vector<float> x = {3.0f, -1e6f, 42.0f};
        auto y = run_bn(x, 3, 1, 1, g, b, Act::none());
        test::check_close(y, b, kConstantChannel);
    }
    SECTION("large offset, small spread: no catastrophic cancellation") {
        // E[x^2] - E[x]^2 in fp32 would lose every digit here (1e4^2 = 1e8 vs a variance of ~1).
        const int hw = 4096;
        std::vector<float> x(3 * hw);
        std::normal_distribution<float> n(0.0f, 1.0f);
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < hw; ++i) x[c * hw + i] = (c == 0 ? 1e4f : c == 1 ? 65504.0f : -3e5f) + n(rng);
        auto y = run_bn(x, 3, 64, 64, g, b, Act::none());
        auto r = ref::batch_norm_per_image(x, 3, hw, g, b, 1e-5, 0, 0);
        // An fp32 mean alone would be off by up to half an ulp of 3e5 (0.016 = 1.6% of the spread).
        test::check_close(y, r, test::tol::accumulation());
    }
    SECTION("HDR values far above 65504 with a wide spread") {
        auto x = test::random_vector(2 * 1000, rng, 0.0f, 1e7f);
        auto y = run_bn(x, 2, 25, 40, {1.0f, 2.0f}, {0.0f, 1.0f}, Act::none());
        auto r = ref::batch_norm_per_image(x, 2, 1000, {1.0f, 2.0f}, {0.0f, 1.0f}, 1e-5, 0, 0);
        test::check_close(y, r, test::tol::short_sum());
    }
}

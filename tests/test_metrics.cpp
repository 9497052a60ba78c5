// MSE / PSNR / SSIM: parity with scikit-image (the oracle; tests/parity/ssim_reference.py) and with a naive
// double-precision transcription of skimage's definition (full 2-D window, reflect padding, crop, mean).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <utility>

#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

// scikit-image's results, generated once per build tree.
fs::path reference_dir() { return ngi::test::python_oracle_data("ssim_reference.py", "metrics_ref"); }

// scipy.ndimage mode 'reflect' (d c b a | a b c d | d c b a), valid for any offset.
int reflect(int i, int n) {
    const int period = 2 * n;
    i %= period;
    if (i < 0) i += period;
    return i < n ? i : period - 1 - i;
}

// skimage's structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False), literally:
// the SSIM map of every pixel with reflect padding, then the mean over the map cropped by 5 pixels, per channel.
double naive_ssim(const ngi::Image& a, const ngi::Image& b, double range) {
    const int r = 5;
    double w1[2 * r + 1], wsum = 0;
    for (int i = -r; i <= r; ++i) wsum += w1[i + r] = std::exp(-0.5 * i * i / (1.5 * 1.5));
    for (double& v : w1) v /= wsum;
    const double c1 = (0.01 * range) * (0.01 * range), c2 = (0.03 * range) * (0.03 * range);
    double total = 0;
    for (int c = 0; c < a.channels; ++c) {
        double sum = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                double mx = 0, my = 0, mxx = 0, myy = 0, mxy = 0;
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx) {
                        const double w = w1[dy + r] * w1[dx + r];
                        const int yy = reflect(y + dy, a.height), xx = reflect(x + dx, a.width);
                        const double u = a.at(c, yy, xx), v = b.at(c, yy, xx);
                        mx += w * u; my += w * v; mxx += w * u * u; myy += w * v * v; mxy += w * u * v;
                    }
                const double s = ((2 * mx * my + c1) * (2 * (mxy - mx * my) + c2)) /
                                 ((mx * mx + my * my + c1) * (mxx - mx * mx + myy - my * my + c2));
                if (y >= r && y < a.height - r && x >= r && x < a.width - r) sum += s;
            }
        total += sum / (double(a.width - 2 * r) * (a.height - 2 * r));
    }
    return total / a.channels;
}

ngi::Image random_image(int w, int h, int c, std::mt19937& rng, float lo = 0.0f, float hi = 1.0f) {
    ngi::Image img(w, h, c);
    img.data = ngi::test::random_vector(img.data.size(), rng, lo, hi);
    return img;
}

}  // namespace

TEST_CASE("MSE, PSNR and SSIM match scikit-image", "[metrics][parity]") {
    const fs::path dir = reference_dir();
    nlohmann::json cases;
    std::ifstream(dir / "cases.json") >> cases;
    REQUIRE(cases.size() >= 20);
    double worst_ssim = 0, worst_mse_rel = 0, worst_psnr = 0;
    std::string worst_case;
    for (const auto& c : cases) {
        const std::string name = c["name"];
        INFO(name);
        const ngi::Image a = ngi::read_image((dir / c["a"].get<std::string>()).string());
        const ngi::Image b = ngi::read_image((dir / c["b"].get<std::string>()).string());
        const double range = c["data_range"];
        const ngi::ImageMetrics m = ngi::compare_images(ngi::test::device(), a, b, range);
        const double ssim_err = std::abs(m.ssim - c["ssim"].get<double>());
        const double ref_mse = c["mse"];
        const double mse_rel = ref_mse == 0 ? m.mse : std::abs(m.mse - ref_mse) / ref_mse;
        // Tolerances: ngi works in float32 (skimage here in float64 on the same float32 values). SSIM is a mean
        // of ratios of O(1); observed differences are ~1e-7, and a wrong tap, weight, constant or crop moves it by
        // 1e-3 or more. MSE: float32 differences and squares, summed with Kahan + double partials.
        CHECK(ssim_err < 2e-6);
        CHECK(mse_rel < 1e-6);
        if (c["psnr"].is_null()) {
            CHECK(m.mse == 0.0);
            CHECK(std::isinf(m.psnr));
            CHECK(m.ssim == Approx(1.0).margin(1e-6));
        } else {
            const double psnr_err = std::abs(m.psnr - c["psnr"].get<double>());
            CHECK(psnr_err < 1e-5);
            worst_psnr = std::max(worst_psnr, psnr_err);
        }
        if (ssim_err > worst_ssim) { worst_ssim = ssim_err; worst_case = name; }
        worst_mse_rel = std::max(worst_mse_rel, mse_rel);
    }
    WARN("largest |ngi - skimage|: SSIM " << worst_ssim << " (" << worst_case << "), MSE relative " << worst_mse_rel
                                          << ", PSNR " << worst_psnr << " dB over " << cases.size() << " cases");
}

TEST_CASE("SSIM matches a naive double-precision transcription of its definition", "[metrics]") {
    std::mt19937 rng(7);
    const int sizes[][3] = {{11, 11, 1}, {12, 19, 3}, {16, 16, 1}, {17, 33, 2}, {48, 31, 3}, {70, 21, 1}};
    for (const auto& s : sizes) {
        const ngi::Image a = random_image(s[0], s[1], s[2], rng);
        ngi::Image b = a;
        std::normal_distribution<float> noise(0.0f, 0.2f);
        for (float& v : b.data) v += noise(rng);
        for (const double range : {1.0, 2.5}) {
            INFO(s[0] << "x" << s[1] << "x" << s[2] << " range " << range);
            CHECK(ngi::ssim(ngi::test::device(), a, b, range) == Approx(naive_ssim(a, b, range)).margin(2e-6));
        }
    }
}

TEST_CASE("metrics: identities and symmetry", "[metrics]") {
    std::mt19937 rng(11);
    const ngi::Image a = random_image(40, 27, 3, rng), b = random_image(40, 27, 3, rng);
    auto& dev = ngi::test::device();
    const ngi::ImageMetrics same = ngi::compare_images(dev, a, a);
    CHECK(same.mse == 0.0);
    CHECK(std::isinf(same.psnr));
    CHECK(same.psnr > 0);
    CHECK(same.ssim == Approx(1.0).margin(1e-6));
    CHECK(ngi::ssim(dev, a, b) == Approx(ngi::ssim(dev, b, a)).margin(1e-7));
    // A constant offset d gives MSE d^2 exactly in exact arithmetic.
    ngi::Image shifted = a;
    for (float& v : shifted.data) v += 0.25f;
    CHECK(ngi::mse(dev, a, shifted) == Approx(0.0625).epsilon(1e-6));
    CHECK(ngi::psnr_from_mse(0.01, 1.0) == Approx(20.0));
    CHECK(ngi::psnr_from_mse(0.01, 10.0) == Approx(40.0));
    const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, 2.0);
    CHECK(m.mse == Approx(ngi::mse(dev, a, b)).epsilon(1e-12));
    CHECK(m.psnr == Approx(ngi::psnr_from_mse(m.mse, 2.0)).epsilon(1e-12));
    CHECK(m.ssim == Approx(ngi::ssim(dev, a, b, 2.0)).epsilon(1e-12));
}

TEST_CASE("metrics: bad input is an InputError that says what is wrong", "[metrics]") {
    std::mt19937 rng(3);
    auto& dev = ngi::test::device();
    const ngi::Image a = random_image(20, 20, 3, rng);
    using Catch::Matchers::Contains;
    CHECK_THROWS_WITH(ngi::compare_images(dev, a, random_image(20, 21, 3, rng)), Contains("differ in size"));
    CHECK_THROWS_WITH(ngi::compare_images(dev, a, random_image(20, 20, 1, rng)), Contains("20x20x3 vs 20x20x1"));
    CHECK_THROWS_WITH(ngi::ssim(dev, random_image(10, 30, 1, rng), random_image(10, 30, 1, rng)),
                      Contains("at least 11x11"));
    CHECK_NOTHROW(ngi::mse(dev, random_image(3, 2, 1, rng), random_image(3, 2, 1, rng)));  // MSE has no window
    ngi::Image nan = a;
    nan.data[5] = std::numeric_limits<float>::quiet_NaN();
    nan.data[9] = std::numeric_limits<float>::infinity();
    CHECK_THROWS_WITH(ngi::compare_images(dev, a, nan), Contains("second image has 2 NaN/Inf"));
    ngi::Image huge = a;
    huge.data[0] = std::numeric_limits<float>::max();  // read_frame's saturated light
    CHECK_THROWS_WITH(ngi::compare_images(dev, huge, a), Contains("first image has 1 values beyond"));
    // compare_images accepts data_range 0 (reported as undefined metrics, see below); ssim() alone does not.
    CHECK_THROWS_WITH(ngi::ssim(dev, a, a, 0.0), Contains("data_range must be finite and > 0"));
    CHECK_THROWS_WITH(ngi::compare_images(dev, a, a, -1.0), Contains("data_range must be finite and >= 0"));
    CHECK_THROWS_AS(ngi::compare_images(dev, a, a, std::nan("")), ngi::InputError);
    CHECK_THROWS_AS(ngi::compare_images(dev, a, a, std::numeric_limits<double>::infinity()), ngi::InputError);
}

namespace {

ngi::Image constant_image(int w, int h, int c, float v) {
    ngi::Image img(w, h, c);
    std::fill(img.data.begin(), img.data.end(), v);
    return img;
}

}  // namespace

TEST_CASE("metrics: all-zero and constant images (an empty or pure-sky reference)", "[metrics]") {
    auto& dev = ngi::test::device();
    std::mt19937 rng(5);
    const ngi::Image zero = constant_image(24, 20, 3, 0.0f), sky = constant_image(24, 20, 3, 0.37f);
    SECTION("identical images: PSNR +infinity with a note, SSIM exactly 1, for any data range") {
        for (const ngi::Image* im : {&zero, &sky})
            for (const double range : {1.0, 0.37, 0.0}) {
                INFO("value " << im->data[0] << " range " << range);
                const ngi::ImageMetrics m = ngi::compare_images(dev, *im, *im, range);
                CHECK(m.mse == 0.0);
                CHECK(std::isinf(m.psnr));
                CHECK(m.psnr > 0);
                CHECK_THAT(m.psnr_note, Catch::Matchers::Contains("identical"));
                CHECK(m.ssim == 1.0);
                CHECK(m.ssim_note.empty());
                // The kernel agrees where Wang's constants are > 0: (C1 C2) / (C1 C2) in every constant window.
                if (range > 0) CHECK(ngi::ssim(dev, *im, *im, range) == Approx(1.0).margin(1e-6));
            }
    }
    SECTION("a constant reference with data_range > 0: defined, and as the definition says") {
        ngi::Image noisy = sky;
        std::normal_distribution<float> noise(0.0f, 0.05f);
        for (float& v : noisy.data) v += noise(rng);
        const ngi::Image bright = constant_image(24, 20, 3, 0.8f);
        using Pair = std::pair<const ngi::Image*, const ngi::Image*>;
        for (const auto& [test, ref] : {Pair{&noisy, &sky}, Pair{&noisy, &zero}, Pair{&bright, &sky}, Pair{&sky, &zero}}) {
            const ngi::ImageMetrics m = ngi::compare_images(dev, *test, *ref, 1.0);
            INFO("test " << test->data[0] << " ref " << ref->data[0]);
            CHECK(std::isfinite(m.psnr));
            CHECK(m.psnr_note.empty());
            CHECK(m.ssim_note.empty());
            CHECK(m.ssim == Approx(naive_ssim(*test, *ref, 1.0)).margin(2e-6));
        }
        // Two different constants: only the luminance term is left, (2 a b + C1) / (a^2 + b^2 + C1).
        const double c1 = 0.01 * 0.01;
        CHECK(ngi::compare_images(dev, bright, sky).ssim ==
              Approx((2 * 0.8 * 0.37 + c1) / (0.8 * 0.8 + 0.37 * 0.37 + c1)).epsilon(1e-6));
    }
    SECTION("data_range 0 (the maximum of an all-zero reference): PSNR and SSIM undefined, with the reason") {
        const ngi::Image test = random_image(24, 20, 3, rng);
        const ngi::ImageMetrics m = ngi::compare_images(dev, test, zero, 0.0);
        CHECK(m.mse == Approx(ngi::mse(dev, test, zero)).epsilon(1e-12));
        CHECK(m.mse > 0);
        CHECK(std::isnan(m.psnr));
        CHECK_THAT(m.psnr_note, Catch::Matchers::Contains("data_range is 0"));
        CHECK(std::isnan(m.ssim));
        CHECK_THAT(m.ssim_note, Catch::Matchers::Contains("C1 = C2 = 0"));
        CHECK(std::isnan(ngi::psnr_from_mse(0.5, 0.0)));
        CHECK(std::isinf(ngi::psnr_from_mse(0.0, 0.0)));
    }
}

TEST_CASE("metrics: 1x1 and other images smaller than the SSIM window", "[metrics]") {
    auto& dev = ngi::test::device();
    std::mt19937 rng(13);
    ngi::Image a(1, 1, 1), b(1, 1, 1);
    a.data = {0.75f};
    b.data = {0.25f};
    const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, 2.0);
    CHECK(m.mse == 0.25);
    CHECK(m.psnr == Approx(10 * std::log10(4.0 / 0.25)).epsilon(1e-12));
    CHECK(m.psnr_note.empty());
    CHECK(std::isnan(m.ssim));
    CHECK_THAT(m.ssim_note, Catch::Matchers::Contains("at least 11x11") && Catch::Matchers::Contains("got 1x1"));
    const ngi::ImageMetrics same = ngi::compare_images(dev, a, a);
    CHECK(std::isinf(same.psnr));
    CHECK(std::isnan(same.ssim));  // no window fits: not even identical images have an SSIM
    for (const auto& [w, h] : {std::pair{10, 30}, std::pair{30, 10}, std::pair{11, 11}}) {
        const ngi::ImageMetrics r = ngi::compare_images(dev, random_image(w, h, 2, rng), random_image(w, h, 2, rng));
        INFO(w << "x" << h);
        CHECK(std::isnan(r.ssim) == (w < 11 || h < 11));
        CHECK(std::isfinite(r.psnr));
    }
    CHECK_THROWS_WITH(ngi::ssim(dev, a, b), Catch::Matchers::Contains("at least 11x11"));
}

TEST_CASE("metrics: HDR values at and beyond the largest half float (65504)", "[metrics]") {
    auto& dev = ngi::test::device();
    std::mt19937 rng(17);
    for (const float scale : {65504.0f, 1.0e6f, 1.0e9f, 1.0e12f}) {
        ngi::Image ref(32, 29, 3), test(32, 29, 3);
        std::lognormal_distribution<float> radiance(0.0f, 1.0f);
        std::normal_distribution<float> noise(0.0f, 0.05f);
        for (std::size_t i = 0; i < ref.data.size(); ++i) {
            ref.data[i] = scale * radiance(rng);
            test.data[i] = ref.data[i] * std::exp(noise(rng));
        }
        double peak = 0, se = 0;
        for (std::size_t i = 0; i < ref.data.size(); ++i) {
            peak = std::max(peak, double(ref.data[i]));
            se += (double(test.data[i]) - ref.data[i]) * (double(test.data[i]) - ref.data[i]);
        }
        const double mse = se / double(ref.data.size());
        for (const double range : {peak, 1.0}) {
            INFO("scale " << scale << " range " << range);
            const ngi::ImageMetrics m = ngi::compare_images(dev, test, ref, range);
            CHECK(m.mse == Approx(mse).epsilon(1e-5));
            CHECK(m.psnr == Approx(10 * std::log10(range * range / mse)).margin(1e-4));
            REQUIRE(std::isfinite(m.ssim));
            CHECK(m.ssim == Approx(naive_ssim(test, ref, range)).margin(2e-6));
        }
    }
}

TEST_CASE("metrics refuse a data range whose SSIM constants are not float32 numbers", "[metrics]") {
    // --range 1e38 gave "ssim": null with an empty note (C1 = (0.01 R)^2 was Inf in the kernel); --range 1e-45 gave
    // PSNR -892 dB. A positive range must lie in [1e-15, 1e15], the bound the values themselves have.
    using Catch::Matchers::Contains;
    auto& dev = ngi::test::device();
    ngi::Image a(16, 16, 1), b(16, 16, 1);
    for (std::size_t i = 0; i < a.data.size(); ++i) {
        a.data[i] = float(i % 5) * 0.1f;
        b.data[i] = float(i % 3) * 0.1f;
    }
    for (double r : {1e38, 1e16, 1e-16, 1e-45}) {
        INFO(r);
        // compare_images (what ngi lightmap scores with) reports them undefined, saying why; ssim() refuses them.
        const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, r);
        CHECK(std::isnan(m.psnr));
        CHECK(std::isnan(m.ssim));
        CHECK_THAT(m.psnr_note, Contains("is outside [1e-15, 1e15]") && Contains("PSNR is not reported"));
        CHECK_THAT(m.ssim_note, Contains("is outside [1e-15, 1e15]") && Contains("SSIM is not reported"));
        CHECK_THROWS_WITH(ngi::ssim(dev, a, b, r), Contains("data_range must be in [1e-15, 1e15]"));
        const ngi::ImageMetrics same = ngi::compare_images(dev, a, a, r);  // identical images: as for every range
        CHECK(std::isinf(same.psnr));
        CHECK(same.ssim == 1.0);
    }
    for (double r : {1e15, 1e-15, 1.0}) {
        INFO(r);
        const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, r);
        CHECK(std::isfinite(m.psnr));
        CHECK(std::isfinite(m.ssim));
    }
}

TEST_CASE("metrics: to_json writes null and a note where JSON has no number", "[metrics]") {
    auto& dev = ngi::test::device();
    std::mt19937 rng(19);
    const ngi::Image a = random_image(16, 16, 1, rng), b = random_image(16, 16, 1, rng);
    const ngi::ImageMetrics m = ngi::compare_images(dev, a, b);
    const nlohmann::json j = nlohmann::json::parse(ngi::to_json(m));
    CHECK(j.size() == 3);  // no notes for finite values
    CHECK(j["mse"].get<double>() == m.mse);  // 17 digits: the same double back
    CHECK(j["psnr"].get<double>() == m.psnr);
    CHECK(j["ssim"].get<double>() == m.ssim);
    const nlohmann::json same = nlohmann::json::parse(ngi::to_json(ngi::compare_images(dev, a, a)));
    CHECK(same["mse"].get<double>() == 0.0);
    CHECK(same["psnr"].is_null());
    CHECK(same["psnr_note"].get<std::string>().find("+infinity") != std::string::npos);
    CHECK(same["ssim"].get<double>() == 1.0);
    CHECK_FALSE(same.contains("ssim_note"));
    const nlohmann::json zero = nlohmann::json::parse(ngi::to_json(ngi::compare_images(dev, a, b, 0.0)));
    CHECK(zero["psnr"].is_null());
    CHECK(zero["ssim"].is_null());
    CHECK(zero.contains("psnr_note"));
    CHECK(zero.contains("ssim_note"));
    ngi::ImageMetrics quoted;
    quoted.psnr = std::nan("");
    quoted.psnr_note = "a \"quoted\" \\ note\n";
    CHECK(nlohmann::json::parse(ngi::to_json(quoted))["psnr_note"].get<std::string>() == quoted.psnr_note);
}

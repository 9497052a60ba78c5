// indirect_share (host/src/pipeline/light_share.cpp): the per-frame guard's signal, against a plain double sum.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cfloat>
#include <limits>
#include <random>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"

using namespace ngi;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN(), kInf = std::numeric_limits<float>::infinity();

// A value in [0, hi), or now and then one the guard must sanitize: NaN, +-Inf, a negative, a huge finite value.
float hostile(std::mt19937& rng, float hi) {
    std::uniform_real_distribution<float> u(0.0f, hi);
    switch (std::uniform_int_distribution<int>(0, 19)(rng)) {
        case 0: return kNaN;
        case 1: return kInf;
        case 2: return -kInf;
        case 3: return -u(rng);
        case 4: return 1e30f;
        default: return u(rng);
    }
}

Image random_image(int n, std::mt19937& rng, float hi) {
    Image im(n, n, 3);
    for (auto& v : im.data) v = hostile(rng, hi);
    return im;
}

// Only the front face: indirect_share reads nothing else.
Frame front_frame(int n, std::mt19937& rng, bool with_emission, bool with_env) {
    Frame fr;
    fr.n = n;
    fr.get(Feature::Albedo, Face::Front) = random_image(n, rng, 1.5f);  // > 1 too: clamped
    fr.get(Feature::Direct, Face::Front) = random_image(n, rng, 3.0f);
    if (with_emission) fr.get(Feature::Emission, Face::Front) = random_image(n, rng, 0.5f);
    if (with_env) fr.get(Feature::Env, Face::Front) = random_image(n, rng, 0.5f);
    return fr;
}

// The definition written out plainly, in double throughout (docs/CONVENTIONS.md section 17).
double naive_share(const Frame& fr, const Image& lm) {
    const double w[3] = {0.2126, 0.7152, 0.0722};
    auto clean = [](float v) -> double {
        if (std::isnan(v) || v < 0) return 0.0;
        return std::isinf(v) ? double(FLT_MAX) : double(v);
    };
    const Image &alb = fr.get(Feature::Albedo, Face::Front), &dir = fr.get(Feature::Direct, Face::Front),
                &em = fr.get(Feature::Emission, Face::Front), &env = fr.get(Feature::Env, Face::Front);
    double added = 0, total = 0;
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < fr.n; ++y)
            for (int x = 0; x < fr.n; ++x) {
                const float av = alb.at(c, y, x);
                const double a = std::isnan(av) ? 0.0 : std::clamp(double(av), 0.0, 1.0);
                const double l = clean(lm.at(c, y, x));
                double f = l * a;
                if (!em.data.empty()) f = std::min(f + clean(em.at(c, y, x)), double(FLT_MAX));
                if (!env.data.empty()) f = std::min(f + clean(env.at(c, y, x)), double(FLT_MAX));
                added += w[c] * a * std::max(l - clean(dir.at(c, y, x)), 0.0);
                total += w[c] * f;
            }
    return total > 0 ? std::clamp(added / total, 0.0, 1.0) : 0.0;
}

}  // namespace

TEST_CASE("indirect_share: random frames of odd sizes with hostile values, against a double reference",
          "[pipeline][indirect_share]") {
    std::mt19937 rng(25);
    for (int n : {1, 3, 7, 17})
        for (int terms = 0; terms < 4; ++terms) {
            const Frame fr = front_frame(n, rng, terms & 1, terms & 2);
            // Finite lightmaps (the share lies strictly inside (0, 1)) and hostile ones (+Inf lightmap values make
            // FLT_MAX-sized terms: the double sums must stay finite).
            for (bool finite : {true, false}) {
                Image lm(n, n, 3);
                std::uniform_real_distribution<float> u(0.0f, 6.0f);
                for (auto& v : lm.data) v = finite ? u(rng) : hostile(rng, 6.0f);
                const double s = indirect_share(fr, lm);
                INFO("n " << n << ", emission " << (terms & 1) << ", env " << (terms & 2) << ", finite " << finite);
                CHECK(s == Approx(naive_share(fr, lm)).epsilon(1e-6).margin(1e-12));
                CHECK(s >= 0.0);
                CHECK(s <= 1.0);
            }
        }
}

TEST_CASE("indirect_share: nothing lit, lightmap = direct light, all indirect", "[pipeline][indirect_share]") {
    std::mt19937 rng(26);
    const int n = 5;
    Frame fr = front_frame(n, rng, true, true);

    // An all-zero frame and lightmap: nothing lit, share 0 (not NaN).
    Frame dark;
    dark.n = n;
    dark.get(Feature::Albedo, Face::Front) = Image(n, n, 3);
    dark.get(Feature::Direct, Face::Front) = Image(n, n, 3);
    CHECK(indirect_share(dark, Image(n, n, 3)) == 0.0);

    // The lightmap is the direct light itself (what a guard fallback writes): nothing added, whatever the frame
    // holds; the same with the raw (unsanitized) direct light and with its sanitized copy.
    const Image& direct = fr.get(Feature::Direct, Face::Front);
    CHECK(indirect_share(fr, direct) == 0.0);
    Image clean = direct;
    for (auto& v : clean.data) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX);
    CHECK(indirect_share(fr, clean) == 0.0);
    // Darker than direct light: nothing added either (max(., 0)).
    Image dim = clean;
    for (auto& v : dim.data) v *= 0.5f;
    CHECK(indirect_share(fr, dim) == 0.0);

    // No direct light, no emission or env, albedo 1: the whole image is what the lightmap adds.
    Frame all;
    all.n = n;
    all.get(Feature::Albedo, Face::Front) = Image(n, n, 3, 1.0f);
    all.get(Feature::Direct, Face::Front) = Image(n, n, 3);
    CHECK(indirect_share(all, random_image(n, rng, 2.0f)) == Approx(1.0).epsilon(1e-12));
    // Direct light 1, lightmap 3 everywhere: two thirds added.
    all.get(Feature::Direct, Face::Front) = Image(n, n, 3, 1.0f);
    CHECK(indirect_share(all, Image(n, n, 3, 3.0f)) == Approx(2.0 / 3.0).epsilon(1e-12));
}

TEST_CASE("indirect_share: bad inputs name the operation and what is wrong", "[pipeline][indirect_share]") {
    std::mt19937 rng(27);
    const Frame fr = front_frame(4, rng, false, false);
    auto throws_with = [&](const Frame& f, const Image& lm, const std::string& what) {
        INFO(what);
        CHECK_THROWS_AS(indirect_share(f, lm), InputError);
        CHECK_THROWS_WITH(indirect_share(f, lm),
                          Catch::Matchers::Contains("indirect_share: ") && Catch::Matchers::Contains(what));
    };
    throws_with(fr, Image(5, 4, 3), "the lightmap is 5x4x3, expected 4x4x3");
    throws_with(fr, Image(4, 4, 1), "the lightmap is 4x4x1");
    throws_with(fr, Image(), "the lightmap is 0x0x0");
    Frame no_albedo = fr;
    no_albedo.get(Feature::Albedo, Face::Front) = Image();
    throws_with(no_albedo, Image(4, 4, 3), "no front albedo");
    Frame no_direct = fr;
    no_direct.get(Feature::Direct, Face::Front) = Image();
    throws_with(no_direct, Image(4, 4, 3), "no front direct");
    Frame small_env = fr;
    small_env.get(Feature::Env, Face::Front) = Image(2, 2, 3);
    throws_with(small_env, Image(4, 4, 3), "front env is 2x2x3, expected 4x4x3");
}

// outside_light_share (host/src/pipeline/light_share.cpp): the per-frame switch's measure, against a direct sum.
#include <catch2/catch.hpp>

#include <cfloat>
#include <limits>
#include <random>

#include "ngi/pipeline.hpp"

using namespace ngi;

namespace {

Frame lit_frame(int n, std::mt19937& rng, bool with_emission_env) {
    Frame fr;
    fr.n = n;
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    for (int f = 0; f < kFaceCount; ++f)
        for (int k = 0; k < kFeatureCount; ++k) {
            const Feature feat = Feature(k);
            if (!with_emission_env && (feat == Feature::Emission || feat == Feature::Env)) continue;
            Image im(n, n, feature_channels(feat));
            for (auto& v : im.data) v = u(rng);
            fr.get(feat, Face(f)) = im;
        }
    return fr;
}

// The same measure, written out plainly: luminance of direct + emission + env, sanitized per term.
double naive_share(const Frame& fr) {
    const double w[3] = {0.2126, 0.7152, 0.0722};
    double total = 0, outside = 0;
    for (int f = 0; f < kFaceCount; ++f) {
        double s = 0;
        for (Feature feat : {Feature::Direct, Feature::Emission, Feature::Env}) {
            const Image& im = fr.get(feat, Face(f));
            for (int c = 0; c < im.channels; ++c)
                for (int y = 0; y < im.height; ++y)
                    for (int x = 0; x < im.width; ++x) {
                        float v = im.at(c, y, x);
                        if (std::isnan(v) || v < 0) v = 0;
                        if (std::isinf(v)) v = FLT_MAX;
                        s += w[c] * v;
                    }
        }
        total += s;
        if (f != int(Face::Front)) outside += s;
    }
    return total > 0 ? outside / total : 0;
}

}  // namespace

TEST_CASE("outside_light_share: random frames, odd sizes, with and without emission/env", "[pipeline][light_share]") {
    std::mt19937 rng(5);
    for (int n : {1, 3, 7, 16})
        for (bool full : {true, false}) {
            const Frame fr = lit_frame(n, rng, full);
            const double s = outside_light_share(fr);
            CHECK(s == Approx(naive_share(fr)).epsilon(1e-12));
            CHECK(s > 0.5);  // five faces of six, random light
            CHECK(s < 1.0);
        }
}

TEST_CASE("outside_light_share: light only in front, only behind, none, hostile values", "[pipeline][light_share]") {
    std::mt19937 rng(6);
    Frame fr = lit_frame(5, rng, true);
    auto clear_faces = [&](auto keep) {
        for (int f = 0; f < kFaceCount; ++f)
            if (!keep(Face(f)))
                for (Feature feat : {Feature::Direct, Feature::Emission, Feature::Env})
                    for (auto& v : fr.get(feat, Face(f)).data) v = 0;
    };
    const Frame front = fr;  // the fully lit frame
    clear_faces([](Face f) { return f == Face::Front; });
    CHECK(outside_light_share(fr) == 0.0);
    fr = front;
    clear_faces([](Face f) { return f == Face::Back; });
    CHECK(outside_light_share(fr) == 1.0);
    clear_faces([](Face) { return false; });
    CHECK(outside_light_share(fr) == 0.0);  // no light at all: nothing outside either

    // NaN and negative values count nothing; +Inf counts FLT_MAX (HDR saturation, like the network input); the
    // double sums neither overflow nor turn into NaN.
    fr = front;
    fr.get(Feature::Direct, Face::Left).data[0] = std::numeric_limits<float>::quiet_NaN();
    fr.get(Feature::Env, Face::Up).data[3] = -1e30f;
    const double clean = outside_light_share(fr);
    CHECK(clean == Approx(naive_share(fr)).epsilon(1e-12));
    fr.get(Feature::Emission, Face::Back).data[1] = std::numeric_limits<float>::infinity();
    fr.get(Feature::Emission, Face::Front).data[1] = 70000.0f;  // beyond the half range: still a finite light
    const double s = outside_light_share(fr);
    CHECK(std::isfinite(s));
    CHECK(s > 0.999);  // FLT_MAX behind the camera dominates
}

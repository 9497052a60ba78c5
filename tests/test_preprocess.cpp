// Preprocessing and the network input (kernels/gbuffer.cl, host/src/pipeline/preprocess.cpp) against the
// naive reference: value rules, NaN/Inf sanitizing and counting, huge depths, HDR light, sky normals.
#include <catch2/catch.hpp>

#include <cfloat>
#include <cstring>
#include <limits>
#include <random>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "reference_pipeline.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

// Random plausible features on all six faces, then hostile values sprinkled over them.
Frame hostile_frame(int n, std::mt19937& rng, bool optional_terms) {
    Frame fr;
    fr.n = n;
    fr.look = {0.3f, -0.2f, -1.0f};
    fr.up = {0.1f, 1.0f, 0.2f};
    std::uniform_real_distribution<float> u(0, 1);
    for (int f = 0; f < kFaceCount; ++f) {
        auto rand_img = [&](int c, float lo, float hi) {
            Image im(n, n, c);
            im.data = test::random_vector(im.data.size(), rng, lo, hi);
            return im;
        };
        fr.get(Feature::Albedo, Face(f)) = rand_img(3, -0.1f, 1.1f);
        fr.get(Feature::Normal, Face(f)) = rand_img(3, -1.5f, 1.5f);
        fr.get(Feature::Depth, Face(f)) = rand_img(1, 0.0f, 1500.0f);
        fr.get(Feature::Direct, Face(f)) = rand_img(3, -0.1f, 20.0f);
        if (optional_terms) {
            fr.get(Feature::Emission, Face(f)) = rand_img(3, 0.0f, 5.0f);
            fr.get(Feature::Env, Face(f)) = rand_img(3, 0.0f, 2.0f);
        }
    }
    const float specials[] = {kNaN, kInf, -kInf, 0.0f, -0.0f, 65504.0f, 65505.0f, 1e30f, FLT_MAX, -FLT_MAX, 1e-7f};
    std::uniform_int_distribution<int> pick_special(0, int(std::size(specials)) - 1), pick_face(0, kFaceCount - 1);
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        for (int k = 0; k < 6 * n; ++k) {
            Image& im = fr.get(Feature(fi), Face(pick_face(rng)));
            if (im.data.empty()) continue;
            im.data[std::size_t(u(rng) * (im.data.size() - 1))] = specials[pick_special(rng)];
        }
    }
    // Sky normals (exactly zero, and nearly zero), huge normals, a whole zero-depth and a far-depth block.
    for (int f = 0; f < kFaceCount; ++f) {
        Image& nm = fr.get(Feature::Normal, Face(f));
        for (int c = 0; c < 3; ++c) {
            nm.at(c, 0, 0) = 0.0f;
            nm.at(c, 0, 1) = 1e-8f;
            nm.at(c, 1, 0) = c == 2 ? 0.0f : 1e30f;
        }
        Image& d = fr.get(Feature::Depth, Face(f));
        d.at(0, 1, 1) = 1e6f;
        d.at(0, 1, 2) = FLT_MAX;
        d.at(0, 1, 3) = 1000.0f;
        Image& l = fr.get(Feature::Direct, Face(f));
        l.at(0, 2, 2) = FLT_MAX;  // + emission/env: the sum must saturate, not overflow
        l.at(1, 2, 2) = 65504.0f;
        if (optional_terms) fr.get(Feature::Emission, Face(f)).at(0, 2, 2) = FLT_MAX;
    }
    return fr;
}

struct Expected {
    std::vector<float> planes;  // [10][faces][n][n], in [0, 1]
    PreprocessStats stats;
};

Expected reference(const Frame& fr, int faces, bool reinhard) {
    const int n = fr.n;
    const CameraCluster cl = CameraCluster::from_look_up(fr.look, fr.up);
    const float S[3][3] = {{cl.alpha.x, cl.alpha.y, cl.alpha.z},
                           {cl.beta.x, cl.beta.y, cl.beta.z},
                           {cl.gamma.x, cl.gamma.y, cl.gamma.z}};
    const std::size_t fp = std::size_t(n) * n, np = fp * faces;
    Expected e;
    e.planes.resize(10 * np);
    for (int f = 0; f < faces; ++f) {
        const bool has_e = !fr.get(Feature::Emission, Face(f)).data.empty();
        const bool has_v = !fr.get(Feature::Env, Face(f)).data.empty();
        for (std::size_t t = 0; t < fp; ++t) {
            float a[3], nm[3], di[3], em[3], ev[3];
            for (int c = 0; c < 3; ++c) {
                a[c] = fr.get(Feature::Albedo, Face(f)).data[c * fp + t];
                nm[c] = fr.get(Feature::Normal, Face(f)).data[c * fp + t];
                di[c] = fr.get(Feature::Direct, Face(f)).data[c * fp + t];
                if (has_e) em[c] = fr.get(Feature::Emission, Face(f)).data[c * fp + t];
                if (has_v) ev[c] = fr.get(Feature::Env, Face(f)).data[c * fp + t];
            }
            const ref::PreTexel o = ref::preprocess_texel(a, nm, fr.get(Feature::Depth, Face(f)).data[t], di,
                                                          has_e ? em : nullptr, has_v ? ev : nullptr, S, reinhard);
            const std::size_t p = f * fp + t;
            for (int c = 0; c < 3; ++c) {
                e.planes[c * np + p] = o.albedo[c];
                e.planes[(3 + c) * np + p] = o.normal[c];
                e.planes[(7 + c) * np + p] = o.lum[c];
            }
            e.planes[6 * np + p] = o.depth;
            for (int k = 0; k < 6; ++k) e.stats.nonfinite[k] += o.bad[k];
            e.stats.sky_normals += o.sky;
            e.stats.far_depths += o.far;
        }
    }
    return e;
}

void require_same_stats(const PreprocessStats& got, const PreprocessStats& want) {
    for (int k = 0; k < kFeatureCount; ++k) {
        INFO("feature " << feature_name(Feature(k)));
        REQUIRE(got.nonfinite[k] == want.nonfinite[k]);
    }
    REQUIRE(got.sky_normals == want.sky_normals);
    REQUIRE(got.far_depths == want.far_depths);
}

ModelConfig config(int input_nc, float lo = -1.0f, float hi = 1.0f) {
    ModelConfig c;
    c.input_nc = input_nc;
    c.output_nc = 3;
    c.input_range[0] = lo;
    c.input_range[1] = hi;
    return c;
}

}  // namespace

TEST_CASE("preprocessing matches the reference, hostile values sanitized and counted", "[pipeline][oclgrind]") {
    std::mt19937 rng(21);
    for (bool optional_terms : {true, false})
        for (LuminationTransfer tr : {LuminationTransfer::Reinhard, LuminationTransfer::Clamp}) {
            const int n = 10;
            const Frame fr = hostile_frame(n, rng, optional_terms);
            SurroundPipeline pl(test::device(), n, GlobalViewMode::Thesis, tr);
            const bool reinhard = tr == LuminationTransfer::Reinhard;
            INFO("emission/env " << optional_terms << ", transfer " << lumination_transfer_name(tr));

            // Front view only: [1, 10, N, N], compared texel by texel, in two input ranges.
            for (auto [lo, hi] : {std::pair{-1.0f, 1.0f}, std::pair{0.5f, 2.0f}}) {
                PreprocessStats st;
                const Tensor x = pl.network_input(fr, config(10, lo, hi), &st);
                REQUIRE(x.shape == std::vector<int>{1, 10, n, n});
                const Expected e = reference(fr, 1, reinhard);
                std::vector<float> want(e.planes.size());
                for (std::size_t i = 0; i < want.size(); ++i) want[i] = lo + e.planes[i] * (hi - lo);
                REQUIRE(test::all_finite(x.data));
                REQUIRE(test::max_abs_diff(x.data, want) < 4e-6);
                require_same_stats(st, e.stats);
                REQUIRE(st.total_nonfinite() > 0);
            }

            // Global view: counts over all six faces; the front crop equals the front-only input bit for bit;
            // the coordinate planes are the coordinate map in the input range.
            PreprocessStats st;
            const Tensor x = pl.network_input(fr, config(12), &st);
            REQUIRE(x.shape == std::vector<int>{1, 12, 2 * n, 4 * n});
            REQUIRE(test::all_finite(x.data));
            require_same_stats(st, reference(fr, 6, reinhard).stats);
            const Tensor single = pl.network_input(fr, config(10));
            const std::size_t plane = std::size_t(8) * n * n;
            for (int c = 0; c < 10; ++c)
                for (int r = 0; r < n; ++r)
                    REQUIRE(std::memcmp(&x.data[c * plane + std::size_t(r + n / 2) * 4 * n + 3 * n / 2],
                                        &single.data[(std::size_t(c) * n + r) * n], n * sizeof(float)) == 0);
            const Image& cm = pl.coord_map();
            for (int c = 0; c < 2; ++c)
                for (std::size_t p = 0; p < plane; ++p)
                    REQUIRE(x.data[(10 + c) * plane + p] == Approx(cm.data[c * plane + p] * 2 - 1).margin(1e-6));
        }
}

TEST_CASE("preprocessing: exact values at the edges of every rule", "[pipeline][oclgrind]") {
    const int n = 2;
    Frame fr;
    fr.look = {0, 0, -1};  // identity cluster basis: cluster space = world space
    fr.up = {0, 1, 0};
    for (int f = 0; f < kFaceCount; ++f) {
        fr.get(Feature::Albedo, Face(f)) = Image(n, n, 3, 0.25f);
        fr.get(Feature::Normal, Face(f)) = Image(n, n, 3, 0.0f);
        fr.get(Feature::Depth, Face(f)) = Image(n, n, 1, 500.0f);
        fr.get(Feature::Direct, Face(f)) = Image(n, n, 3, 1.0f);
    }
    Frame& f = fr;
    Image& nm = f.get(Feature::Normal, Face::Front);
    nm.at(2, 0, 1) = -3.0f;  // texel (0, 1): normal -z, renormalized
    Image& d = f.get(Feature::Depth, Face::Front);
    d.at(0, 0, 1) = 1e20f;
    d.at(0, 1, 0) = kNaN;
    d.at(0, 1, 1) = -kInf;
    Image& l = f.get(Feature::Direct, Face::Front);
    l.at(0, 0, 1) = kInf;
    l.at(1, 0, 1) = -2.0f;
    l.at(2, 0, 1) = 65504.0f;
    SurroundPipeline pl(test::device(), n);
    PreprocessStats st;
    const Tensor x = pl.network_input(fr, config(10, 0.0f, 1.0f), &st);
    auto at = [&](int c, int r, int col) { return x.data[(c * n + r) * n + col]; };
    REQUIRE(at(0, 0, 0) == 0.25f);                 // albedo unchanged inside [0, 1]
    REQUIRE(at(3, 0, 0) == 0.5f);                  // sky normal: the zero vector, mapped to 0.5
    REQUIRE(at(5, 0, 1) == 0.0f);                  // -z -> 0
    REQUIRE(at(3, 0, 1) == 0.5f);
    REQUIRE(at(6, 0, 0) == Approx(0.5f));          // 500 m
    REQUIRE(at(6, 0, 1) == 1.0f);                  // 1e20 m: clamped
    REQUIRE(at(6, 1, 0) == 1.0f);                  // NaN: far
    REQUIRE(at(6, 1, 1) == 0.0f);                  // -Inf: near
    REQUIRE(at(7, 0, 0) == 0.5f);                  // lumination 1 -> 1 / 2
    REQUIRE(at(7, 0, 1) == 1.0f);                  // +Inf: the brightest
    REQUIRE(at(8, 0, 1) == 0.0f);                  // negative light: none
    REQUIRE(at(9, 0, 1) == Approx(65504.0 / 65505.0).epsilon(1e-7));
    REQUIRE(st.nonfinite[int(Feature::Depth)] == 2);
    REQUIRE(st.nonfinite[int(Feature::Direct)] == 1);
    REQUIRE(st.total_nonfinite() == 3);
    REQUIRE(st.far_depths == 1);
    REQUIRE(st.sky_normals == 3);
}

TEST_CASE("network input rejects frames and models that do not fit", "[pipeline][oclgrind]") {
    using Catch::Matchers::Contains;
    const int n = 4;
    Frame fr;
    for (int f = 0; f < kFaceCount; ++f) {
        fr.get(Feature::Albedo, Face(f)) = Image(n, n, 3);
        fr.get(Feature::Normal, Face(f)) = Image(n, n, 3);
        fr.get(Feature::Depth, Face(f)) = Image(n, n, 1);
        fr.get(Feature::Direct, Face(f)) = Image(n, n, 3);
    }
    SurroundPipeline pl(test::device(), n);
    REQUIRE_NOTHROW(pl.network_input(fr, config(12)));
    REQUIRE_THROWS_WITH(pl.network_input(fr, config(11)), Contains("11") && Contains("12"));
    ModelConfig c = config(12);
    c.input_layout = surround_input_channels();
    REQUIRE_NOTHROW(pl.network_input(fr, c));
    std::swap(c.input_layout[10], c.input_layout[11]);
    REQUIRE_THROWS_WITH(pl.network_input(fr, c), Contains("channel 10") && Contains("coord.theta"));
    REQUIRE_THROWS_WITH(pl.network_input(fr, config(12, 1.0f, 1.0f)), Contains("input_range"));

    Frame bad = fr;
    bad.get(Feature::Emission, Face::Up) = Image(n, n, 3);
    REQUIRE_THROWS_WITH(pl.network_input(bad, config(12)), Contains("'emission'") && Contains("'front'"));
    // ... but the front-only input looks at the front face alone.
    bad = fr;
    bad.get(Feature::Direct, Face::Down) = Image();
    REQUIRE_THROWS_WITH(pl.network_input(bad, config(12)), Contains("'direct'") && Contains("'down'"));
    REQUIRE_NOTHROW(pl.network_input(bad, config(10)));
    bad = fr;
    bad.get(Feature::Depth, Face::Back) = Image(n, n, 3);
    REQUIRE_THROWS_WITH(pl.network_input(bad, config(12)), Contains("'depth'") && Contains("channels"));
    bad = fr;
    bad.get(Feature::Normal, Face::Right) = Image(2 * n, 2 * n, 3);
    REQUIRE_THROWS_WITH(pl.network_input(bad, config(12)), Contains("'normal'") && Contains("'right'"));
    bad = fr;
    bad.n = 2 * n;
    REQUIRE_THROWS_AS(pl.network_input(bad, config(12)), InputError);
    bad = fr;
    bad.look = bad.up;
    REQUIRE_THROWS_AS(pl.network_input(bad, config(12)), InputError);
}

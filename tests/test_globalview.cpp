// MergeToGlobalView, the coordinate map and front-view extraction (kernels/globalview.cl,
// host/src/pipeline/global_view.cpp): geometry, bit-exact copies, the gather kernel against references.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "reference_pipeline.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

constexpr double kPi = 3.14159265358979323846;

glm::vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    glm::vec3 v;
    do v = {g(rng), g(rng), g(rng)};
    while (glm::length(v) < 1e-3f);
    return glm::normalize(v);
}

double angle(glm::vec3 a, glm::vec3 b) {
    const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
    return std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y));
}

// A frame whose normal feature stores, at every texel of every face, that texel's world-space view direction.
Frame direction_frame(int n, glm::vec3 look, glm::vec3 up) {
    Frame fr;
    fr.n = n;
    fr.look = look;
    fr.up = up;
    const CameraCluster cl = CameraCluster::from_look_up(look, up);
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cl.face(Face(f));
        Image im(n, n, 3);
        for (int row = 0; row < n; ++row)
            for (int col = 0; col < n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(b, col, row, n));
                for (int c = 0; c < 3; ++c) im.at(c, row, col) = d[c];
            }
        fr.get(Feature::Normal, Face(f)) = im;
    }
    return fr;
}

const float* px(const Image& im, int c, int y, int x) { return &im.data[(std::size_t(c) * im.height + y) * im.width + x]; }

Image random_image(int w, int h, int c, std::mt19937& rng, float lo = -1, float hi = 1) {
    Image im(w, h, c);
    im.data = test::random_vector(im.data.size(), rng, lo, hi);
    return im;
}

}  // namespace

TEST_CASE("thesis layout is continuous with camera.hpp: side faces touch across every middle-band seam",
          "[pipeline]") {
    // Neighbouring columns across a face seam look in directions one texel apart, like any two neighbours
    // (a face texel spans at most 2 atan(1/N), at the face centre).
    for (int n : {4, 16, 64}) {
        const double texel = 2 * std::atan(1.0 / n);
        for (int y = n / 2; y < 3 * n / 2; ++y)
            for (int x = 0; x < 4 * n; ++x) {
                const glm::vec3 a = global_view_direction(x, y, n, GlobalViewMode::Thesis);
                const glm::vec3 b = global_view_direction((x + 1) % (4 * n), y, n, GlobalViewMode::Thesis);
                REQUIRE(angle(a, b) < 1.01 * texel);
            }
        // The band edges: the last top-band row and the first middle-band row are neighbours too.
        for (int x = 0; x < 4 * n; ++x) {
            for (int y : {n / 2 - 1, 3 * n / 2 - 1}) {
                const double a = angle(global_view_direction(x, y, n, GlobalViewMode::Thesis),
                                       global_view_direction(x, y + 1, n, GlobalViewMode::Thesis));
                REQUIRE(a < 1.01 * texel);
            }
        }
    }
    // Middle band = the side faces' own pixel directions (camera.hpp), front in the middle.
    const int n = 8;
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col) {
            const glm::vec3 d = glm::normalize(face_pixel_direction(cluster_face_basis(Face::Front), col, row, n));
            REQUIRE(angle(global_view_direction(col + 3 * n / 2, row + n / 2, n, GlobalViewMode::Thesis), d) < 1e-6);
        }
    REQUIRE(angle(global_view_direction(0, 0, n, GlobalViewMode::Thesis), {0, 1, 0}) < kPi / 2 / n);
    REQUIRE(angle(global_view_direction(0, 2 * n - 1, n, GlobalViewMode::Thesis), {0, -1, 0}) < kPi / 2 / n);
}

TEST_CASE("phi/theta: definition and round trip", "[pipeline]") {
    auto pt = direction_to_phi_theta({0, 0, -1});
    REQUIRE(pt.x == Approx(0.5f));
    REQUIRE(pt.y == Approx(0.5f));
    pt = direction_to_phi_theta({1, 0, 0});  // right of the front camera
    REQUIRE(pt.x == Approx(0.75f));
    REQUIRE(direction_to_phi_theta({0, 3, 0}).y == Approx(0.0f).margin(1e-7));
    REQUIRE(direction_to_phi_theta({0, -2, 0}).y == Approx(1.0f));
    std::mt19937 rng(3);
    for (int i = 0; i < 1000; ++i) {
        const glm::vec3 d = random_unit(rng);
        const glm::vec2 p = direction_to_phi_theta(d * 3.0f);
        REQUIRE(p.x >= 0.0f);
        REQUIRE(p.x <= 1.0f);
        REQUIRE(angle(phi_theta_to_direction(p.x, p.y), d) < 1e-5);
    }
}

TEST_CASE("merged self-directions agree with the coordinate map within one texel angle", "[pipeline]") {
    std::mt19937 rng(7);
    for (GlobalViewMode mode : {GlobalViewMode::Thesis, GlobalViewMode::Equirect}) {
        for (int n : {8, 18, 32}) {
            const glm::vec3 look = random_unit(rng), up = random_unit(rng);
            const Frame fr = direction_frame(n, look, up);
            const CameraCluster cl = CameraCluster::from_look_up(look, up);
            SurroundPipeline pl(test::device(), n, mode);
            const Image gv = pl.global_view(fr, Feature::Normal);
            const Image& cm = pl.coord_map();
            REQUIRE(gv.width == 4 * n);
            REQUIRE(gv.height == 2 * n);
            REQUIRE(cm.channels == 2);

            // The same directions through preprocessing: with input range [-1, 1] the normal channels are the
            // cluster-space normal itself.
            ModelConfig cfg;
            cfg.input_nc = 12;
            const Tensor x = pl.network_input(
                [&] {
                    Frame f2 = fr;
                    for (int f = 0; f < kFaceCount; ++f) {
                        f2.get(Feature::Albedo, Face(f)) = Image(n, n, 3, 0.5f);
                        f2.get(Feature::Depth, Face(f)) = Image(n, n, 1, 1.0f);
                        f2.get(Feature::Direct, Face(f)) = Image(n, n, 3, 0.0f);
                    }
                    return f2;
                }(),
                cfg);
            const std::size_t plane = std::size_t(8) * n * n;

            const double texel = kPi / 2 / n;
            double worst_merge = 0, worst_input = 0, worst_analytic = 0;
            for (int y = 0; y < 2 * n; ++y)
                for (int xx = 0; xx < 4 * n; ++xx) {
                    const glm::vec3 world(gv.at(0, y, xx), gv.at(1, y, xx), gv.at(2, y, xx));
                    const glm::vec3 coord = phi_theta_to_direction(cm.at(0, y, xx), cm.at(1, y, xx));
                    const std::size_t p = std::size_t(y) * 4 * n + xx;
                    const glm::vec3 in(x.data[3 * plane + p], x.data[4 * plane + p], x.data[5 * plane + p]);
                    worst_merge = std::max(worst_merge, angle(cl.to_cluster(world), coord));
                    worst_input = std::max(worst_input, angle(in, coord));
                    worst_analytic = std::max(worst_analytic, angle(global_view_direction(xx, y, n, mode), coord));
                }
            // Run with -s to see these numbers for passing runs too.
            INFO(global_view_mode_name(mode) << " N=" << n << ": max angle merged/coord = " << worst_merge / texel
                                             << " texel angles (pi/2/N), preprocessed/coord = " << worst_input / texel
                                             << ", analytic/coord = " << worst_analytic / texel);
            REQUIRE(worst_merge < texel);
            REQUIRE(worst_input < texel);
            REQUIRE(worst_analytic < 1e-3 * texel);
        }
    }
}

TEST_CASE("thesis merge: middle band and front crop are bit-exact copies of the faces", "[pipeline][oclgrind]") {
    std::mt19937 rng(11);
    const int n = 20;
    Frame fr;
    for (int f = 0; f < kFaceCount; ++f) {
        Image im = random_image(n, n, 3, rng);
        im.data[5] = -0.0f;  // signed zero survives a copy, not an "acc = 0 + 1 * v"
        fr.get(Feature::Albedo, Face(f)) = im;
    }
    SurroundPipeline pl(test::device(), n);
    const Image gv = pl.global_view(fr, Feature::Albedo);
    const Image* faces[kFaceCount];
    for (int f = 0; f < kFaceCount; ++f) faces[f] = &fr.get(Feature::Albedo, Face(f));
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < n; ++row)
            REQUIRE(std::memcmp(px(gv, c, row + n / 2, 3 * n / 2), px(*faces[int(Face::Front)], c, row, 0),
                                n * sizeof(float)) == 0);
    REQUIRE(std::signbit(gv.at(0, n / 2, 3 * n / 2 + 5)));
    // Every other middle-band segment: left, right, and the back face split over both ends.
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < n; ++row) {
            const int y = row + n / 2;
            REQUIRE(std::memcmp(px(gv, c, y, n / 2), px(*faces[int(Face::Left)], c, row, 0), n * 4) == 0);
            REQUIRE(std::memcmp(px(gv, c, y, 5 * n / 2), px(*faces[int(Face::Right)], c, row, 0), n * 4) == 0);
            REQUIRE(std::memcmp(px(gv, c, y, 0), px(*faces[int(Face::Back)], c, row, n / 2), n / 2 * 4) == 0);
            REQUIRE(std::memcmp(px(gv, c, y, 7 * n / 2), px(*faces[int(Face::Back)], c, row, 0), n / 2 * 4) == 0);
        }
}

TEST_CASE("thesis merge matches the naive layout reference, the gather kernel matches its table", "[pipeline][oclgrind]") {
    std::mt19937 rng(5);
    for (int n : {2, 6, 16, 30}) {
        Frame fr;
        Image faces[kFaceCount];
        for (int f = 0; f < kFaceCount; ++f) fr.get(Feature::Depth, Face(f)) = faces[f] = random_image(n, n, 1, rng);
        SurroundPipeline pl(test::device(), n);
        const Image gv = pl.global_view(fr, Feature::Depth);
        const Image want = ref::merge_thesis(faces, n);
        INFO("N = " << n);
        // The table holds float positions: a column near N carries ~N * 2^-24 of error into the weights.
        REQUIRE(test::max_abs_diff(gv.data, want.data) < 1e-5);
    }
    // The kernel against a host gather through the same table, both modes, several channels.
    for (GlobalViewMode mode : {GlobalViewMode::Thesis, GlobalViewMode::Equirect}) {
        const int n = 12;
        const detail::GatherLut lut = detail::build_merge_lut(n, mode);
        REQUIRE(lut.idx.size() == std::size_t(8 * n * n));
        Frame fr;
        for (int f = 0; f < kFaceCount; ++f) fr.get(Feature::Direct, Face(f)) = random_image(n, n, 3, rng, 0, 10);
        SurroundPipeline pl(test::device(), n, mode);
        const Image gv = pl.global_view(fr, Feature::Direct);
        const std::size_t fp = std::size_t(n) * n;
        double worst = 0, wsum = 0;
        for (std::size_t p = 0; p < lut.idx.size(); ++p) {
            float s = 0;
            for (int k = 0; k < 4; ++k) {
                REQUIRE(lut.idx[p][k] >= 0);
                REQUIRE(lut.idx[p][k] < int(6 * fp));
                REQUIRE(lut.w[p][k] >= 0.0f);
                s += lut.w[p][k];
            }
            wsum = std::max(wsum, std::abs(double(s) - 1.0));
            for (int c = 0; c < 3; ++c) {
                double acc = 0;
                for (int k = 0; k < 4; ++k) {
                    const int face = lut.idx[p][k] / int(fp), texel = lut.idx[p][k] % int(fp);
                    acc += double(lut.w[p][k]) * fr.get(Feature::Direct, Face(face)).data[c * fp + texel];
                }
                worst = std::max(worst, std::abs(acc - gv.data[c * 8 * fp + p]));
            }
        }
        REQUIRE(wsum < 1e-6);
        REQUIRE(worst < 1e-5);
    }
}

TEST_CASE("equirect merge: every pixel resampled at its phi/theta", "[pipeline][oclgrind]") {
    // A smooth function of direction survives the equirect resampling to within interpolation error.
    const int n = 32;
    Frame fr;
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cluster_face_basis(Face(f));
        Image im(n, n, 1);
        for (int row = 0; row < n; ++row)
            for (int col = 0; col < n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(b, col, row, n));
                im.at(0, row, col) = d.x + 0.5f * d.y * d.z;
            }
        fr.get(Feature::Depth, Face(f)) = im;
    }
    SurroundPipeline pl(test::device(), n, GlobalViewMode::Equirect);
    const Image gv = pl.global_view(fr, Feature::Depth);
    double worst = 0;
    for (int y = 0; y < 2 * n; ++y)
        for (int x = 0; x < 4 * n; ++x) {
            const glm::vec3 d = phi_theta_to_direction((x + 0.5f) / (4 * n), (y + 0.5f) / (2 * n));
            worst = std::max(worst, std::abs(double(gv.at(0, y, x)) - (d.x + 0.5 * d.y * d.z)));
        }
    REQUIRE(worst < 0.02);  // bilinear on a 32-texel face: O(texel^2) plus edge clamping
}

TEST_CASE("front view extraction: exact crop in thesis mode, resampling in equirect mode", "[pipeline][oclgrind]") {
    std::mt19937 rng(9);
    const int n = 16;
    ModelConfig cfg;
    cfg.input_nc = 12;
    cfg.output_nc = 3;
    Tensor y({1, 3, 2 * n, 4 * n});
    y.data = test::random_vector(y.size(), rng, -1, 1);
    SurroundPipeline pl(test::device(), n);
    const Image light = pl.front_lightmap(y, cfg);
    // The same crop given as a front-only output must decode to the same bits.
    Tensor crop({1, 3, n, n});
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < n; ++r)
            for (int col = 0; col < n; ++col)
                crop.data[(c * n + r) * n + col] = y.data[(c * 2 * n + r + n / 2) * 4 * n + col + 3 * n / 2];
    const Image light2 = pl.front_lightmap(crop, cfg);
    REQUIRE(std::memcmp(light.data.data(), light2.data.data(), light.data.size() * 4) == 0);

    // Equirect: a global view that is a smooth function of direction gives back that function on the front view.
    SurroundPipeline eq(test::device(), n, GlobalViewMode::Equirect);
    cfg.output_range[0] = 0.0f;  // output range [0, 1]: the decode is y / (1 - y)
    for (int c = 0; c < 3; ++c)
        for (int gy = 0; gy < 2 * n; ++gy)
            for (int gx = 0; gx < 4 * n; ++gx) {
                const glm::vec3 d = global_view_direction(gx, gy, n, GlobalViewMode::Equirect);
                y.data[(c * 2 * n + gy) * 4 * n + gx] = 0.3f + 0.1f * d.x + 0.05f * c * d.y;
            }
    const Image fl = eq.front_lightmap(y, cfg);
    const FaceBasis front = cluster_face_basis(Face::Front);
    double worst = 0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < n; ++r)
            for (int col = 0; col < n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(front, col, r, n));
                const double v = 0.3 + 0.1 * d.x + 0.05 * c * d.y;
                worst = std::max(worst, std::abs(fl.at(c, r, col) - v / (1 - v)));
            }
    REQUIRE(worst < 2e-3);
}

TEST_CASE("global view rejects odd N, mismatched and non-square faces with clear errors", "[pipeline][oclgrind]") {
    using Catch::Matchers::Contains;
    REQUIRE_THROWS_WITH(SurroundPipeline(test::device(), 17), Contains("even") && Contains("17"));
    REQUIRE_THROWS_AS(SurroundPipeline(test::device(), 0), InputError);
    REQUIRE_THROWS_AS(global_view_direction(32, 0, 8, GlobalViewMode::Thesis), InputError);
    const int n = 8;
    SurroundPipeline pl(test::device(), n);
    Frame fr;
    for (int f = 0; f < kFaceCount; ++f) fr.get(Feature::Albedo, Face(f)) = Image(n, n, 3);
    fr.get(Feature::Albedo, Face::Left) = Image(n / 2, n / 2, 3);
    REQUIRE_THROWS_WITH(pl.global_view(fr, Feature::Albedo),
                        Contains("'albedo'") && Contains("'left'") && Contains("4x4") && Contains("same size"));
    fr.get(Feature::Albedo, Face::Left) = Image(n, n, 3);
    fr.get(Feature::Albedo, Face::Up) = Image(n, n / 2, 3);
    REQUIRE_THROWS_WITH(pl.global_view(fr, Feature::Albedo), Contains("'up'") && Contains("square"));
    fr.get(Feature::Albedo, Face::Up) = Image(n, n, 1);
    REQUIRE_THROWS_WITH(pl.global_view(fr, Feature::Albedo), Contains("'up'") && Contains("channels"));
    fr.get(Feature::Albedo, Face::Up) = Image();
    REQUIRE_THROWS_WITH(pl.global_view(fr, Feature::Albedo), Contains("'up'") && Contains("missing"));
}

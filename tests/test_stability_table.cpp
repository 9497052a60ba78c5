// Issue 31's stability table (docs/RELIABILITY.md, "Stability table"): every shipped model family through the
// library's API on inputs whose values are all of one extreme class -- NaN, +-Inf, +-FLT_MAX, a denormal, all zero,
// a constant, or (where the input has one) a depth of 1e5 m -- and three questions per cell:
//   finite   is every output value finite (and, where the output has a range, inside it)?
//   warned   did the API report replacing values (the sanitized/non-finite counter the CLI prints)?
//   score    MSE and SSIM of the output against the clean input's output: "valid" (both finite numbers),
//            "refused" (compare_images throws an InputError saying why, e.g. values whose squares overflow) or
//            "undefined" (a NaN with a note)
// The expected table is written out below and compared cell by cell with what the run observes, so the table in
// the docs is this test's table: a change of behaviour fails here and names the cell. The API path is the one with
// no reader in front: a frame folder read from disk is sanitized on read as well (read_frame, FrameReadStats),
// which the CLI prints and metrics.json records as "scores_valid": false (tests/cli/test_cli.sh).
#include <catch2/catch.hpp>
#include <cfloat>
#include <cmath>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ngi/ao.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/neural_gi.hpp"
#include "ngi/pipeline.hpp"
#include "test_support.hpp"

namespace {

struct Extreme {
    const char* name;
    float value;
    bool depth_only;  // the class changes only the depth (1e5 m); the other classes change every input value
};

const std::vector<Extreme>& extremes() {
    static const std::vector<Extreme> e = {
        {"NaN", NAN, false},          {"+Inf", INFINITY, false},     {"-Inf", -INFINITY, false},
        {"+FLT_MAX", FLT_MAX, false}, {"-FLT_MAX", -FLT_MAX, false}, {"denormal", 1.0e-40f, false},
        {"zero", 0.0f, false},        {"constant", 0.5f, false},     {"depth 1e5 m", 1.0e5f, true},
    };
    return e;
}

struct Cell {
    bool finite = false, warned = false;
    std::string score;
};

std::string yes_no(bool b) { return b ? "yes" : "no"; }

bool all_finite_in(const ngi::Image& im, float lo = -FLT_MAX, float hi = FLT_MAX) {
    for (float v : im.data)
        if (!std::isfinite(v) || v < lo || v > hi) return false;
    return true;
}

// MSE and SSIM of `out` against the clean run's output (data range: the clean output's largest magnitude).
std::string score(const ngi::Image& out, const ngi::Image& clean) {
    double peak = 0;
    for (float v : clean.data) peak = std::max(peak, double(std::abs(v)));
    try {
        const ngi::ImageMetrics m = ngi::compare_images(ngi::test::device(), out, clean, peak > 0 ? peak : 1.0);
        return std::isfinite(m.mse) && std::isfinite(m.ssim) ? "valid" : "undefined";
    } catch (const ngi::InputError&) {
        return "refused";
    }
}
// Both scores of a pair of outputs: the worse one.
std::string score(const ngi::Image& a, const ngi::Image& clean_a, const ngi::Image& b, const ngi::Image& clean_b) {
    const std::string sa = score(a, clean_a), sb = score(b, clean_b);
    return sa != "valid" ? sa : sb;
}

// A frame of n x n faces: albedo in [0.05, 0.9], axis normals, depth 0.5-8 m, HDR direct light; the neural GI
// fields (camera position, an area light) set, so every family can take it.
ngi::Frame clean_frame(int n) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ngi::Frame f;
    f.n = n;
    f.look = glm::vec3(0, 0, -1);
    f.up = glm::vec3(0, 1, 0);
    f.position = glm::vec3(6.0f, 3.0f, 9.0f);
    ngi::AreaLight light;
    light.centre = glm::vec3(7.0f, 7.5f, 5.0f);
    light.half_u = glm::vec3(0.6f, 0.0f, 0.0f);
    light.half_v = glm::vec3(0.0f, 0.0f, 0.4f);
    light.radiance = glm::vec3(20.0f, 18.0f, 15.0f);
    f.area_light = light;
    for (int feat = 0; feat < ngi::kFeatureCount; ++feat)
        for (int face = 0; face < ngi::kFaceCount; ++face) {
            ngi::Image im(n, n, ngi::feature_channels(ngi::Feature(feat)));
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const int axis = (x / 3 + y / 5 + face) % 3;
                    for (int c = 0; c < im.channels; ++c) {
                        float v = 0.0f;
                        switch (ngi::Feature(feat)) {
                            case ngi::Feature::Albedo: v = 0.05f + 0.85f * u(rng); break;
                            case ngi::Feature::Normal: v = c == axis ? 1.0f : 0.0f; break;
                            case ngi::Feature::Depth: v = 0.5f + 7.5f * u(rng); break;
                            case ngi::Feature::Direct: v = 20.0f * u(rng) * u(rng); break;
                            default: v = 0.0f; break;  // emission, environment
                        }
                        im.at(c, y, x) = v;
                    }
                }
            f.faces[feat][face] = std::move(im);
        }
    return f;
}

// The frame with every value of the features the class touches set to it (depth_only: every depth).
ngi::Frame extreme_frame(const ngi::Frame& clean, const Extreme& e, bool front_only) {
    ngi::Frame f = clean;
    for (int feat = 0; feat < ngi::kFeatureCount; ++feat) {
        if (e.depth_only != (ngi::Feature(feat) == ngi::Feature::Depth)) continue;
        for (int face = 0; face < ngi::kFaceCount; ++face) {
            if (front_only && ngi::Face(face) != ngi::Face::Front) continue;
            for (float& v : f.faces[feat][face].data) v = e.value;
        }
    }
    return f;
}

using Table = std::map<std::string, Cell>;  // extreme class -> cell

std::string markdown(const std::string& family, const Table& t) {
    std::ostringstream s;
    for (const Extreme& e : extremes()) {
        const auto it = t.find(e.name);
        if (it == t.end()) continue;
        s << "| " << family << " | " << e.name << " | " << yes_no(it->second.finite) << " | "
          << yes_no(it->second.warned) << " | " << it->second.score << " |\n";
    }
    return s.str();
}

// Compares the observed table with the expected one, cell by cell, and prints the observed rows (the docs' table).
void check_table(const std::string& family, const Table& observed, const Table& expected) {
    INFO(family << " observed:\n" << markdown(family, observed));
    REQUIRE(observed.size() == expected.size());
    for (const auto& [name, want] : expected) {
        CAPTURE(family, name);
        REQUIRE(observed.count(name));
        const Cell& got = observed.at(name);
        CHECK(got.finite == want.finite);
        CHECK(got.warned == want.warned);
        CHECK(got.score == want.score);
    }
    // The one invariant of every cell: a model's output is finite, whatever its input held.
    for (const auto& [name, got] : observed) {
        CAPTURE(family, name);
        CHECK(got.finite);
    }
}

// Expected rows: warned and score per class (finite is always required).
Table expect(std::initializer_list<std::pair<const char*, std::pair<bool, const char*>>> rows) {
    Table t;
    for (const auto& [name, ws] : rows) t[name] = Cell{true, ws.first, ws.second};
    return t;
}

}  // namespace

TEST_CASE("stability table: the surround and single-view generators and the ssgi rung on extreme frames", "[stability][pipeline]") {
    const int n = 32;
    const ngi::Frame clean = clean_frame(n);
    for (const char* name : {"surround_n32_ngf32", "single_view_n32_ngf32", "ssgi_surround"}) {
        ngi::Model model = ngi::Model::load(ngi::test::device(), ngi::resolve_model(name));
        ngi::SurroundPipeline pipeline(ngi::test::device(), n);
        ngi::PreprocessStats stats;
        const ngi::FrameImages base = pipeline.run(model, clean, true, true, false, {}, &stats);
        REQUIRE(stats.total_nonfinite() == 0);
        Table observed;
        for (const Extreme& e : extremes()) {
            const ngi::FrameImages out = pipeline.run(model, extreme_frame(clean, e, false), true, true, false, {}, &stats);
            observed[e.name] = {all_finite_in(out.lightmap, 0.0f) && all_finite_in(out.final_image, 0.0f),
                                stats.total_nonfinite() > 0 || stats.far_depths > 0,
                                score(out.lightmap, base.lightmap, out.final_image, base.final_image)};
        }
        // Non-finite features are replaced and counted (per feature); FLT_MAX, denormals and constants are values
        // the pipeline takes as they are (light is clamped to float range, albedo to [0, 1] in compose), depths
        // beyond 1000 m are clamped and counted as far. An FLT_MAX direct light makes an FLT_MAX lightmap: finite,
        // but its squared error against the clean frame's overflows, so no score.
        check_table(name, observed,
                    expect({{"NaN", {true, "valid"}}, {"+Inf", {true, "refused"}}, {"-Inf", {true, "valid"}},
                            {"+FLT_MAX", {false, "refused"}}, {"-FLT_MAX", {false, "valid"}},
                            {"denormal", {false, "valid"}}, {"zero", {false, "valid"}}, {"constant", {false, "valid"}},
                            {"depth 1e5 m", {true, "valid"}}}));
    }
}

TEST_CASE("stability table: the AO network on extreme normals", "[stability][ao]") {
    ngi::AoNetwork net = ngi::AoNetwork::load(ngi::test::device(), ngi::resolve_model("ao_bunny_16x8"));
    const int n = 32;
    ngi::Image clean(n, n, 3);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const glm::vec3 v = glm::normalize(glm::vec3(float(x - n / 2), float(y - n / 2), 8.0f));
            for (int c = 0; c < 3; ++c) clean.at(c, y, x) = v[c];
        }
    const ngi::Image base = net.run(clean);
    Table observed;
    for (const Extreme& e : extremes()) {
        if (e.depth_only) continue;  // normals only: no depth
        ngi::Image in = clean;
        for (float& v : in.data) v = e.value;
        ngi::RunInfo info;
        const ngi::Image out = net.run(in, -1.0f, &info);
        observed[e.name] = {all_finite_in(out, 0.0f, 1.0f), info.sanitized_inputs > 0, score(out, base)};
    }
    // NaN, +-Inf and +-FLT_MAX are outside the model's input range [-1, 1] by more than 1/1024: replaced and
    // counted. A zero normal is the background (AO 1, nothing to warn about); a denormal normal is a surface.
    check_table("ao_bunny_16x8", observed,
                expect({{"NaN", {true, "valid"}}, {"+Inf", {true, "valid"}}, {"-Inf", {true, "valid"}}, {"+FLT_MAX", {true, "valid"}},
                        {"-FLT_MAX", {true, "valid"}}, {"denormal", {false, "valid"}}, {"zero", {false, "valid"}},
                        {"constant", {false, "valid"}}}));
}

TEST_CASE("stability table: the neural GI network on extreme frames", "[stability][neural_gi]") {
    ngi::Model model = ngi::Model::load(ngi::test::device(), ngi::resolve_model("neural_gi_room"));
    // 32 = the smallest face its 5-level buffer U-Net takes: ten runs of the 8 x 256 MLP at 64^2 took 680 s on
    // llvmpipe (rusticl, 0.4 GFLOP/s) -- half the rusticl stage -- and the extremes are the same at any size.
    const int n = 32;
    const ngi::Frame clean = clean_frame(n);
    ngi::NeuralGiRenderer renderer(ngi::test::device());
    const ngi::NeuralGiImages base = renderer.run(model, clean);
    REQUIRE(base.sanitized_inputs == 0);
    Table observed;
    for (const Extreme& e : extremes()) {
        const ngi::NeuralGiImages out = renderer.run(model, extreme_frame(clean, e, true));
        observed[e.name] = {all_finite_in(out.indirect, 0.0f) && all_finite_in(out.lighting, 0.0f),
                            out.sanitized_inputs > 0 || out.nonfinite_features > 0, score(out.lighting, base.lighting)};
    }
    check_table("neural_gi_room", observed,
                expect({{"NaN", {true, "valid"}}, {"+Inf", {true, "refused"}}, {"-Inf", {true, "valid"}},
                        {"+FLT_MAX", {false, "refused"}}, {"-FLT_MAX", {false, "valid"}}, {"denormal", {false, "valid"}},
                        {"zero", {false, "valid"}}, {"constant", {false, "valid"}}, {"depth 1e5 m", {false, "valid"}}}));
}

TEST_CASE("stability table: the voxel SH network on extreme voxel features", "[stability][voxel_sh]") {
    ngi::Model model = ngi::Model::load(ngi::test::device(), ngi::resolve_model("voxel_sh_set"));
    const int v = 257, c = model.config().input_nc;
    std::mt19937 rng(3);
    ngi::Tensor clean({v, c});
    for (float& x : clean.data) x = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
    const ngi::Tensor base = model.run(clean);
    auto as_image = [v](const ngi::Tensor& t) {  // [V, 27] as a 27 x V image, so that SSIM has whole windows
        ngi::Image im(int(t.data.size()) / v, v, 1);
        im.data = t.data;
        return im;
    };
    Table observed;
    for (const Extreme& e : extremes()) {
        if (e.depth_only) continue;  // voxel features: no depth
        ngi::Tensor in = clean;
        for (float& x : in.data) x = e.value;
        ngi::RunInfo info;
        const ngi::Tensor out = model.run(in, &info);
        observed[e.name] = {all_finite_in(as_image(out)), info.sanitized_inputs > 0, score(as_image(out), as_image(base))};
    }
    check_table("voxel_sh_set", observed,
                expect({{"NaN", {true, "valid"}}, {"+Inf", {true, "valid"}}, {"-Inf", {true, "valid"}}, {"+FLT_MAX", {true, "valid"}},
                        {"-FLT_MAX", {true, "valid"}}, {"denormal", {false, "valid"}}, {"zero", {false, "valid"}},
                        {"constant", {false, "valid"}}}));
}

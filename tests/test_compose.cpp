// Output side (kernels/compose.cl, host/src/pipeline/compose.cpp) against the naive references: lightmap
// decoding, final composition, bilinear resize at odd sizes, tone mapping; hostile values; bad input.
#include <catch2/catch.hpp>

#include <cfloat>
#include <cstring>
#include <limits>
#include <random>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "reference_pipeline.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

void sprinkle(std::vector<float>& v, std::mt19937& rng, std::initializer_list<float> specials) {
    std::uniform_int_distribution<std::size_t> at(0, v.size() - 1);
    for (float s : specials) v[at(rng)] = s;
}

double rel_err(double got, double want) { return std::abs(got - want) / (1e-6 + std::abs(want)); }

}  // namespace

TEST_CASE("front lightmap: model output range and inverse transfer", "[pipeline][oclgrind]") {
    std::mt19937 rng(31);
    const int n = 6;
    for (LuminationTransfer tr : {LuminationTransfer::Reinhard, LuminationTransfer::Clamp})
        for (auto [lo, hi] : {std::pair{-1.0f, 1.0f}, std::pair{0.0f, 1.0f}}) {
            SurroundPipeline pl(test::device(), n, GlobalViewMode::Thesis, tr);
            ModelConfig cfg;
            cfg.output_range[0] = lo;
            cfg.output_range[1] = hi;
            Tensor y({1, 3, n, n});
            y.data = test::random_vector(y.size(), rng, lo - 0.2f, hi + 0.2f);
            sprinkle(y.data, rng, {kNaN, kInf, -kInf, lo, hi, std::nextafter(hi, lo), FLT_MAX});
            const Image l = pl.front_lightmap(y, cfg);
            REQUIRE(l.width == n);
            REQUIRE(l.channels == 3);
            double worst = 0;
            for (std::size_t i = 0; i < l.data.size(); ++i) {
                const double want = ref::decode_light(y.data[i], lo, hi, tr == LuminationTransfer::Reinhard);
                REQUIRE(std::isfinite(l.data[i]));
                REQUIRE(l.data[i] >= 0.0f);
                REQUIRE(l.data[i] <= 65504.0f);
                worst = std::max(worst, rel_err(l.data[i], want));
            }
            INFO(lumination_transfer_name(tr) << " [" << lo << ", " << hi << "]");
            REQUIRE(worst < 2e-5);  // y / (1 - y) amplifies the float rounding of 1 - y near 1
        }
}

TEST_CASE("preprocess then decode: lumination survives the round trip through the transfer", "[pipeline][oclgrind]") {
    // What the model sees as lumination, read back as a lightmap, is the light itself (an identity "model").
    const int n = 4;
    Frame fr;
    std::mt19937 rng(2);
    for (int f = 0; f < kFaceCount; ++f) {
        fr.get(Feature::Albedo, Face(f)) = Image(n, n, 3, 1.0f);
        fr.get(Feature::Normal, Face(f)) = Image(n, n, 3, 0.0f);
        fr.get(Feature::Depth, Face(f)) = Image(n, n, 1, 1.0f);
        Image d(n, n, 3);
        d.data = test::random_vector(d.data.size(), rng, 0.0f, 50.0f);
        d.data[0] = 0.0f;
        d.data[1] = 1000.0f;
        fr.get(Feature::Direct, Face(f)) = d;
    }
    SurroundPipeline pl(test::device(), n);
    ModelConfig cfg;
    cfg.input_nc = 12;
    const Tensor x = pl.network_input(fr, cfg);
    Tensor y({1, 3, 2 * n, 4 * n});
    std::memcpy(y.data.data(), &x.data[7 * y.data.size() / 3], y.data.size() * sizeof(float));  // planes 7..9
    const Image l = pl.front_lightmap(y, cfg);
    // Relative error ~ (1 + x) * 2^-23: 1000 comes back to within ~1e-4.
    const Image& want = fr.get(Feature::Direct, Face::Front);
    for (std::size_t i = 0; i < l.data.size(); ++i) REQUIRE(l.data[i] == Approx(want.data[i]).epsilon(5e-4).margin(1e-6));
}

TEST_CASE("compose: lightmap x albedo + emission + env, hostile values, reference final image", "[pipeline][oclgrind]") {
    std::mt19937 rng(41);
    const int n = 8;
    SurroundPipeline pl(test::device(), n);
    for (int terms = 0; terms < 4; ++terms) {
        Frame fr;
        Image a(n, n, 3), e(n, n, 3), v(n, n, 3), l(n, n, 3);
        a.data = test::random_vector(a.data.size(), rng, -0.2f, 1.2f);
        e.data = test::random_vector(e.data.size(), rng, 0.0f, 3.0f);
        v.data = test::random_vector(v.data.size(), rng, 0.0f, 1.0f);
        l.data = test::random_vector(l.data.size(), rng, 0.0f, 100.0f);
        sprinkle(a.data, rng, {kNaN, kInf, -kInf});
        sprinkle(e.data, rng, {kNaN, kInf, -1.0f, FLT_MAX});
        sprinkle(v.data, rng, {kNaN, -kInf, FLT_MAX});
        sprinkle(l.data, rng, {kNaN, kInf, -5.0f});
        fr.get(Feature::Albedo, Face::Front) = a;
        const bool has_e = terms & 1, has_v = terms & 2;
        if (has_e) fr.get(Feature::Emission, Face::Front) = e;
        if (has_v) fr.get(Feature::Env, Face::Front) = v;
        fr.reference = l;
        const Image out = pl.compose(*fr.reference, fr);
        REQUIRE(out.width == n);
        for (std::size_t i = 0; i < out.data.size(); ++i) {
            const double want = ref::compose(l.data[i], a.data[i], has_e ? &e.data[i] : nullptr,
                                             has_v ? &v.data[i] : nullptr);
            REQUIRE(std::isfinite(out.data[i]));
            REQUIRE(rel_err(out.data[i], want) < 1e-6);
        }
    }
}

TEST_CASE("upscale: bilinear resize at random sizes, odd widths included", "[pipeline][oclgrind]") {
    std::mt19937 rng(51);
    SurroundPipeline pl(test::device(), 2);
    std::uniform_int_distribution<int> size(1, 37), chans(1, 4);
    for (int trial = 0; trial < 25; ++trial) {
        Image in(size(rng), size(rng), chans(rng));
        in.data = test::random_vector(in.data.size(), rng, -2, 2);
        const int w = trial == 0 ? in.width : size(rng) * 2 + 1, h = trial == 0 ? in.height : size(rng);
        const Image out = pl.upscale(in, w, h);
        const Image want = ref::resize(in, w, h);
        INFO(in.width << "x" << in.height << "x" << in.channels << " -> " << w << "x" << h);
        REQUIRE(out.width == w);
        REQUIRE(out.height == h);
        REQUIRE(out.channels == in.channels);
        if (trial == 0) REQUIRE(out.data == in.data);  // same size: an exact copy
        // Float source positions (~W * 2^-24) against the double reference.
        REQUIRE(test::max_abs_diff(out.data, want.data) < 1e-5);
    }
}

TEST_CASE("tone map: exposure, curves, sRGB, always in [0, 1]", "[pipeline][oclgrind]") {
    std::mt19937 rng(61);
    SurroundPipeline pl(test::device(), 2);
    Image in(13, 7, 3);
    in.data = test::random_vector(in.data.size(), rng, -0.5f, 20.0f);
    sprinkle(in.data, rng, {kNaN, kInf, -kInf, FLT_MAX, 65504.0f, 0.0f, 0.002f, 1e-30f});
    for (ToneCurve curve : {ToneCurve::AcesFitted, ToneCurve::Reinhard, ToneCurve::Clamp})
        for (bool srgb : {true, false})
            for (float ev : {0.0f, -2.5f, 3.0f}) {
                const Image out = pl.tonemap(in, {ev, curve, srgb});
                double worst = 0;
                for (std::size_t i = 0; i < out.data.size(); ++i) {
                    REQUIRE(out.data[i] >= 0.0f);
                    REQUIRE(out.data[i] <= 1.0f);
                    worst = std::max(worst, std::abs(out.data[i] - ref::tonemap(in.data[i], std::exp2(double(ev)),
                                                                                  int(curve), srgb)));
                }
                INFO(tone_curve_name(curve) << " srgb " << srgb << " ev " << ev);
                REQUIRE(worst < 2e-6);
            }
    REQUIRE(tone_curve_from_name("aces") == ToneCurve::AcesFitted);
    REQUIRE_THROWS_AS(tone_curve_from_name("filmic"), InputError);
    REQUIRE_THROWS_AS(pl.tonemap(in, {kNaN, ToneCurve::Clamp, true}), InputError);
}

TEST_CASE("output side rejects tensors and images that do not fit", "[pipeline][oclgrind]") {
    using Catch::Matchers::Contains;
    const int n = 4;
    SurroundPipeline pl(test::device(), n);
    ModelConfig cfg;
    REQUIRE_THROWS_WITH(pl.front_lightmap(Tensor({1, 3, n, 2 * n}), cfg), Contains("[1, 3, 4, 8]") && Contains("[1, 3, 8, 16]"));
    REQUIRE_THROWS_AS(pl.front_lightmap(Tensor({1, 1, 2 * n, 4 * n}), cfg), InputError);
    REQUIRE_THROWS_AS(pl.front_lightmap(Tensor({3, 2 * n, 4 * n}), cfg), InputError);
    Tensor short_data({1, 3, n, n});
    short_data.data.pop_back();
    REQUIRE_THROWS_AS(pl.front_lightmap(short_data, cfg), InputError);
    cfg.output_range[1] = cfg.output_range[0];
    REQUIRE_THROWS_WITH(pl.front_lightmap(Tensor({1, 3, n, n}), cfg), Contains("output_range"));

    Frame fr;
    fr.get(Feature::Albedo, Face::Front) = Image(n, n, 3);
    REQUIRE_NOTHROW(pl.compose(Image(n, n, 3), fr));
    REQUIRE_THROWS_WITH(pl.compose(Image(2 * n, 2 * n, 3), fr), Contains("lightmap"));
    fr.get(Feature::Albedo, Face::Front) = Image(n, n / 2, 3);
    REQUIRE_THROWS_WITH(pl.compose(Image(n, n, 3), fr), Contains("'albedo'") && Contains("square"));
    REQUIRE_THROWS_AS(pl.upscale(Image(), 4, 4), InputError);
    REQUIRE_THROWS_AS(pl.upscale(Image(3, 3, 1), 0, 4), InputError);
    // Beyond the device's largest allocation: refused by the device buffer's check, which now comes before the host
    // image of the same size (issue 31 item 6: `lightmap --size 16384x16384` reached 3.2 GB of host memory first).
    const std::size_t big = std::size_t(16384) * 16384 * 3 * sizeof(float);
    if (big > test::device().info().max_alloc_bytes)
        REQUIRE_THROWS_WITH(pl.upscale(Image(3, 3, 3), 16384, 16384),
                            Contains("upscale output") && Contains("CL_DEVICE_MAX_MEM_ALLOC_SIZE"));
}

TEST_CASE("encode lightmap: the inverse of the decoding, the same encoding as the input's lumination", "[pipeline][oclgrind]") {
    using Catch::Matchers::Contains;
    std::mt19937 rng(53);
    const int n = 6;
    for (LuminationTransfer tr : {LuminationTransfer::Reinhard, LuminationTransfer::Clamp})
        for (auto [lo, hi] : {std::pair{-1.0f, 1.0f}, std::pair{0.0f, 1.0f}}) {
            INFO(lumination_transfer_name(tr) << " [" << lo << ", " << hi << "]");
            SurroundPipeline pl(test::device(), n, GlobalViewMode::Thesis, tr);
            ModelConfig cfg;
            cfg.input_nc = 10;
            cfg.input_range[0] = cfg.output_range[0] = lo;
            cfg.input_range[1] = cfg.output_range[1] = hi;
            Frame fr;
            fr.n = n;
            fr.get(Feature::Albedo, Face::Front) = Image(n, n, 3, 0.5f);
            fr.get(Feature::Normal, Face::Front) = Image(n, n, 3, 0.0f);
            fr.get(Feature::Depth, Face::Front) = Image(n, n, 1, 1.0f);
            Image light(n, n, 3);
            light.data = test::random_vector(light.data.size(), rng, 0.0f, tr == LuminationTransfer::Clamp ? 1.0f : 200.0f);
            light.data[0] = 0.0f;
            fr.get(Feature::Direct, Face::Front) = light;
            const Tensor t = pl.encode_lightmap(light, cfg);
            REQUIRE(t.shape == std::vector<int>{1, 3, n, n});
            // Bit for bit the front view's lumination channels (7..9) of the network input.
            const Tensor x = pl.network_input(fr, cfg);
            REQUIRE(std::memcmp(t.data.data(), &x.data[7 * t.data.size() / 3], t.data.size() * sizeof(float)) == 0);
            // Decoding gives the light back (float rounding of 1 - y aside).
            const Image back = pl.front_lightmap(t, cfg);
            for (std::size_t i = 0; i < back.data.size(); ++i)
                REQUIRE(back.data[i] == Approx(light.data[i]).epsilon(5e-5).margin(1e-6));
            // Hostile light is sanitized like lumination: NaN and negative -> 0 (lo), +Inf -> the top (hi).
            Image bad(3, 1, 3, 0.0f);
            bad.data = {kNaN, -5.0f, kInf, -kInf, 0.0f, FLT_MAX, 1.0f, 2.0f, 3.0f};
            const Tensor e = pl.encode_lightmap(bad, cfg);
            REQUIRE(e.shape == std::vector<int>{1, 3, 1, 3});
            REQUIRE(e.data[0] == lo);
            REQUIRE(e.data[1] == lo);
            REQUIRE(e.data[2] == hi);
            REQUIRE(e.data[3] == lo);
            REQUIRE(e.data[5] == hi);
        }
    SurroundPipeline pl(test::device(), n);
    ModelConfig cfg;
    REQUIRE_THROWS_WITH(pl.encode_lightmap(Image(n, n, 1), cfg), Contains("channels"));
    REQUIRE_THROWS_AS(pl.encode_lightmap(Image(), cfg), InputError);
    cfg.output_range[1] = cfg.output_range[0];
    REQUIRE_THROWS_WITH(pl.encode_lightmap(Image(n, n, 3), cfg), Contains("output_range"));
}

namespace {

// What decode_indirect adds, in float as the kernel does: NaN and negative -> 0, +Inf -> FLT_MAX.
float clean_light_f(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX); }

// Direct light with every hostile value an application's buffer may hold.
std::vector<float> hostile_direct(std::size_t count, std::mt19937& rng) {
    std::vector<float> d = test::random_vector(count, rng, -0.5f, 30.0f);
    sprinkle(d, rng, {kNaN, kInf, -kInf, -3.0f, 65504.0f, 70000.0f, 1e30f, FLT_MAX, 0.0f});
    return d;
}

}  // namespace

TEST_CASE("decode_indirect: decoded indirect light + sanitized direct, against a naive reference at odd sizes",
          "[pipeline][oclgrind]") {
    // The kernel itself at odd element counts and offsets (the pipeline only launches 3 N^2 with N even): each
    // value equals decode_lightmap's value + the cleaned direct light in float, saturating at FLT_MAX.
    detail::Context& c = test::ctx();
    detail::Kernel decode = c.kernel("compose", "decode_lightmap", detail::compose_defines());
    detail::Kernel indirect = c.kernel("compose", "decode_indirect", detail::compose_defines());
    std::mt19937 rng(71);
    std::uniform_int_distribution<int> size(1, 301), offset(0, 97);
    for (int trial = 0; trial < 12; ++trial) {
        const int count = trial == 0 ? 1 : size(rng) | 1;  // odd
        const int off = offset(rng);
        const bool reinhard = trial % 2 == 0;
        const float lo = trial % 3 == 0 ? 0.0f : -1.0f, hi = 1.0f;
        std::vector<float> v = test::random_vector(std::size_t(count), rng, lo - 0.2f, hi + 0.2f);
        sprinkle(v, rng, {kNaN, kInf, hi, std::nextafter(hi, lo)});
        std::vector<float> direct(std::size_t(off), kNaN);  // before the offset: never read
        const std::vector<float> d = hostile_direct(std::size_t(count), rng);
        direct.insert(direct.end(), d.begin(), d.end());
        CAPTURE(trial, count, off, reinhard, lo);

        detail::Buffer xb = test::upload(v), lb = test::upload(v), db = test::upload(direct);
        const std::size_t g[1] = {std::size_t(count)}, l[1] = {64};
        indirect.args(xb, count, lo, hi, int(!reinhard), db, off);
        c.launch(indirect, 1, g, l);
        decode.args(lb, count, lo, hi, int(!reinhard));
        c.launch(decode, 1, g, l);
        const std::vector<float> got = test::download(xb, std::size_t(count));
        const std::vector<float> light = test::download(lb, std::size_t(count));
        double worst = 0;
        for (int i = 0; i < count; ++i) {
            REQUIRE(std::isfinite(got[i]));
            REQUIRE(got[i] >= 0.0f);
            // Bit for bit: the lightmap mode's decoding plus the cleaned direct light.
            REQUIRE(got[i] == std::min(light[i] + clean_light_f(d[i]), FLT_MAX));
            const double want = std::min(ref::decode_light(v[i], lo, hi, reinhard) + ref::clean_light(d[i]),
                                         double(FLT_MAX));
            worst = std::max(worst, rel_err(got[i], want));
        }
        REQUIRE(worst < 2e-5);  // as the lightmap decoding's test: y / (1 - y) near 1
    }
}

TEST_CASE("front lightmap, output_mode indirect: the decoded output + the frame's front direct light",
          "[pipeline][oclgrind]") {
    using Catch::Matchers::Contains;
    std::mt19937 rng(73);
    for (int n : {2, 6, 10}) {
        SurroundPipeline pl(test::device(), n);
        ModelConfig lightmap_cfg, indirect_cfg;
        indirect_cfg.output_mode = "indirect";
        Frame fr;
        fr.n = n;
        Image direct(n, n, 3);
        direct.data = hostile_direct(direct.data.size(), rng);
        fr.get(Feature::Direct, Face::Front) = direct;
        for (bool global : {true, false}) {
            CAPTURE(n, global);
            Tensor y(global ? std::vector<int>{1, 3, 2 * n, 4 * n} : std::vector<int>{1, 3, n, n});
            y.data = test::random_vector(y.size(), rng, -1.1f, 1.1f);
            sprinkle(y.data, rng, {kNaN, 1.0f});
            const Image base = pl.front_lightmap(y, lightmap_cfg);
            // A lightmap-mode model does not read the frame: the same result with or without it.
            REQUIRE(pl.front_lightmap(y, lightmap_cfg, fr).data == base.data);
            const Image l = pl.front_lightmap(y, indirect_cfg, fr);
            REQUIRE(l.width == n);
            REQUIRE(l.channels == 3);
            for (std::size_t i = 0; i < l.data.size(); ++i)
                REQUIRE(l.data[i] == std::min(base.data[i] + clean_light_f(direct.data[i]), FLT_MAX));
        }
        // Without the frame, or with a frame that lacks the front direct light: refused, saying what is missing.
        const Tensor y({1, 3, n, n});
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, indirect_cfg),
                            Contains("indirect") && Contains("needs the frame's front direct light"));
        Frame no_direct;
        no_direct.get(Feature::Direct, Face::Back) = direct;
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, indirect_cfg, no_direct),
                            Contains("'direct'") && Contains("'front'") && Contains("missing"));
        Frame wrong_size;
        wrong_size.get(Feature::Direct, Face::Front) = Image(n + 2, n + 2, 3);
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, indirect_cfg, wrong_size), Contains("'direct'"));
        ModelConfig bad = indirect_cfg;
        bad.output_mode = "residual";
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, bad, fr), Contains("residual") && Contains("\"indirect\""));
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, bad), Contains("residual"));
    }
}

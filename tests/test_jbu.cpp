// Joint bilateral upsampling (ops/jbu.*) against the double-precision reference (tests/reference_jbu.hpp) on
// synthetic scenes of planar regions seen at both resolutions (tests/jbu_scene.hpp): the property the op exists for
// (no light bleeds across a depth step or a crease where bilinear does), the bilinear fallback, surfaceless pixels,
// HDR and non-finite values, surfaces 10^5 m away, both kernels under the simulators, and bad input.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded,
// random scenes, sizes and ratios (odd, non-integer, 1x, down), radii, normal powers and both kernels among them;
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>

#include "ops/jbu.hpp"
#include "jbu_scene.hpp"
#include "reference_jbu.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;
using Catch::Matchers::Contains;
using namespace ngi::test::jbu_scene;

namespace {

struct Run {
    std::vector<float> out;
    int fallbacks = 0;
};

Run run_jbu(const test::JbuRefImage& low, const std::vector<float>& normal, const std::vector<float>& position, int W,
            int H, const JbuParams& params = {}) {
    auto& ctx = test::ctx();
    const Buffer v = test::upload(low.values), ln = test::upload(low.normal), lp = test::upload(low.position),
                 n = test::upload(normal), p = test::upload(position);
    Buffer out = ctx.alloc(std::size_t(low.channels) * W * H * sizeof(float), "test jbu output");
    JbuInputs in;
    in.low_width = low.width;
    in.low_height = low.height;
    in.channels = low.channels;
    in.low = v.get();
    in.low_normal = ln.get();
    in.low_position = lp.get();
    in.width = W;
    in.height = H;
    in.normal = n.get();
    in.position = p.get();
    JointBilateralUpsample op(ctx);
    Run r;
    r.fallbacks = op.enqueue(ctx, in, params, out.get());
    r.out = test::download(out, std::size_t(low.channels) * W * H);
    return r;
}


test::JbuRefImage low_view(const Scene& s, int w, int h, int channels, std::vector<float> values) {
    const Guides g = render_guides(s, w, h);
    return {w, h, channels, std::move(values), g.normal, g.position};
}

// The reference's borderline pixels (a fallback decision within 1% of the threshold: the float kernel may decide
// the other way there), flagged in every channel: the elements a comparison skips.
std::vector<char> borderline_mask(const test::JbuRefResult& ref, int channels) {
    std::vector<char> mask;
    for (int c = 0; c < channels; ++c) mask.insert(mask.end(), ref.borderline.begin(), ref.borderline.end());
    return mask;
}

// Float weights (exp, pow of up to 36 taps) against double: observed < 1e-5 of the value range.
test::Tol weights(double range) {
    return test::Tol::scaled(1e-4, "float exp/pow weights of up to 36 taps, observed < 1e-5").of(range);
}
// Where a saturated tap (FLT_MAX) takes part the sums are near FLT_MAX: relative to the largest magnitude.
const test::Tol kSaturated = test::Tol::scaled(1e-5, "sums of taps near FLT_MAX").of(FLT_MAX);

}  // namespace

// Outside the harness: the property the op exists for, with plain bilinear failing the same check.
TEST_CASE("JBU: no light crosses a depth step or a crease, bilinear does", "[jbu]") {
    // A floor (y = 0, normal +y) with a one-block platform (y = 1, also +y: a depth step only the plane term
    // separates) and a wall (x = 0, normal +x: a crease the normal term separates), at 4x, edges off the grid.
    Scene s;
    s.regions.push_back({0.0, 0.0, 0.37, 1.0, {0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}});      // wall
    s.regions.push_back({0.37, 0.0, 0.71, 0.58, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}});    // platform
    s.regions.push_back({0.0, 0.0, 1.0, 1.0, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}});       // floor
    const std::array<float, 3> light = {0.25f, 3.0f, 1.0f};  // per region
    const int w = 13, h = 11, W = 4 * w, H = 4 * h;
    const Guides lo = render_guides(s, w, h), hi = render_guides(s, W, H);
    std::vector<float> values(std::size_t(w) * h);
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = light[lo.region[i]];
    const test::JbuRefImage low{w, h, 1, values, lo.normal, lo.position};
    const Run got = run_jbu(low, hi.normal, hi.position, W, H);

    // The bilinear resize of the same image, for contrast: full-resolution normals no tap faces (-z) make every
    // pixel fall back.
    std::vector<float> away(hi.normal.size(), 0.0f);
    std::fill(away.begin() + 2 * W * H, away.end(), -1.0f);
    const Run bilinear = run_jbu(low, away, hi.position, W, H);
    CHECK(bilinear.fallbacks == W * H);

    std::vector<double> want(std::size_t(W) * H);
    for (std::size_t i = 0; i < want.size(); ++i) want[i] = light[hi.region[i]];
    CHECK(got.fallbacks == 0);
    // Each output pixel sees taps of its own region only: their normalized weights sum to 1 within rounding.
    test::check_close(got.out, want, test::Tol::relative(1e-5, "a normalized sum of equal values"));
    // The same test fails for plain bilinear: it bleeds across both edges, by more than half the light somewhere.
    CHECK_FALSE(test::compare(bilinear.out, want, test::Tol::relative(0.5, "bilinear bleeds across the edges")).ok);
}

// Outside the harness: the fallback and surfaceless pixels, pixel by pixel, on a hand-built scene.
TEST_CASE("JBU: a surface the low resolution does not see falls back to bilinear, no surface gives 0", "[jbu]") {
    // Low: floor only. High: the floor, a wall facing -z the low image never saw (fallback), and sky (0).
    Scene low_scene, hi_scene;
    const Region floor{0.0, 0.0, 1.0, 1.0, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}};
    low_scene.regions = {floor};
    hi_scene.regions = {{0.5, 0.1, 0.8, 0.5, {0, 0, 4}, {-1, 0, 0}, {0, 1, 0}, {0, 0, -1}},
                        {0.1, 0.6, 0.4, 0.9, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}},
                        floor};
    std::mt19937 rng(7);
    const int w = 9, h = 7, W = 36, H = 28, channels = 3;
    const test::JbuRefImage low =
        low_view(low_scene, w, h, channels, test::random_vector(std::size_t(channels) * w * h, rng, 0.5f, 2.0f));
    const Guides hi = render_guides(hi_scene, W, H);
    const test::JbuRefResult ref = test::jbu_reference(low, hi.normal, hi.position, W, H, {});
    const Run got = run_jbu(low, hi.normal, hi.position, W, H);
    int wall = 0;
    for (std::size_t i = 0; i < std::size_t(W) * H; ++i) {
        CHECK(bool(ref.fallback[i]) == (hi.region[i] == 0));
        wall += hi.region[i] == 0;
        if (hi.region[i] == 1)
            for (int c = 0; c < channels; ++c) CHECK(got.out[c * W * H + i] == 0.0f);
    }
    CHECK(wall > 0);
    CHECK(got.fallbacks == wall);
    test::check_close(got.out, ref.out, test::Tol::scaled(1e-5, "bilinear and planar taps, values <= 2").of(2.0),
                      borderline_mask(ref, channels));
}

// Outside the harness: extremes (HDR and non-finite values and guides, surfaces 1e5 m away).
TEST_CASE("JBU: HDR and non-finite values, constant images, surfaces 1e5 m away", "[jbu]") {
    std::mt19937 rng(11);
    Scene s;
    // Axis-aligned planes far from the origin (a distant horizon): positions near 1e5, float spacing 0.008 m.
    for (double far : {0.0, 1.0e4, 1.0e5}) {
        s.regions = {{0.0, 0.0, 0.45, 1.0, {far, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}},
                     {0.0, 0.0, 1.0, 1.0, {0, far, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}}};
        const int w = 10, h = 8, W = 40, H = 32;
        const Guides lo = render_guides(s, w, h), hi = render_guides(s, W, H);
        INFO("surfaces at " << far << " m");
        // A constant image stays constant (the weights are normalized), to float rounding; FLT_MAX stays finite.
        for (float value : {0.0f, 1.0f, 65504.0f, 1.0e30f, FLT_MAX}) {
            const test::JbuRefImage low{w, h, 1, std::vector<float>(std::size_t(w) * h, value), lo.normal, lo.position};
            const Run got = run_jbu(low, hi.normal, hi.position, W, H);
            INFO("constant " << value);
            CHECK(got.fallbacks == 0);
            test::check_close(got.out, std::vector<float>(got.out.size(), value),
                              test::Tol::relative(2e-6, "16 normalized weights' rounding"));
        }
    }
    // Hostile values: NaN -> 0, +-Inf -> +-FLT_MAX, HDR beyond half precision; outputs finite and as the reference.
    const int w = 6, h = 5, W = 17, H = 13;
    s.regions = {random_region(rng, 0, 0, 1, 1)};
    std::vector<float> values = test::random_vector(std::size_t(w) * h, rng, 0.0f, 1.0e5f);
    values[0] = std::numeric_limits<float>::quiet_NaN();
    values[3] = std::numeric_limits<float>::infinity();
    values[7] = -std::numeric_limits<float>::infinity();
    values[12] = 65504.0f * 4;
    values[20] = FLT_MAX;
    const test::JbuRefImage low = low_view(s, w, h, 1, values);
    const Guides hi = render_guides(s, W, H);
    const Run got = run_jbu(low, hi.normal, hi.position, W, H);
    const test::JbuRefResult ref = test::jbu_reference(low, hi.normal, hi.position, W, H, {});
    CHECK(test::all_finite(got.out));
    test::check_close(got.out, ref.out, kSaturated, borderline_mask(ref, 1));
    // Non-finite guides: a NaN normal or position makes a tap (or a pixel) surfaceless, never a NaN output.
    test::JbuRefImage broken = low;
    broken.normal[1] = std::numeric_limits<float>::quiet_NaN();
    broken.position[2 * w * h + 4] = std::numeric_limits<float>::infinity();
    std::vector<float> hi_normal = hi.normal;
    hi_normal[5] = std::numeric_limits<float>::quiet_NaN();
    const Run got2 = run_jbu(broken, hi_normal, hi.position, W, H);
    const test::JbuRefResult ref2 = test::jbu_reference(broken, hi_normal, hi.position, W, H, {});
    CHECK(test::all_finite(got2.out));
    CHECK(got2.out[5] == 0.0f);
    test::check_close(got2.out, ref2.out, kSaturated, borderline_mask(ref2, 1));
}

// Outside the harness: the Rows8 kernel (a knob) under oclgrind; the tiny row takes the default.
TEST_CASE("JBU: small random case for the simulators", "[jbu][oclgrind]") {
    std::mt19937 rng(3);
    const Scene scene = random_scene(rng);
    const int w = 5, h = 3, W = 19, H = 11, channels = 3;
    const test::JbuRefImage low =
        low_view(scene, w, h, channels, test::random_vector(std::size_t(channels) * w * h, rng, 0.0f, 1.0f));
    const Guides hi = render_guides(scene, W, H);
    const test::JbuRefResult ref = test::jbu_reference(low, hi.normal, hi.position, W, H, {});
    // Both kernels: jbu_upsample8 runs by default only on PoCL's CPU devices (ops/jbu.hpp), and oclgrind is where its
    // gathers are checked for bounds and uninitialized reads. Not on Mesa's llvmpipe: building it there takes ~65 s.
    const bool llvmpipe = test::device().info().name.rfind("llvmpipe", 0) == 0;
    for (JbuParams::Kernel k : {JbuParams::Kernel::OnePixel, JbuParams::Kernel::Rows8}) {
        if (llvmpipe && k == JbuParams::Kernel::Rows8) continue;
        JbuParams p;
        p.kernel = k;
        const Run got = run_jbu(low, hi.normal, hi.position, W, H, p);
        test::check_close(got.out, ref.out, weights(1.0), borderline_mask(ref, channels));
        CHECK(got.fallbacks == ref.fallbacks);
    }
}

// Outside the harness: two paths of one kernel against each other, bit for bit. jbu_upsample8 reads the taps once per
// work-item where its eight pixels share their tap columns (outputs ~8x the input and more, as a display view is);
// that path must give the per-lane gathers' exact bits, hostile values and broken guides included. Ratios 6.7 to 16
// (both paths taken within one image below ~8), 1 to 4 channels, every radius, widths that are not multiples of 8.
// Small enough for oclgrind, where the tap records' reads (jbu_pack_taps) are checked for bounds.
TEST_CASE("JBU: the 8-pixel kernel's shared tap columns give the gathers' bits", "[jbu][oclgrind]") {
    // Not on Mesa's llvmpipe: building jbu_upsample8 there takes ~65 s, and only PoCL's CPUs run it by default.
    if (test::device().info().name.rfind("llvmpipe", 0) == 0) {
        WARN("jbu_upsample8 is not built on llvmpipe (~65 s); its paths are compared on PoCL and oclgrind");
        return;
    }
    std::mt19937 rng(11);
    const std::array<std::array<int, 4>, 4> shapes = {{{3, 2, 41, 13}, {4, 3, 27, 20}, {2, 2, 32, 9}, {5, 1, 53, 7}}};
    for (int k = 0; k < 4; ++k) {
        const auto [w, h, W, H] = shapes[std::size_t(k)];
        const Scene scene = random_scene(rng);
        const int channels = 1 + k;
        std::vector<float> values = test::random_vector(std::size_t(channels) * w * h, rng, -1.0f, 4.0f);
        values[0] = std::numeric_limits<float>::quiet_NaN();
        values[1] = k % 2 ? FLT_MAX : -std::numeric_limits<float>::infinity();
        test::JbuRefImage low = low_view(scene, w, h, channels, values);
        if (k == 1) low.normal[2] = std::numeric_limits<float>::quiet_NaN();  // a tap without a surface
        if (k == 2) low.position[w * h + 1] = std::numeric_limits<float>::infinity();
        const Guides hi = render_guides(scene, W, H);
        JbuParams p;
        p.kernel = JbuParams::Kernel::Rows8;
        p.radius = 1 + k % 3;
        if (k == 3) p.normal_power = 7.5f;
        const Run shared = run_jbu(low, hi.normal, hi.position, W, H, p);
        p.shared_columns = false;
        const Run gathered = run_jbu(low, hi.normal, hi.position, W, H, p);
        INFO("shape " << k << ": " << w << "x" << h << " -> " << W << "x" << H);
        REQUIRE(shared.out.size() == gathered.out.size());
        int differ = 0;
        for (std::size_t i = 0; i < shared.out.size(); ++i)
            differ += std::memcmp(&shared.out[i], &gathered.out[i], sizeof(float)) != 0;
        CHECK(differ == 0);
        CHECK(shared.fallbacks == gathered.fallbacks);
    }
}

// Outside the harness: refusals.
TEST_CASE("JBU: bad input names the parameter or buffer", "[jbu]") {
    auto& ctx = test::ctx();
    JointBilateralUpsample op(ctx);
    Buffer small = ctx.alloc(16, "small"), big = ctx.alloc(3 * 64 * 64 * sizeof(float), "big"),
           out = ctx.alloc(3 * 64 * 64 * sizeof(float), "out");
    JbuInputs in;
    in.low_width = in.low_height = 8;
    in.width = in.height = 32;
    in.channels = 3;
    in.low = in.low_normal = in.low_position = in.normal = in.position = big.get();
    CHECK(op.enqueue(ctx, in, {}, out.get()) >= 0);  // the valid call the cases below break one field of

    auto expect = [&](JbuInputs bad, JbuParams params, cl_mem o, const std::string& what) {
        CHECK_THROWS_WITH(op.enqueue(ctx, bad, params, o), Contains("joint bilateral upsampling") && Contains(what));
    };
    JbuInputs b = in;
    b.low_width = 0;
    expect(b, {}, out.get(), "low-resolution width 0");
    b = in;
    b.height = kJbuMaxSide + 1;
    expect(b, {}, out.get(), "output height");
    b = in;
    b.channels = 0;
    expect(b, {}, out.get(), "0 channels");
    b = in;
    b.normal = nullptr;
    expect(b, {}, out.get(), "the normal buffer is null");
    b = in;
    b.low_position = small.get();
    expect(b, {}, out.get(), "low-resolution position buffer holds 16 bytes");
    expect(in, {}, small.get(), "output buffer holds 16 bytes");
    expect(in, {}, big.get(), "output buffer is also an input");
    JbuParams p;
    p.sigma_spatial = std::numeric_limits<float>::quiet_NaN();
    expect(in, p, out.get(), "sigma_spatial");
    p = {};
    p.sigma_plane = 0.0f;
    expect(in, p, out.get(), "sigma_plane");
    p = {};
    p.sigma_plane = 1e-30f;
    expect(in, p, out.get(), "overflows");
    p = {};
    p.normal_power = -1.0f;
    expect(in, p, out.get(), "normal_power");
    p = {};
    p.radius = kJbuMaxRadius + 1;
    expect(in, p, out.get(), "radius 4");
    p = {};
    p.fallback_ratio = 1.0f;
    expect(in, p, out.get(), "fallback_ratio");
}

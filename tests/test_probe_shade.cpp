// Probe shading (ops/probe_shade.*) against the double-precision reference (tests/reference_voxel.hpp): hit points
// exactly on block edges and corners, every kind of miss and its count, the counts left on the device, bad input.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded,
// random cameras and faces among them (NaN and Inf pixels, both field modes, odd and even faces);
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <array>
#include <cstdint>
#include <limits>

#include "ops/probe_shade.hpp"
#include "reference_voxel.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

using Vec = std::array<double, 3>;

template <class T>
Buffer upload_raw(const std::vector<T>& v) {
    Buffer b = test::ctx().alloc(std::max<std::size_t>(1, v.size()) * sizeof(T), "test input");
    if (!v.empty()) test::ctx().write(b, 0, v.size() * sizeof(T), v.data(), "test input");
    return b;
}

// A camera face as the op takes it, rounded to float, and the same floats in double for the reference (the float
// camera is the one both see).
void set_camera(test::ProbeRefInputs& r, const Vec& centre, const Vec& look, const Vec& right, const Vec& up) {
    for (int c = 0; c < 3; ++c) {
        r.centre[c] = float(centre[c]);
        r.look[c] = float(look[c]);
        r.right[c] = float(right[c]);
        r.up[c] = float(up[c]);
    }
}

// Runs the op on the reference's inputs; returns the lighting [3][n*n] and the counts.
std::vector<float> shade(ProbeShade& op, const test::ProbeRefInputs& r, ProbeShadeCounts* counts, int* returned) {
    auto& ctx = test::ctx();
    const Buffer depth = upload_raw(r.depth), normal = upload_raw(r.normal), index = upload_raw(r.index_of),
                 field = upload_raw(r.field);
    ProbeShadeInputs in;
    in.n = r.n;
    in.depth = depth.get();
    in.normal = normal.get();
    for (int c = 0; c < 3; ++c) {
        in.camera.centre[c] = float(r.centre[c]);
        in.camera.look[c] = float(r.look[c]);
        in.camera.right[c] = float(r.right[c]);
        in.camera.up[c] = float(r.up[c]);
        in.grid[c] = r.grid[c];
    }
    in.index_of = index.get();
    in.voxels = r.voxels;
    in.mode = r.sh ? ProbeField::Sh : ProbeField::PerVoxel;
    in.field = field.get();
    Buffer out = ctx.alloc(std::size_t(3) * r.n * r.n * sizeof(float), "test out");
    *returned = op.enqueue(ctx, in, out.get());
    *counts = op.counts(ctx);
    return test::download(out, std::size_t(3) * r.n * r.n);
}

std::vector<float> random_field(int V, bool sh, std::mt19937& rng) {
    std::vector<float> f = test::random_vector(std::size_t(V) * (sh ? 27 : 4), rng, -1.0f, 1.0f);
    if (sh)  // band 0 mostly dominant, so most pixels are lit and some are clamped at 0
        for (int i = 0; i < V; ++i)
            for (int c = 0; c < 3; ++c) f[std::size_t(27) * i + 9 * c] = std::abs(f[std::size_t(27) * i + 9 * c]) * 3.0f;
    else
        for (float& x : f) x = std::abs(x) * 5.0f;
    return f;
}

}  // namespace

// Outside the harness: hand-placed hit points on block edges and corners, every kind of miss counted.
TEST_CASE("probe shading: hit points exactly on block edges and corners find the block, misses are counted",
          "[probe]") {
    auto& ctx = test::ctx();
    ProbeShade op(ctx);
    // n = 3: the centre pixel looks exactly along look = -y (u = v = 0), from (3, 8, 3) down to the plane y = 5:
    // the hit point (3, 5, 3) is the corner shared by the top faces of blocks (2..3, 4, 2..3).
    auto face = [](int occupied_cells) {
        test::ProbeRefInputs r;
        r.n = 3;
        r.sh = false;
        for (int c = 0; c < 3; ++c) r.grid[c] = 6;
        set_camera(r, {3.0, 8.0, 3.0}, {0, -1, 0}, {1, 0, 0}, {0, 0, -1});  // right x up = (0, 1, 0) = -look
        r.depth.assign(9, 1.0e4f);
        r.normal.assign(27, 0.0f);
        r.depth[4] = 3.0f;
        r.normal[9 + 4] = 1.0f;
        r.index_of.assign(216, -1);
        r.voxels = occupied_cells;
        return r;
    };
    auto id = [](int x, int y, int z) { return x + 6 * (y + 6 * z); };
    // q = (3, 4.5, 3) (half a block behind the face); its 0.25-m neighbourhood spans blocks x, z in {2, 3}, y = 4.
    struct Case {
        std::vector<std::array<int, 3>> blocks;  // occupied; voxel k is blocks[k]
        int expect;                              // the voxel the centre pixel must use, -1 = a miss
    };
    const Case cases[] = {
        {{{3, 4, 3}}, 0},             // the cell the point rounds to
        {{{2, 4, 3}}, 0},             // across the x edge
        {{{3, 4, 2}}, 0},             // across the z edge
        {{{2, 4, 2}}, 0},             // across the corner
        {{{2, 4, 2}, {3, 4, 3}}, 1},  // the cell itself wins over a neighbour
        {{{2, 4, 2}, {2, 4, 3}}, 1},  // an axis neighbour wins over a diagonal one
        {{{3, 5, 3}}, -1},            // the block in front of the face (0.5 m away) is never taken
        {{{0, 0, 0}}, -1},            // nothing near
    };
    for (const Case& k : cases) {
        test::ProbeRefInputs r = face(int(k.blocks.size()));
        for (std::size_t b = 0; b < k.blocks.size(); ++b)
            r.index_of[id(k.blocks[b][0], k.blocks[b][1], k.blocks[b][2])] = int(b);
        r.field.resize(std::size_t(4) * r.voxels);
        for (int v = 0; v < r.voxels; ++v)
            for (int c = 0; c < 4; ++c) r.field[std::size_t(4) * v + c] = float(10 * (v + 1) + c);
        ProbeShadeCounts counts;
        int returned = 0;
        const std::vector<float> got = shade(op, r, &counts, &returned);
        const test::ProbeRefResult want = test::probe_shade_reference(r);
        CAPTURE(k.blocks.size(), k.blocks[0][0], k.blocks[0][1], k.blocks[0][2]);
        REQUIRE(want.voxel[4] == k.expect);  // the reference agrees with the intent
        REQUIRE(counts.no_voxel == (k.expect < 0 ? 1 : 0));
        REQUIRE(counts.non_finite == 0);
        REQUIRE(returned == counts.no_voxel);
        for (int pix = 0; pix < 9; ++pix)
            for (int c = 0; c < 3; ++c) {
                const float expect = pix == 4 && k.expect >= 0 ? float(10 * (k.expect + 1) + c) : 0.0f;
                REQUIRE(got[std::size_t(c) * 9 + pix] == expect);
            }
    }

    // Every way to miss on one face: sky (not counted), NaN/Inf depth or normal, a zero normal under a surface
    // depth, a point outside the grid, an empty block far from any voxel.
    test::ProbeRefInputs r = face(1);
    r.index_of[id(3, 4, 3)] = 0;
    r.field = {1.0f, 2.0f, 3.0f, 0.0f};
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    r.depth = {1.0e4f, nan, inf, 3.0f, 3.0f, 3.0f, 100.0f, 1.5f, -inf};
    r.normal.assign(27, 0.0f);
    for (int pix = 0; pix < 9; ++pix) r.normal[9 + pix] = 1.0f;  // +y everywhere ...
    r.normal[0] = 0.0f;                                          // ... pixel 0: sky
    r.normal[3] = nan;                                           // pixel 3: NaN normal x
    r.normal[9 + 5] = 0.0f;                                      // pixel 5: no normal at all
    ProbeShadeCounts counts;
    int returned = 0;
    const std::vector<float> got = shade(op, r, &counts, &returned);
    const test::ProbeRefResult want = test::probe_shade_reference(r);
    // Non-finite: pixels 1, 2, 3, 8. No voxel: 5 (zero normal), 6 (below the grid), 7 (empty block (.., 5, ..)).
    CHECK(counts.non_finite == 4);
    CHECK(counts.no_voxel == 3);
    CHECK(returned == 7);
    CHECK(want.non_finite == 4);
    CHECK(want.no_voxel == 3);
    {  // read_counts = false: nothing moves through the host; the counters wait on the device
        const Buffer depth = upload_raw(r.depth), normal = upload_raw(r.normal), index = upload_raw(r.index_of),
                     field = upload_raw(r.field);
        Buffer out = ctx.alloc(27 * sizeof(float), "test out");
        ProbeShadeInputs in;
        in.n = 3;
        in.depth = depth.get();
        in.normal = normal.get();
        for (int c = 0; c < 3; ++c) {
            in.camera.centre[c] = float(r.centre[c]);
            in.camera.look[c] = float(r.look[c]);
            in.camera.right[c] = float(r.right[c]);
            in.camera.up[c] = float(r.up[c]);
            in.grid[c] = r.grid[c];
        }
        in.index_of = index.get();
        in.voxels = r.voxels;
        in.mode = ProbeField::PerVoxel;
        in.field = field.get();
        const HostTransfers t0 = ctx.transfers();
        REQUIRE(op.enqueue(ctx, in, out.get(), false) == -1);
        const HostTransfers t1 = ctx.transfers();
        REQUIRE(t1.uploads == t0.uploads);
        REQUIRE(t1.downloads == t0.downloads);
        const ProbeShadeCounts later = op.counts(ctx);
        CHECK(later.non_finite == 4);
        CHECK(later.no_voxel == 3);
    }
    REQUIRE(test::all_finite(got));
    for (int pix = 0; pix < 9; ++pix)
        for (int c = 0; c < 3; ++c) REQUIRE(got[std::size_t(c) * 9 + pix] == (pix == 4 ? float(c + 1) : 0.0f));
}

// Outside the harness: refusals.
TEST_CASE("probe shading: bad input is an InputError naming it", "[probe]") {
    auto& ctx = test::ctx();
    ProbeShade op(ctx);
    const int n = 4;
    Buffer depth = ctx.alloc(n * n * sizeof(float), "test depth");
    Buffer normal = ctx.alloc(3 * n * n * sizeof(float), "test normal");
    Buffer index = ctx.alloc(8 * sizeof(int), "test index"), field = ctx.alloc(27 * 2 * sizeof(float), "test field");
    Buffer out = ctx.alloc(3 * n * n * sizeof(float), "test out");
    ProbeShadeInputs good;
    good.n = n;
    good.depth = depth.get();
    good.normal = normal.get();
    good.grid[0] = good.grid[1] = good.grid[2] = 2;
    good.index_of = index.get();
    good.voxels = 2;
    good.field = field.get();
    auto fails = [&](const ProbeShadeInputs& in, cl_mem o, const std::string& what) {
        CAPTURE(what);
        try {
            op.enqueue(ctx, in, o);
            FAIL("no InputError");
        } catch (const InputError& e) {
            CHECK_THAT(e.what(), Catch::Contains(what));
        }
    };
    ProbeShadeInputs in = good;
    in.n = 0;
    fails(in, out.get(), "face size");
    in = good;
    in.grid[1] = 0;
    fails(in, out.get(), "grid");
    in = good;
    in.grid[2] = 3;  // 12 blocks, index_of holds 8
    fails(in, out.get(), "index_of");
    in = good;
    in.voxels = 3;
    fails(in, out.get(), "SH field");
    in = good;
    in.depth = nullptr;
    fails(in, out.get(), "depth");
    in = good;
    in.camera.look[1] = std::numeric_limits<float>::quiet_NaN();
    fails(in, out.get(), "look");
    in = good;
    fails(in, index.get(), "output");
    fails(good, normal.get(), "output buffer is also an input");
}

// Outside the harness: the per-voxel field under oclgrind (the tiny row is SH-27).
TEST_CASE("probe shading at a small shape (oclgrind: bounds, races, uninitialized reads)", "[oclgrind][probe]") {
    std::mt19937 rng(4104);
    auto& ctx = test::ctx();
    ProbeShade op(ctx);
    for (int sh = 0; sh < 2; ++sh) {
        test::ProbeRefInputs r;
        r.n = 3;
        r.sh = sh;
        for (int c = 0; c < 3; ++c) r.grid[c] = 3;
        set_camera(r, {1.5, 1.5, 6.0}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0});  // looking at the +z faces of z = 1 blocks
        r.depth.assign(9, 4.0f);  // the plane z = 2
        r.normal.assign(27, 0.0f);
        for (int pix = 0; pix < 9; ++pix) r.normal[18 + pix] = 1.0f;
        r.depth[0] = 1.0e4f;
        r.normal[18] = 0.0f;
        r.index_of.assign(27, -1);
        for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 2; ++y) r.index_of[x + 3 * (y + 3 * 1)] = r.voxels++;  // row y = 2 missing: misses
        r.field = random_field(r.voxels, sh, rng);
        ProbeShadeCounts counts;
        int returned = 0;
        const std::vector<float> got = shade(op, r, &counts, &returned);
        const test::ProbeRefResult want = test::probe_shade_reference(r);
        CAPTURE(sh);
        REQUIRE(counts.no_voxel == want.no_voxel);
        REQUIRE(want.no_voxel > 0);
        test::require_close(got, want.lighting, test::tol::short_sum());
    }
}

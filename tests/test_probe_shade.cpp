// Probe shading (ops/probe_shade.*) against the double-precision reference (tests/reference_voxel.hpp): random
// cameras and synthetic depth/normal faces whose pixels land on known voxels, both field modes, odd and even faces,
// hit points exactly on block edges and corners, and the miss counts.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded;
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

Vec cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec normalized(Vec a) {
    const double l = std::sqrt(dot(a, a));
    for (double& x : a) x /= l;
    return a;
}

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

// True when x is within `margin` of a multiple of 0.25: the kernel (float) and the reference (double) could pick
// different cells for it or for its 0.25-m neighbours.
bool near_lattice(double x, double margin) {
    const double k = x * 4.0;
    return std::abs(k - std::round(k)) < margin * 4.0;
}

}  // namespace

// Outside the harness: random camera orientations and NaN/Inf pixels; the rows look down -z.
TEST_CASE("probe shading = the reference on random cameras and faces (both fields, odd and even n)", "[probe]") {
    std::mt19937 rng(4101);
    auto& ctx = test::ctx();
    ProbeShade op(ctx);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int n : {1, 2, 7, 16, 33}) {
        for (int sh = 0; sh < 2; ++sh) {
            test::ProbeRefInputs r;
            r.n = n;
            r.sh = sh;
            for (int c = 0; c < 3; ++c) r.grid[c] = 4 + int(rng() % 7);
            // A random orthonormal face basis with right x up = -look (docs/CONVENTIONS.md section 2).
            const Vec look = normalized({g(rng), g(rng), g(rng)});
            Vec right = {g(rng), g(rng), g(rng)};
            const double k = dot(right, look);
            for (int c = 0; c < 3; ++c) right[c] -= k * look[c];
            right = normalized(right);
            const Vec up = cross(right, look);
            Vec centre;  // in or near the grid
            for (int c = 0; c < 3; ++c) centre[c] = u01(rng) * (r.grid[c] + 4) - 2;
            set_camera(r, centre, look, right, up);
            const int npix = n * n;
            r.depth.assign(npix, 1.0e4f);
            r.normal.assign(std::size_t(3) * npix, 0.0f);
            r.index_of.assign(std::size_t(r.grid[0]) * r.grid[1] * r.grid[2], -1);
            std::vector<int> cells;  // cells to occupy, in the order pixels claimed them
            for (int pix = 0; pix < npix; ++pix) {
                const double kind = u01(rng);
                if (kind < 0.1) continue;  // sky
                if (kind < 0.14) {         // a damaged pixel: NaN or Inf in depth or normal
                    if (rng() % 2) r.depth[pix] = std::numeric_limits<float>::quiet_NaN();
                    else r.normal[std::size_t(rng() % 3) * npix + pix] = std::numeric_limits<float>::infinity();
                    continue;
                }
                const int row = pix / n, col = pix % n;
                const double u = 2.0 * (col + 0.5) / n - 1.0, v = 1.0 - 2.0 * (row + 0.5) / n;
                Vec dir;
                for (int c = 0; c < 3; ++c) dir[c] = r.look[c] + u * r.right[c] + v * r.up[c];
                dir = normalized(dir);
                const double along = dir[0] * r.look[0] + dir[1] * r.look[1] + dir[2] * r.look[2];
                const int f = int(rng() % 6);
                double nr[3] = {0, 0, 0};
                nr[f >> 1] = (f & 1) ? -1.0 : 1.0;
                for (int attempt = 0;; ++attempt) {
                    REQUIRE(attempt < 1000);
                    const float depth = float(0.3 + u01(rng) * 14.0);
                    double q[3];
                    bool ambiguous = false;
                    for (int c = 0; c < 3; ++c) {
                        q[c] = r.centre[c] + dir[c] * (double(depth) / along) - 0.5 * nr[c];
                        ambiguous |= near_lattice(q[c], 2e-3);
                    }
                    if (ambiguous) continue;
                    r.depth[pix] = depth;
                    for (int c = 0; c < 3; ++c) r.normal[std::size_t(c) * npix + pix] = float(nr[c]);
                    // Occupy the block behind the face for three pixels in four (the others may still find a
                    // neighbour within 0.25 m, or miss).
                    bool inside = true;
                    for (int c = 0; c < 3; ++c) inside &= q[c] >= 0 && q[c] < r.grid[c];
                    if (inside && u01(rng) < 0.75)
                        cells.push_back(int(q[0]) + r.grid[0] * (int(q[1]) + r.grid[1] * int(q[2])));
                    break;
                }
            }
            if (n >= 7) {  // a surface pixel with no normal: counted as a miss
                r.depth[3] = 2.0f;
                for (int c = 0; c < 3; ++c) r.normal[std::size_t(c) * npix + 3] = 0.0f;
            }
            for (int extra = 0; extra < 10; ++extra) cells.push_back(int(rng() % r.index_of.size()));
            std::shuffle(cells.begin(), cells.end(), rng);
            for (int cell : cells)
                if (r.index_of[cell] < 0) r.index_of[cell] = r.voxels++;
            if (!r.index_of.empty()) r.index_of[rng() % r.index_of.size()] = r.voxels + 3;  // out of range: empty
            r.field = random_field(r.voxels, sh, rng);

            const test::ProbeRefResult want = test::probe_shade_reference(r);
            ProbeShadeCounts counts;
            int returned = 0;
            const std::vector<float> got = shade(op, r, &counts, &returned);
            CAPTURE(n, sh, r.voxels, want.no_voxel, want.non_finite);
            REQUIRE(counts.no_voxel == want.no_voxel);
            REQUIRE(counts.non_finite == want.non_finite);
            REQUIRE(returned == want.no_voxel + want.non_finite);
            test::require_close(got, want.lighting, test::tol::short_sum());
        }
    }
}

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

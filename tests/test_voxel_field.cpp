// Seed 004's voxel radiance field (ngi/voxel_field.hpp, docs/VOXEL_FIELD.md): the device compaction against a host
// loop, the path-traced SH ground truth against analytic answers (uniform sky, sun alone), the face lighting
// against the renderer's reference, determinism under any split of the samples, and the visibility mask against
// a host DDA.
#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "ngi/camera.hpp"
#include "ngi/error.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/voxel_field.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRayOffset = 1.0e-3;  // scene.cl RAY_OFFSET
const double kLobeA[9] = {kPi, 2 * kPi / 3, 2 * kPi / 3, 2 * kPi / 3, kPi / 4, kPi / 4, kPi / 4, kPi / 4, kPi / 4};

// Real SH bands 0-2, Condon-Shortley phase (docs/CONVENTIONS.md section 14), in double precision.
void sh9(double x, double y, double z, double* Y) {
    Y[0] = 0.28209479177387814;
    Y[1] = -0.48860251190291992 * y;
    Y[2] = 0.48860251190291992 * z;
    Y[3] = -0.48860251190291992 * x;
    Y[4] = 1.0925484305920792 * x * y;
    Y[5] = -1.0925484305920792 * y * z;
    Y[6] = 0.31539156525252005 * (3 * z * z - 1);
    Y[7] = -1.0925484305920792 * x * z;
    Y[8] = 0.54627421529603959 * (x * x - y * y);
}

// Lighting (irradiance / pi) toward unit normal n of channel c of voxel i's SH: (1/pi) sum A_l c_lm Y_lm(n).
double sh_lighting(const std::vector<float>& sh, std::size_t i, int c, glm::dvec3 n) {
    double Y[9];
    sh9(n.x, n.y, n.z, Y);
    double e = 0;
    for (int k = 0; k < 9; ++k) e += kLobeA[k] * sh[i * 27 + std::size_t(c) * 9 + std::size_t(k)] * Y[k];
    return e / kPi;
}

const glm::ivec3 kDirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// The definitions of docs/VOXEL_FIELD.md as a straight host loop.
struct HostVoxel {
    glm::ivec3 cell;
    int exposed = 0;
    glm::dvec3 normal, probe;
    float attr[kVoxelAttributes];
};

std::vector<HostVoxel> host_surface(const VoxelScene& s, const Lighting& l) {
    std::vector<HostVoxel> out;
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x) {
                const glm::ivec3 c(x, y, z);
                if (!s.solid(c)) continue;
                HostVoxel v;
                v.cell = c;
                for (int f = 0; f < 6; ++f)
                    if (!s.solid(c + kDirs[f])) v.exposed |= 1 << f;
                if (!v.exposed) continue;
                int first = -1;  // the stand-in face: the first exposed face toward the grid's interior, if any
                for (int f = 0; f < 6 && first < 0; ++f)
                    if (v.exposed >> f & 1 && s.inside(c + kDirs[f])) first = f;
                for (int f = 0; f < 6 && first < 0; ++f)
                    if (v.exposed >> f & 1) first = f;
                const glm::dvec3 nf(kDirs[first]);
                const glm::ivec3 grad(int(s.solid(c - glm::ivec3(1, 0, 0))) - int(s.solid(c + glm::ivec3(1, 0, 0))),
                                      int(s.solid(c - glm::ivec3(0, 1, 0))) - int(s.solid(c + glm::ivec3(0, 1, 0))),
                                      int(s.solid(c - glm::ivec3(0, 0, 1))) - int(s.solid(c + glm::ivec3(0, 0, 1))));
                glm::ivec3 g(0);
                for (int f = 0; f < 6; ++f)
                    if (v.exposed >> f & 1) g += kDirs[f];
                REQUIRE(g == grad);  // the sum of the exposed faces' normals is the occupancy gradient
                const bool flat = g == glm::ivec3(0);
                v.normal = flat ? nf : glm::normalize(glm::dvec3(g));
                const glm::dvec3 gp = flat || s.solid(c + g) ? nf : glm::dvec3(g);
                const glm::dvec3 centre = glm::dvec3(c) + 0.5;
                v.probe = centre + 0.5 * gp + kRayOffset * glm::normalize(gp);
                const Material& m = s.palette[s.at(c)];
                const glm::vec3 e = m.emission * (m.lamp ? l.lamp_level : 1.0f);
                const float a[kVoxelAttributes] = {float(x) + 0.5f, float(y) + 0.5f, float(z) + 0.5f,
                                                   m.albedo.r, m.albedo.g, m.albedo.b, e.r, e.g, e.b,
                                                   float(s.index(c))};
                std::copy(a, a + kVoxelAttributes, v.attr);
                out.push_back(v);
            }
    return out;
}

VoxelScene random_grid(glm::ivec3 size, double density, std::mt19937& rng) {
    VoxelScene s(size, "random");
    const std::uint8_t a = s.add_material({glm::vec3(0.3f, 0.5f, 0.7f), glm::vec3(0.0f), false});
    const std::uint8_t b = s.add_material({glm::vec3(0.9f, 0.1f, 0.2f), glm::vec3(1.5f, 0.5f, 0.25f), false});
    const std::uint8_t lamp = s.add_material({glm::vec3(0.8f), glm::vec3(3.0f, 2.0f, 1.0f), true});
    std::uniform_real_distribution<double> u(0, 1);
    for (auto& v : s.voxels) {
        const double r = u(rng);
        v = r >= density ? 0 : r < 0.8 * density ? a : r < 0.95 * density ? b : lamp;
    }
    return s;
}

void check_against_host(const VoxelScene& s, const Lighting& l) {
    INFO("grid " << s.size.x << "x" << s.size.y << "x" << s.size.z);
    const std::vector<HostVoxel> ref = host_surface(s, l);
    if (ref.empty()) {  // e.g. a 1x1x1 grid that came out empty
        CHECK_THROWS_WITH(surface_voxels(test::device(), s, l), Catch::Contains("no surface voxels"));
        return;
    }
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    REQUIRE(sv.grid == s.size);
    REQUIRE(sv.size() == ref.size());
    REQUIRE(sv.attributes.size() == ref.size() * kVoxelAttributes);
    REQUIRE(sv.index_of.size() == s.voxels.size());
    std::vector<std::int32_t> index(s.voxels.size(), -1);
    int creases = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) {
        const HostVoxel& h = ref[i];
        index[s.index(h.cell)] = std::int32_t(i);
        REQUIRE(sv.cell[i] == h.cell);
        REQUIRE(int(sv.exposed[i]) == h.exposed);
        for (int k = 0; k < kVoxelAttributes; ++k) REQUIRE(sv.attributes[i * kVoxelAttributes + k] == h.attr[k]);
        for (int k = 0; k < 3; ++k) {
            REQUIRE(std::abs(sv.normal[i][k] - h.normal[k]) < 1e-6);
            REQUIRE(std::abs(sv.probe[i][k] - h.probe[k]) < 1e-5);
        }
        creases += glm::length(glm::dvec3(sv.probe[i]) - (glm::dvec3(h.cell) + 0.5)) < 0.5 + 2e-3 &&
                   std::abs(glm::length(h.normal) - 1.0) < 1e-9 &&
                   std::abs(std::abs(h.normal.x) + std::abs(h.normal.y) + std::abs(h.normal.z) - 1.0) > 1e-6;
    }
    REQUIRE(sv.index_of == index);
    // Probe points lie in air (outside the grid counts as air).
    for (std::size_t i = 0; i < sv.size(); ++i) REQUIRE_FALSE(s.solid(glm::ivec3(glm::floor(sv.probe[i]))));
    INFO("creases (probe moved to a face centre): " << creases);
}

Lighting dark() { return Lighting{}; }

Lighting uniform_sky(glm::vec3 L) {
    Lighting l;
    l.sky.zenith = l.sky.horizon = l.sky.ground = L;
    return l;
}

}  // namespace

TEST_CASE("surface voxels: device compaction equals a host loop on random grids, empty and all-solid grids",
          "[voxel_field]") {
    std::mt19937 rng(4);
    Lighting l = dark();
    l.lamp_level = 0.375f;
    // Odd sizes; several tiles (4096 blocks each); the last one more than 64 tiles (the tile scan's chunk loop).
    const glm::ivec3 sizes[] = {{1, 1, 1}, {7, 5, 3}, {13, 9, 11}, {33, 17, 65}, {67, 65, 63}};
    for (const glm::ivec3 size : sizes)
        for (double density : {0.15, 0.6, 0.93}) check_against_host(random_grid(size, density, rng), l);

    VoxelScene full({9, 7, 5}, "full");  // all solid: the boundary blocks are the surface (outside is air)
    full.fill({0, 0, 0}, full.size, full.add_material({}));
    check_against_host(full, l);
    CHECK(surface_voxels(test::device(), full, l).size() == std::size_t(9 * 7 * 5 - 7 * 5 * 3));

    const VoxelScene empty({6, 5, 7}, "empty");
    CHECK_THROWS_AS(surface_voxels(test::device(), empty, l), InputError);
    CHECK_THROWS_WITH(surface_voxels(test::device(), empty, l), Catch::Contains("no surface voxels"));
    const VoxelScene huge({4097, 4096, 1}, "huge");  // 2^24 + 4096 blocks: ids no longer exact as floats
    CHECK_THROWS_WITH(surface_voxels(test::device(), huge, l), Catch::Contains("2^24"));
}

TEST_CASE("surface voxels: compaction at small shapes (oclgrind: bounds, races, uninitialized reads)",
          "[voxel_field][oclgrind]") {
    std::mt19937 rng(11);
    check_against_host(random_grid({5, 4, 3}, 0.5, rng), dark());
    check_against_host(random_grid({19, 3, 2}, 0.7, rng), dark());
}

TEST_CASE("voxel field: uniform sky over a floor gives the analytic SH, lighting L everywhere, nothing from below",
          "[voxel_field]") {
    VoxelScene s({9, 3, 9}, "floor");
    s.fill({0, 0, 0}, {9, 1, 9}, s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false}));
    const glm::vec3 L(0.2f, 0.5f, 1.0f);
    const Lighting l = uniform_sky(L);
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    REQUIRE(sv.size() == 81);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 1024;
    vs.point_samples = 64;
    vs.max_bounces = 2;
    vs.seed = 1;
    const VoxelField f = r.render_voxel_field(sv, l, vs);
    REQUIRE(f.sh.size() == 81 * 27);
    CHECK(f.rays > 0);

    // Radiance L over the upper hemisphere, 0 below (the floor): c_00 = 2 pi L Y_00 = sqrt(pi) L,
    // c_1-1 = -0.4886 L * integral of y over the hemisphere = -0.4886 pi L, every other coefficient 0 (odd, or
    // even with a zero integral over the whole sphere). Tolerance: 4 standard deviations of the unstratified
    // estimator, sigma_k^2 = ((4 pi)^2 E[(L Y_k)^2] - c_k^2) / M = (2 pi L^2 - c_k^2) / M (stratification never
    // increases it; here the horizon y = 0 is the meridian phi = 0, pi, a boundary of the strata, so the error
    // is far smaller).
    const std::size_t centre = std::size_t(sv.index_of[s.index({4, 0, 4})]);
    const double M = vs.directions;
    for (int c = 0; c < 3; ++c) {
        double expected[9] = {std::sqrt(kPi) * L[c], -0.48860251190291992 * kPi * L[c], 0, 0, 0, 0, 0, 0, 0};
        double sigma[9];
        for (int k = 0; k < 9; ++k) {
            sigma[k] = std::sqrt((2 * kPi * L[c] * L[c] - expected[k] * expected[k]) / M);
            const double got = f.sh[centre * 27 + std::size_t(c) * 9 + std::size_t(k)];
            INFO("channel " << c << " coefficient " << k << ": " << got << " expected " << expected[k] << " +- "
                            << sigma[k]);
            CHECK(std::abs(got - expected[k]) < 4 * sigma[k]);
        }
        // Lighting from the SH: L facing up, 0 facing down (up to the same noise, propagated).
        const double tol = 4 * (kLobeA[0] * sigma[0] * 0.2821 + kLobeA[1] * sigma[1] * 0.4886) / kPi;
        CHECK(std::abs(sh_lighting(f.sh, centre, c, {0, 1, 0}) - L[c]) < tol);
        CHECK(std::abs(sh_lighting(f.sh, centre, c, {0, -1, 0})) < tol);
    }
    // Every voxel's probe lighting, direct and full, is L (cosine sampling of a constant sky has no variance; only
    // grazing rays that meet a neighbouring top face differ); every exposed face too (sides see sky above and
    // ground below, both L); faces that are not exposed are exactly 0.
    for (std::size_t i = 0; i < sv.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            REQUIRE(f.direct[i * 3 + c] == Approx(L[c]).epsilon(0.01));
            REQUIRE(f.lighting[i * 3 + c] == Approx(L[c]).epsilon(0.01));
            for (int face = 0; face < 6; ++face) {
                const float v = f.face_lighting[(i * 6 + face) * 3 + c];
                if (sv.exposed[i] >> face & 1) REQUIRE(v == Approx(L[c]).epsilon(0.01));
                else REQUIRE(v == 0.0f);
            }
        }
}

TEST_CASE("voxel field: the sun alone projects to E V Y(s), its band-2 irradiance is the truncated cosine lobe",
          "[voxel_field]") {
    VoxelScene s({12, 6, 12}, "plane");
    const std::uint8_t black = s.add_material({glm::vec3(0.0f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {12, 1, 12}, black);
    const glm::ivec3 p_lo(7, 1, 5), p_hi(8, 4, 6);  // a pillar
    s.fill(p_lo, p_hi, black);
    const double theta = 35.0 * kPi / 180.0;
    Lighting l = dark();
    l.sun.direction = glm::normalize(glm::vec3(-0.8f * float(std::sin(theta)), float(std::cos(theta)),
                                               0.6f * float(std::sin(theta))));
    l.sun.irradiance = {2.0f, 1.5f, 1.0f};
    l.sun.angular_radius = 0.0f;  // exact visibility
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 64;
    vs.sun_rays = 4;
    vs.point_samples = 4;
    vs.max_bounces = 1;
    const VoxelField f = r.render_voxel_field(sv, l, vs);

    // Host ray / box test for the pillar's shadow from a probe point; `grow` enlarges (> 0) or shrinks the box.
    const glm::dvec3 sd(l.sun.direction);
    auto blocked = [&](glm::dvec3 o, double grow) {
        double t0 = 0, t1 = 1e30;
        for (int k = 0; k < 3; ++k) {
            const double ta = (p_lo[k] - grow - o[k]) / sd[k], tb = (p_hi[k] + grow - o[k]) / sd[k];
            t0 = std::max(t0, std::min(ta, tb));
            t1 = std::min(t1, std::max(ta, tb));
        }
        return t0 <= t1;
    };
    double Ys[9];
    sh9(sd.x, sd.y, sd.z, Ys);
    const double cg = sd.y;  // cos(angle between the sun and the floor normal +y)
    int lit = 0, shadowed = 0;
    for (std::size_t i = 0; i < sv.size(); ++i) {
        if (sv.cell[i].y != 0 || sv.probe[i].y < 1.0f || sv.exposed[i] != 4 + 8) continue;  // floor tops, not at edges
        const glm::dvec3 p(sv.probe[i]);
        if (blocked(p, 0.02) != blocked(p, -0.02)) continue;  // at a shadow edge
        const bool shade = blocked(p, 0.0);
        for (int c = 0; c < 3; ++c) {
            const double E = l.sun.irradiance[c];
            for (int k = 0; k < 9; ++k)
                REQUIRE(f.sh[i * 27 + std::size_t(c) * 9 + std::size_t(k)] ==
                        Approx(shade ? 0.0 : E * Ys[k]).margin(1e-6).epsilon(1e-5));
            // A delta's irradiance from bands 0-2: E sum_l A_l (2l + 1) / (4 pi) P_l(cos g) (addition theorem)
            // = E (1/4 + cos g / 2 + 5 (3 cos^2 g - 1) / 32): 1.0625 E at normal incidence, where the true value
            // is E; E * 0.035 too much at 35 degrees, E / 32 at grazing where it should be 0.
            const double truncated = shade ? 0.0 : E * (0.25 + cg / 2 + 5 * (3 * cg * cg - 1) / 32) / kPi;
            REQUIRE(sh_lighting(f.sh, i, c, {0, 1, 0}) == Approx(truncated).margin(1e-6).epsilon(1e-5));
            const double exact = shade ? 0.0 : E * cg / kPi;
            REQUIRE(f.direct[i * 3 + c] == Approx(exact).margin(1e-6).epsilon(1e-4));
            REQUIRE(f.lighting[i * 3 + c] == Approx(exact).margin(1e-6).epsilon(1e-4));
        }
        (shade ? shadowed : lit)++;
    }
    CHECK(lit > 60);
    CHECK(shadowed >= 2);
}

TEST_CASE("voxel field: face lighting of a sunlit floor face next to a wall equals the reference render of it",
          "[voxel_field]") {
    VoxelScene s({14, 7, 12}, "wall");
    s.fill({0, 0, 0}, {14, 1, 12}, s.add_material({glm::vec3(0.6f, 0.5f, 0.4f), glm::vec3(0.0f), false}));
    s.fill({8, 1, 2}, {9, 6, 11}, s.add_material({glm::vec3(0.9f, 0.3f, 0.2f), glm::vec3(0.0f), false}));  // wall
    Lighting l = lighting_at(15.0f, 0.0f);
    l.sun.direction = glm::normalize(glm::vec3(0.6f, 0.7f, 0.2f));  // from the +x side: the wall's +x face is lit
    const glm::ivec3 cell(9, 0, 6);                                   // the floor right in front of it
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 16;
    vs.sun_rays = 4;
    vs.point_samples = 1024;
    vs.max_bounces = 4;
    vs.seed = 3;
    const VoxelField f = r.render_voxel_field(sv, l, vs);
    const std::size_t i = std::size_t(sv.index_of[s.index(cell)]);

    // The reference of a camera 2 m above the face looking down: the face covers the central 8 x 8 pixels of 32,
    // a regular grid of points over it.
    RenderSettings rs;
    rs.n = 32;
    rs.reference_spp = 96;
    rs.max_bounces = 4;
    rs.seed = 5;
    const CameraPose pose{glm::vec3(cell) + glm::vec3(0.5f, 3.0f, 0.5f), {0, -1, 0}, {0, 0, -1}};
    Image var;
    const Image ref = r.render_reference(pose, l, rs, &var);
    for (int c = 0; c < 3; ++c) {
        double sum = 0, v = 0;
        int count = 0;
        for (int row = 12; row < 20; ++row)
            for (int col = 12; col < 20; ++col) {
                sum += ref.at(c, row, col);
                v += var.at(c, row, col);
                ++count;
            }
        const double mean = sum / count, se_ref = std::sqrt(v) / count;
        // One sample's variance from the reference's per-pixel variances; the face estimate averages S samples.
        const double se_face = std::sqrt(v / count * rs.reference_spp / vs.point_samples);
        const double got = f.face_lighting[(i * 6 + 2) * 3 + std::size_t(c)];
        INFO("channel " << c << ": face lighting " << got << ", reference " << mean << " +- " << se_ref
                        << ", face +- " << se_face);
        CHECK(std::abs(got - mean) < 4 * std::sqrt(se_ref * se_ref + se_face * se_face) + 0.01 * mean);
        // The probe point is the face's centre: the same lighting up to the variation across the face.
        CHECK(f.lighting[i * 3 + c] == Approx(mean).epsilon(0.1));
        CHECK(f.direct[i * 3 + c] < f.lighting[i * 3 + c]);
    }
}

TEST_CASE("voxel field: deterministic, samples split over launches give the same bits, seeds are independent",
          "[voxel_field]") {
    // A room with a window, a lamp and a table: every estimator (sun, sky portals, sunlit patches, emitters).
    VoxelScene s({10, 7, 10}, "room");
    const std::uint8_t wall = s.add_material({glm::vec3(0.7f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {10, 7, 10}, wall);
    s.fill({1, 1, 1}, {9, 6, 9}, 0);
    s.fill({3, 2, 0}, {6, 5, 1}, 0);  // window in -z
    s.set({5, 5, 5}, s.add_material({glm::vec3(0.8f), glm::vec3(4.0f, 3.0f, 2.0f), true}));
    s.fill({3, 1, 4}, {6, 2, 6}, s.add_material({glm::vec3(0.3f, 0.6f, 0.2f), glm::vec3(0.0f), false}));
    Lighting l = lighting_at(17.5f, 2.8f);
    l.lamp_level = 0.5f;
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 25;  // odd m
    vs.sun_rays = 7;
    vs.point_samples = 9;
    vs.max_bounces = 3;
    vs.seed = 9;
    const VoxelField a = r.render_voxel_field(sv, l, vs);
    const VoxelField b = r.render_voxel_field(sv, l, vs);
    vs.max_samples_per_launch = 2;
    const VoxelField c = r.render_voxel_field(sv, l, vs);
    for (const VoxelField* x : {&b, &c}) {
        CHECK(x->sh == a.sh);
        CHECK(x->direct == a.direct);
        CHECK(x->lighting == a.lighting);
        CHECK(x->face_lighting == a.face_lighting);
        CHECK(x->rays == a.rays);
    }
    CHECK(test::all_finite(a.sh));
    CHECK(test::all_finite(a.face_lighting));
    vs.seed = 10;
    vs.max_samples_per_launch = 0;
    const VoxelField d = r.render_voxel_field(sv, l, vs);
    CHECK(d.sh != a.sh);
    // The same voxels in another renderer of the same scene: the same bits (nothing depends on launch history).
    Renderer r2(test::device(), s);
    vs.seed = 9;
    CHECK(r2.render_voxel_field(sv, l, vs).sh == a.sh);
    // Without bounces, `lighting` is the same estimate as `direct` (same samples).
    vs.max_bounces = 0;
    const VoxelField e = r.render_voxel_field(sv, l, vs);
    CHECK(e.lighting == e.direct);
    CHECK(e.direct == a.direct);
}

namespace {

// Host reference of the visibility rule: the cells a segment passes through, from every plane crossing (double
// precision, crossings sorted), each tested at the middle of its stretch of the segment.
bool host_clear(const VoxelScene& s, glm::dvec3 a, glm::dvec3 b, glm::ivec3 ca, glm::ivec3 cb) {
    const glm::dvec3 d = b - a;
    std::vector<double> ts = {0.0, 1.0};
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) continue;
        const double lo = std::min(a[k], b[k]), hi = std::max(a[k], b[k]);
        for (double p = std::ceil(lo); p <= hi; p += 1) ts.push_back((p - a[k]) / d[k]);
    }
    std::sort(ts.begin(), ts.end());
    for (std::size_t i = 0; i + 1 < ts.size(); ++i) {
        if (ts[i + 1] - ts[i] < 1e-12) continue;
        const glm::ivec3 c(glm::floor(a + d * (0.5 * (ts[i] + ts[i + 1]))));
        if (s.solid(c) && c != ca && c != cb) return false;
    }
    return true;
}

}  // namespace

TEST_CASE("voxel visibility: symmetric, walls block, open pairs see each other, equals a host DDA", "[voxel_field]") {
    VoxelScene s({9, 5, 8}, "vis");
    const std::uint8_t m = s.add_material({});
    s.fill({0, 0, 0}, {9, 1, 8}, m);  // floor
    s.fill({4, 1, 0}, {5, 4, 8}, m);  // a wall across it, splitting the floor's top in two
    s.set({1, 1, 2}, m);              // a block on the floor
    s.set({7, 2, 5}, m);              // a floating block
    const SurfaceVoxels sv = surface_voxels(test::device(), s, dark());
    Renderer r(test::device(), s);
    const std::vector<std::uint32_t> mask = r.voxel_visibility(sv);
    const std::size_t V = sv.size(), words = (V + 31) / 32;
    REQUIRE(mask.size() == V * words);
    auto bit = [&](std::size_t i, std::size_t j) { return (mask[i * words + j / 32] >> (j % 32)) & 1u; };
    int mismatches = 0, ambiguous = 0, visible = 0, hidden = 0;
    for (std::size_t i = 0; i < V; ++i) {
        CHECK(bit(i, i) == 0u);
        for (std::size_t j = V; j < words * 32; ++j) REQUIRE(bit(i, j) == 0u);  // padding
        for (std::size_t j = 0; j < V; ++j) {
            if (j == i) continue;
            REQUIRE(bit(i, j) == bit(j, i));
            if (j < i) continue;
            const glm::dvec3 a(sv.probe[i]), b(sv.probe[j]);
            const bool ref = host_clear(s, a, b, sv.cell[i], sv.cell[j]);
            // Segments grazing a block edge within float rounding may go either way: skip them.
            const glm::dvec3 e(1.3e-4, -0.7e-4, 1.1e-4);
            if (host_clear(s, a + e, b + e, sv.cell[i], sv.cell[j]) != ref ||
                host_clear(s, a - e, b - e, sv.cell[i], sv.cell[j]) != ref) {
                ++ambiguous;
                continue;
            }
            mismatches += bit(i, j) != (ref ? 1u : 0u);
            (ref ? visible : hidden)++;
        }
    }
    INFO("visible " << visible << ", hidden " << hidden << ", ambiguous " << ambiguous);
    CHECK(mismatches == 0);
    CHECK(visible > 1000);
    CHECK(hidden > 1000);
    // Named pairs: floor tops on either side of the wall are hidden from each other; on one side they see each other.
    const std::size_t west = std::size_t(sv.index_of[s.index({1, 0, 5})]), west2 = std::size_t(sv.index_of[s.index({2, 0, 6})]);
    const std::size_t east = std::size_t(sv.index_of[s.index({7, 0, 3})]);
    CHECK(bit(west, east) == 0u);
    CHECK(bit(west, west2) == 1u);
}

TEST_CASE("voxel field: bad inputs are refused with the value named", "[voxel_field]") {
    VoxelScene s({6, 4, 5}, "small");
    s.fill({0, 0, 0}, {6, 1, 5}, s.add_material({}));
    const SurfaceVoxels sv = surface_voxels(test::device(), s, dark());
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 1000;
    CHECK_THROWS_AS(r.render_voxel_field(sv, dark(), vs), InputError);
    CHECK_THROWS_WITH(r.render_voxel_field(sv, dark(), vs), Catch::Contains("directions 1000"));
    vs.directions = 0;
    CHECK_THROWS_WITH(r.render_voxel_field(sv, dark(), vs), Catch::Contains("directions 0"));
    vs.directions = 4;
    vs.sun_rays = 0;
    CHECK_THROWS_WITH(r.render_voxel_field(sv, dark(), vs), Catch::Contains("sun_rays 0"));
    vs.sun_rays = 1;
    vs.point_samples = -3;
    CHECK_THROWS_WITH(r.render_voxel_field(sv, dark(), vs), Catch::Contains("point_samples -3"));
    vs.point_samples = 1;
    vs.max_bounces = -1;
    CHECK_THROWS_WITH(r.render_voxel_field(sv, dark(), vs), Catch::Contains("max_bounces -1"));
    vs.max_bounces = 0;

    VoxelScene other({6, 4, 6}, "other");
    other.fill({0, 0, 0}, {6, 1, 6}, other.add_material({}));
    const SurfaceVoxels ov = surface_voxels(test::device(), other, dark());
    CHECK_THROWS_WITH(r.render_voxel_field(ov, dark(), vs), Catch::Contains("6x4x6") && Catch::Contains("6x4x5"));
    CHECK_THROWS_WITH(r.voxel_visibility(ov), Catch::Contains("6x4x6"));
    SurfaceVoxels broken = sv;
    broken.probe.pop_back();
    CHECK_THROWS_AS(r.render_voxel_field(broken, dark(), vs), InputError);
    SurfaceVoxels too_many = sv;
    too_many.cell.resize(kMaxFieldVoxels + 1);
    CHECK_THROWS_WITH(r.render_voxel_field(too_many, dark(), vs), Catch::Contains(std::to_string(kMaxFieldVoxels + 1)));

    // A mask of more than kMaxVisibilityVoxels voxels (V^2 / 8 bytes) is refused; the field itself is not.
    VoxelScene wide({200, 1, 200}, "wide");
    wide.fill({0, 0, 0}, wide.size, wide.add_material({}));
    const SurfaceVoxels wv = surface_voxels(test::device(), wide, dark());
    REQUIRE(wv.size() == 40000);
    Renderer rw(test::device(), wide);
    CHECK_THROWS_WITH(rw.voxel_visibility(wv), Catch::Contains("40000"));
}

TEST_CASE("voxel field and visibility at a tiny shape (oclgrind)", "[voxel_field][oclgrind-small]") {
    VoxelScene s({4, 3, 4}, "tiny");
    s.fill({0, 0, 0}, {4, 1, 4}, s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false}));
    s.set({1, 1, 1}, s.add_material({glm::vec3(0.8f), glm::vec3(2.0f), false}));  // an emitter on the floor
    s.set({2, 2, 2}, 1);                                                             // a floating block
    const Lighting l = lighting_at(14.0f, 0.5f);
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 4;
    vs.sun_rays = 2;
    vs.point_samples = 2;
    vs.max_bounces = 1;
    const VoxelField f = r.render_voxel_field(sv, l, vs);
    CHECK(test::all_finite(f.sh));
    CHECK(test::all_finite(f.face_lighting));
    const std::vector<std::uint32_t> mask = r.voxel_visibility(sv);
    CHECK(mask.size() == sv.size() * ((sv.size() + 31) / 32));
    for (const bool indirect : {false, true})
        CHECK(test::all_finite(r.project_points_sh({{0.5f, 1.5f, 0.5f}, {3.2f, 2.7f, 1.1f}}, l, vs, indirect).sh));
}

namespace {

// Naive reference of a probe's indirect SH over an open floor lit by a uniform sky: every surface the probe can see
// is the floor slab [0, W] x [0, 1] x [0, W] (top and sides), whose lighting is L everywhere (its top sees only
// sky, a side sees sky above and the sky's ground colour below, both L), so one bounce sends a L toward the probe
// and c_k = a L * integral over the directions that meet the slab of Y_k. The integral by the midpoint rule over
// (z = cos theta, phi) cells of equal solid angle, each direction tested against the slab with a slab ray test.
std::vector<double> floor_integral(glm::dvec3 p, double W, int cells) {
    std::vector<double> out(9, 0.0);
    const double dA = 4 * kPi / (double(cells) * 2 * cells);
    for (int a = 0; a < cells; ++a)
        for (int b = 0; b < 2 * cells; ++b) {
            const double z = 1 - 2 * (a + 0.5) / cells, phi = 2 * kPi * (b + 0.5) / (2 * cells);
            const double r = std::sqrt(std::max(0.0, 1 - z * z));
            const glm::dvec3 w(r * std::cos(phi), r * std::sin(phi), z);
            double t0 = 0, t1 = 1e30;
            const glm::dvec3 lo(0, 0, 0), hi(W, 1, W);
            bool hit = true;
            for (int k = 0; k < 3 && hit; ++k) {
                if (w[k] == 0) {
                    hit = p[k] >= lo[k] && p[k] <= hi[k];
                    continue;
                }
                double ta = (lo[k] - p[k]) / w[k], tb = (hi[k] - p[k]) / w[k];
                if (ta > tb) std::swap(ta, tb);
                t0 = std::max(t0, ta);
                t1 = std::min(t1, tb);
                hit = t0 <= t1;
            }
            if (!hit) continue;
            double Y[9];
            sh9(w.x, w.y, w.z, Y);
            for (int k = 0; k < 9; ++k) out[std::size_t(k)] += Y[k] * dA;
        }
    return out;
}

}  // namespace

TEST_CASE("point SH: indirect light of a floor under a uniform sky equals the naive integral, the sky itself is "
          "not in it",
          "[voxel_field][point_sh]") {
    const int W = 24;
    VoxelScene s({W, 6, W}, "floor");
    const float albedo = 0.6f;
    s.fill({0, 0, 0}, {W, 1, W}, s.add_material({glm::vec3(albedo), glm::vec3(0.0f), false}));
    const glm::vec3 L(0.2f, 0.5f, 1.0f);
    const Lighting l = uniform_sky(L);
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 4096;
    vs.max_bounces = 1;
    vs.seed = 3;
    // Probes at several heights and one off-centre (the slab's edge in view at grazing angles).
    const std::vector<glm::vec3> points = {{12.0f, 1.5f, 12.0f}, {12.3f, 3.0f, 11.6f}, {5.5f, 2.25f, 18.0f}};
    const PointSh got = r.project_points_sh(points, l, vs, true);
    REQUIRE(got.sh.size() == points.size() * 27);
    CHECK(got.rays > 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const std::vector<double> I = floor_integral(glm::dvec3(points[i]), W, 1024);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 9; ++k) {
                const double want = albedo * L[c] * I[std::size_t(k)];
                // 4 standard deviations of the unstratified estimator with radiance at most a L (the stratified one
                // is never worse), plus the midpoint rule's error along the slab's outline (< 1e-3 of a L here).
                const double tol = 4 * albedo * L[c] * std::sqrt(4 * kPi / vs.directions) + 1e-3 * albedo * L[c];
                INFO("point " << i << " channel " << c << " coefficient " << k);
                CHECK(std::abs(got.sh[i * 27 + std::size_t(c) * 9 + std::size_t(k)] - want) < tol);
            }
    }
    // Without bounces there is no indirect light at all.
    vs.max_bounces = 0;
    const PointSh none = r.project_points_sh(points, l, vs, true);
    for (float v : none.sh) REQUIRE(v == 0.0f);
}

TEST_CASE("point SH: full(B) - full(0) = indirect(B) on random grids with sun, sky, lamps and emitters, "
          "deterministic under any split of the directions",
          "[voxel_field][point_sh]") {
    std::mt19937 rng(4601);
    for (int trial = 0; trial < 4; ++trial) {
        const glm::ivec3 size(5 + trial * 3, 4 + trial, 7 - trial);
        VoxelScene s = random_grid(size, 0.25, rng);
        Lighting l = lighting_at(8.0f + 3.0f * float(trial), 0.7f * float(trial));
        l.lamp_level = 0.75f;
        Renderer r(test::device(), s);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        std::vector<glm::vec3> points;
        for (int i = 0; i < 13 + trial; ++i)
            points.push_back(glm::vec3(u(rng), u(rng), u(rng)) * glm::vec3(size));
        points.push_back(glm::vec3(size));  // the grid's far corner belongs to its last block
        VoxelFieldSettings vs;
        vs.directions = (3 + trial) * (3 + trial);
        vs.sun_rays = 5;
        vs.max_bounces = 2 + trial;
        vs.seed = std::uint32_t(11 + trial);
        INFO("trial " << trial << ", grid " << size.x << "x" << size.y << "x" << size.z);
        const PointSh full = r.project_points_sh(points, l, vs, false);
        const PointSh indirect = r.project_points_sh(points, l, vs, true);
        VoxelFieldSettings v0 = vs;
        v0.max_bounces = 0;
        const PointSh direct = r.project_points_sh(points, l, v0, false);
        REQUIRE(test::all_finite(full.sh));
        double peak = 0, worst = 0;
        for (std::size_t j = 0; j < full.sh.size(); ++j) {
            peak = std::max(peak, double(std::abs(full.sh[j])));
            worst = std::max(worst, std::abs(double(full.sh[j]) - direct.sh[j] - indirect.sh[j]));
        }
        INFO("worst |full - direct - indirect| " << worst << " of peak " << peak);
        // Float sums of the same terms in another grouping: rounding of the directions' sum, 1e-5 of the peak.
        CHECK(worst <= 1e-5 * std::max(peak, 1e-3));
        VoxelFieldSettings split = vs;
        split.max_samples_per_launch = 2;
        CHECK(r.project_points_sh(points, l, split, true).sh == indirect.sh);
    }
}

TEST_CASE("point SH: bad points and settings are refused by name", "[voxel_field][point_sh]") {
    VoxelScene s({6, 4, 5}, "small");
    s.fill({0, 0, 0}, {6, 1, 5}, s.add_material({}));
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    vs.directions = 4;
    CHECK_THROWS_WITH(r.project_points_sh({}, dark(), vs, true), Catch::Contains("no points"));
    CHECK_THROWS_WITH(r.project_points_sh({{1, 2, 3}, {1, std::nanf(""), 3}}, dark(), vs, true),
                      Catch::Contains("point 1") && Catch::Contains("6x4x5"));
    CHECK_THROWS_WITH(r.project_points_sh({{6.5f, 2, 3}}, dark(), vs, true), Catch::Contains("point 0"));
    CHECK_THROWS_WITH(r.project_points_sh({{1, -0.01f, 3}}, dark(), vs, true), Catch::Contains("not inside"));
    CHECK_THROWS_WITH(r.project_points_sh(std::vector<glm::vec3>(kMaxFieldVoxels + 1, glm::vec3(1.0f)), dark(), vs,
                                          true),
                      Catch::Contains(std::to_string(kMaxFieldVoxels + 1)));
    vs.directions = 5;
    CHECK_THROWS_WITH(r.project_points_sh({{1, 2, 3}}, dark(), vs, true), Catch::Contains("directions 5"));
}

// Timing and noise on a seed-scale scene (not part of the suite: minutes on a CPU). Run with
// tests/ngi_tests "[.voxel_field_bench]"; environment: NGI_VF_BENCH_SCENE (default room:seed=1),
// NGI_VF_BENCH_DIRECTIONS, NGI_VF_BENCH_BOUNCES.
TEST_CASE("voxel field: timing and SH noise on a room scene", "[.voxel_field_bench]") {
    const char* spec = std::getenv("NGI_VF_BENCH_SCENE");
    const VoxelScene s = make_scene(spec && *spec ? spec : "room:seed=1");
    const Lighting l = lighting_at(s.default_time, s.sun_azimuth);
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceVoxels sv = surface_voxels(test::device(), s, l);
    const double compact_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    Renderer r(test::device(), s);
    VoxelFieldSettings vs;
    if (const char* d = std::getenv("NGI_VF_BENCH_DIRECTIONS")) vs.directions = std::atoi(d);
    if (const char* d = std::getenv("NGI_VF_BENCH_BOUNCES")) vs.max_bounces = std::atoi(d);
    const VoxelField a = r.render_voxel_field(sv, l, vs);
    vs.seed = 1;
    const VoxelField b = r.render_voxel_field(sv, l, vs);
    // Relative RMS difference of two independent seeds (one seed's noise is that / sqrt 2), over a selection of
    // the values (SH coefficient k of band `band`, or all).
    auto rel_rms = [](const std::vector<float>& x, const std::vector<float>& y, std::size_t stride, int lo, int hi) {
        double diff = 0, norm = 0;
        for (std::size_t i = 0; i < x.size(); ++i) {
            const int k = int(i % stride);
            if (k < lo || k >= hi) continue;
            diff += double(x[i] - y[i]) * (x[i] - y[i]);
            norm += 0.25 * double(x[i] + y[i]) * (x[i] + y[i]);
        }
        return std::sqrt(diff / norm);
    };
    // The lighting toward the voxel normal from the SH (band-limited) against the directly estimated `lighting`.
    double lit_diff = 0, lit_norm = 0;
    for (std::size_t i = 0; i < sv.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double from_sh = sh_lighting(a.sh, i, c, glm::dvec3(sv.normal[i]));
            const double direct_estimate = 0.5 * (a.lighting[i * 3 + c] + b.lighting[i * 3 + c]);
            lit_diff += (from_sh - direct_estimate) * (from_sh - direct_estimate);
            lit_norm += direct_estimate * direct_estimate;
        }
    WARN("relative RMS difference of two seeds: SH " << rel_rms(a.sh, b.sh, 9, 0, 9) << " (band 0 "
         << rel_rms(a.sh, b.sh, 9, 0, 1) << ", band 1 " << rel_rms(a.sh, b.sh, 9, 1, 4) << ", band 2 "
         << rel_rms(a.sh, b.sh, 9, 4, 9) << "), direct " << rel_rms(a.direct, b.direct, 1, 0, 1) << ", lighting "
         << rel_rms(a.lighting, b.lighting, 1, 0, 1) << ", face lighting "
         << rel_rms(a.face_lighting, b.face_lighting, 1, 0, 1)
         << "; relative RMS of SH-derived lighting at the normal vs the lighting estimate "
         << std::sqrt(lit_diff / lit_norm));
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<std::uint32_t> mask = sv.size() <= kMaxVisibilityVoxels ? r.voxel_visibility(sv)
                                                                               : std::vector<std::uint32_t>{};
    const double vis_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
    WARN(s.name << " " << s.size.x << "x" << s.size.y << "x" << s.size.z << ": " << sv.size()
                << " surface voxels, compaction " << compact_ms << " ms; field at M = " << vs.directions << ": "
                << a.ms << " ms, " << a.rays << " rays (" << double(a.rays) / a.ms / 1e3
                << " Mrays/s); visibility mask " << vis_ms << " ms");
}

// Procedural smooth objects as triangle meshes: what seed 001's per-object AO networks were designed for (the
// voxel "sculpture" family is their blocky stand-in). Each is closed (every edge shared by exactly two triangles),
// oriented outward, about 40 m across like a sculpture in its 64^3 grid (so the 4 m AO distance means the same),
// with 65k-82k triangles. Deterministic per seed: parameters come from render/rand.hpp's Rand (no std::
// distributions), and positions are computed in double and rounded to float once, so a last-bit difference in a
// platform's std::sin or std::pow would almost never reach the float result.
//   knot          a (p, q) torus-knot tube; p, q, torus radii and tube thickness drawn from the seed; the tube is
//                 kept thinner than the knot's closest approach and its tightest bend (no self-intersection);
//                 analytic normals (a tube's normal is its radial direction)
//   superquadric  a superellipsoid or a supertoroid with seeded exponents (boxy to pinched) and axes; analytic
//                 normals
//   blob          a seeded displaced icosphere (6 subdivisions: 81,920 triangles): Gaussian bumps and dents on the
//                 sphere's radius, which keeps it star-shaped and so free of self-intersection; area-weighted normals
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <glm/gtc/constants.hpp>

#include "ngi/error.hpp"
#include "render/mesh_scene.hpp"
#include "render/rand.hpp"

namespace ngi::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Signed power: sgn(x) |x|^e (the superquadric's building block).
double spow(double x, double e) { return x < 0.0 ? -std::pow(-x, e) : std::pow(x, e); }

// A uniformly distributed rotation from three uniforms (Shoemake's random unit quaternion).
glm::dmat3 random_rotation(Rand& r) {
    const double u1 = r.uniform(), u2 = 2.0 * kPi * r.uniform(), u3 = 2.0 * kPi * r.uniform();
    const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
    const double x = a * std::sin(u2), y = a * std::cos(u2), z = b * std::sin(u3), w = b * std::cos(u3);
    return glm::dmat3(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),   // column 0
                      2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),   // column 1
                      2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y));  // column 2
}

// A mesh under construction in double precision.
struct MeshBuilder {
    std::vector<glm::dvec3> p, n;
    std::vector<glm::uvec3> t;
    std::uint32_t vertex(glm::dvec3 pos, glm::dvec3 normal = glm::dvec3(0.0)) {
        p.push_back(pos);
        n.push_back(normal);
        return std::uint32_t(p.size() - 1);
    }
    // A closed grid of rows x cols vertices (row-major, both directions wrapping): a torus's topology.
    void torus_grid(std::uint32_t first, int rows, int cols) {
        for (int i = 0; i < rows; ++i)
            for (int k = 0; k < cols; ++k) {
                const auto v = [&](int a, int b) { return first + std::uint32_t((a % rows) * cols + b % cols); };
                t.push_back({v(i, k), v(i, k + 1), v(i + 1, k)});
                t.push_back({v(i + 1, k), v(i, k + 1), v(i + 1, k + 1)});
            }
    }
};

// Rotates, scales the largest extent to `size` metres, moves the minimum corner to the origin, orients the
// triangles outward (positive signed volume) and rounds to float; normals analytic if given, else area-weighted.
LoadedMesh finish(MeshBuilder& b, Rand& r, double size, bool analytic_normals, Material material) {
    const glm::dmat3 R = random_rotation(r);
    glm::dvec3 lo(1e300), hi(-1e300);
    for (auto& q : b.p) {
        q = R * q;
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    const glm::dvec3 e = hi - lo;
    const double s = size / std::max({e.x, e.y, e.z});
    double volume = 0.0;
    for (const auto& tri : b.t) volume += glm::dot(b.p[tri.x], glm::cross(b.p[tri.y], b.p[tri.z]));
    if (volume < 0.0)
        for (auto& tri : b.t) std::swap(tri.y, tri.z);
    LoadedMesh out;
    TriangleMesh& m = out.mesh;
    m.positions.reserve(b.p.size());
    for (const auto& q : b.p) m.positions.push_back(glm::vec3((q - lo) * s));
    m.triangles = b.t;
    m.materials.assign(b.t.size(), 1);
    if (analytic_normals) {
        for (const auto& q : b.n) m.normals.push_back(glm::vec3(glm::normalize(R * q)));
    } else {
        compute_vertex_normals(m);
    }
    out.materials.push_back(material);
    return out;
}

// One light material: a light grey, or a seeded soft colour (linear albedo, <= 0.95 like every scene's).
Material object_material(Rand& r) {
    static const std::vector<glm::vec3> tints = {{0.70f, 0.45f, 0.35f}, {0.45f, 0.60f, 0.40f}, {0.40f, 0.50f, 0.70f},
                                                 {0.72f, 0.64f, 0.38f}, {0.62f, 0.45f, 0.62f}, {0.40f, 0.62f, 0.64f}};
    glm::vec3 a = r.chance(0.5f) ? glm::vec3(r.range(0.55f, 0.75f)) : r.pick(tints) * r.range(0.9f, 1.1f);
    return Material{glm::clamp(a, glm::vec3(0.0f), glm::vec3(0.95f)), glm::vec3(0.0f), false};
}

// ---- knot ------------------------------------------------------------------------------------------------------
LoadedMesh knot(std::uint32_t seed) {
    Rand r(seed, 0x6b6e6f74u);  // "knot"
    static const std::vector<glm::ivec2> kinds = {{2, 3}, {2, 5}, {3, 2}, {3, 4}, {3, 5},
                                                  {2, 7}, {4, 3}, {5, 2}, {5, 3}};
    const glm::ivec2 pq = r.pick(kinds);
    const double p = pq.x, q = pq.y, R = 1.0, rt = r.range(0.35f, 0.55f);
    const int U = 1024, V = 32;  // 65,536 triangles
    std::vector<glm::dvec3> C(U), T(U), N(U);
    for (int i = 0; i < U; ++i) {
        const double f = 2.0 * kPi * i / U, cq = std::cos(q * f), sq = std::sin(q * f), cp = std::cos(p * f),
                     sp = std::sin(p * f);
        C[i] = {(R + rt * cq) * cp, (R + rt * cq) * sp, rt * sq};
        T[i] = glm::normalize(glm::dvec3(-rt * q * sq * cp - p * (R + rt * cq) * sp,
                                         -rt * q * sq * sp + p * (R + rt * cq) * cp, rt * q * cq));
        // The offset from the torus's core circle is perpendicular to the tangent (|offset| is constant and the
        // core's tangent is horizontal and perpendicular to it): a closed, twist-free frame.
        N[i] = glm::dvec3(cq * cp, cq * sp, sq);
    }
    // Thickness: half the closest approach of two strands (pairs whose chord is nearly perpendicular to the
    // tangent: neighbours along one strand have a chord along it) and the tightest radius of curvature.
    double thick = 1e300;
    for (int i = 0; i < U; ++i) {
        const glm::dvec3 dT = T[(i + 1) % U] - T[(i + U - 1) % U];
        const double ds = glm::length(C[(i + 1) % U] - C[(i + U - 1) % U]);
        thick = std::min(thick, ds / std::max(glm::length(dT), 1e-12));
        for (int j = i + 1; j < U; ++j) {
            const glm::dvec3 d = C[j] - C[i];
            const double len = glm::length(d);
            if (std::abs(glm::dot(d, T[i])) < 0.2 * len) thick = std::min(thick, 0.5 * len);
        }
    }
    const double tube = std::min(double(r.range(0.10f, 0.22f)), 0.7 * thick);
    MeshBuilder b;
    for (int i = 0; i < U; ++i) {
        const glm::dvec3 B = glm::cross(T[i], N[i]);
        for (int k = 0; k < V; ++k) {
            const double th = 2.0 * kPi * k / V;
            const glm::dvec3 radial = std::cos(th) * N[i] + std::sin(th) * B;
            b.vertex(C[i] + tube * radial, radial);
        }
    }
    b.torus_grid(0, U, V);
    const Material mat = object_material(r);
    return finish(b, r, r.range(36.0f, 44.0f), true, mat);
}

// ---- superquadric ----------------------------------------------------------------------------------------------
LoadedMesh superquadric(std::uint32_t seed) {
    Rand r(seed, 0x73717561u);  // "squa"
    // Exponents below 1 are boxy, 1 round, above 1 pinched; 2 - e stays positive, so the normals stay finite.
    const double e1 = r.range(0.3f, 1.7f), e2 = r.range(0.3f, 1.7f);
    const glm::dvec3 a(1.0, r.range(0.6f, 1.0f), r.range(0.6f, 1.0f));
    MeshBuilder b;
    if (r.chance(0.6f)) {  // superellipsoid: latitude rings and two poles
        const int rings = 128, around = 256;  // 2 x 256 x 127 = 65,024 triangles
        const std::uint32_t south = b.vertex({0.0, 0.0, -a.z}, {0.0, 0.0, -1.0});
        for (int j = 1; j < rings; ++j) {
            const double eta = -0.5 * kPi + kPi * j / rings, ce = std::cos(eta), se = std::sin(eta);
            for (int k = 0; k < around; ++k) {
                const double w = 2.0 * kPi * k / around, cw = std::cos(w), sw = std::sin(w);
                b.vertex({a.x * spow(ce, e1) * spow(cw, e2), a.y * spow(ce, e1) * spow(sw, e2), a.z * spow(se, e1)},
                         {spow(ce, 2 - e1) * spow(cw, 2 - e2) / a.x, spow(ce, 2 - e1) * spow(sw, 2 - e2) / a.y,
                          spow(se, 2 - e1) / a.z});
            }
        }
        const std::uint32_t north = b.vertex({0.0, 0.0, a.z}, {0.0, 0.0, 1.0});
        const auto v = [&](int ring, int k) { return 1 + std::uint32_t((ring - 1) * around + k % around); };
        for (int k = 0; k < around; ++k) {
            b.t.push_back({south, v(1, k + 1), v(1, k)});
            b.t.push_back({north, v(rings - 1, k), v(rings - 1, k + 1)});
            for (int j = 1; j + 1 < rings; ++j) {
                b.t.push_back({v(j, k), v(j, k + 1), v(j + 1, k)});
                b.t.push_back({v(j + 1, k), v(j, k + 1), v(j + 1, k + 1)});
            }
        }
    } else {  // supertoroid: a ring (radius 1) swept by a superellipse of radius `tube`
        const double tube = r.range(0.25f, 0.5f);
        const int around = 384, sides = 96;  // 73,728 triangles
        for (int i = 0; i < around; ++i) {
            const double w = 2.0 * kPi * i / around, cw = std::cos(w), sw = std::sin(w);
            for (int k = 0; k < sides; ++k) {
                const double eta = 2.0 * kPi * k / sides, ce = std::cos(eta), se = std::sin(eta);
                const double rad = 1.0 + tube * spow(ce, e1);
                b.vertex({a.x * rad * spow(cw, e2), a.y * rad * spow(sw, e2), a.z * tube * spow(se, e1)},
                         {spow(ce, 2 - e1) * spow(cw, 2 - e2) / a.x, spow(ce, 2 - e1) * spow(sw, 2 - e2) / a.y,
                          spow(se, 2 - e1) / a.z});
            }
        }
        b.torus_grid(0, around, sides);
    }
    // Orientation is fixed by finish(); the analytic normals point outward either way.
    const Material mat = object_material(r);
    return finish(b, r, r.range(36.0f, 44.0f), true, mat);
}

// ---- blob ------------------------------------------------------------------------------------------------------
LoadedMesh blob(std::uint32_t seed) {
    Rand r(seed, 0x626c6f62u);  // "blob"
    MeshBuilder b;
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    const glm::dvec3 ico[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (const auto& v : ico) b.vertex(glm::normalize(v));
    b.t = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6},
           {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10},
           {8, 6, 7}, {9, 8, 1}};
    for (int level = 0; level < 6; ++level) {  // 20 x 4^6 = 81,920 triangles
        std::unordered_map<std::uint64_t, std::uint32_t> mid;  // lookups only: the numbering follows the loop
        auto midpoint = [&](std::uint32_t x, std::uint32_t y) {
            const std::uint64_t key = std::uint64_t(std::min(x, y)) << 32 | std::max(x, y);
            const auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            const std::uint32_t v = b.vertex(glm::normalize(b.p[x] + b.p[y]));
            mid.emplace(key, v);
            return v;
        };
        std::vector<glm::uvec3> next;
        next.reserve(b.t.size() * 4);
        for (const auto& t : b.t) {
            const std::uint32_t ab = midpoint(t.x, t.y), bc = midpoint(t.y, t.z), ca = midpoint(t.z, t.x);
            next.insert(next.end(), {{t.x, ab, ca}, {t.y, bc, ab}, {t.z, ca, bc}, {ab, bc, ca}});
        }
        b.t = std::move(next);
    }
    // The radius over the unit sphere: 1 plus 48-72 Gaussian bumps (and dents) of seeded size, place and width.
    // Narrow (1.5-4 m at the object's size) and many that the creases between them hold ambient occlusion within seed
    // 001's 4 m rays; broad bumps alone leave a nearly convex object whose AO is 1 everywhere.
    struct Bump { glm::dvec3 c; double amp, width; };
    std::vector<Bump> bumps;
    for (int k = 0, n = r.irange(48, 72); k < n; ++k) {
        const double z = r.range(-1.0f, 1.0f), phi = r.range(0.0f, 6.2831853f), s = std::sqrt(1.0 - z * z);
        bumps.push_back({{s * std::cos(phi), s * std::sin(phi), z}, r.range(-0.12f, 0.3f), r.range(0.08f, 0.2f)});
    }
    const glm::dvec3 stretch(1.0, r.range(0.7f, 1.0f), r.range(0.7f, 1.0f));
    for (auto& v : b.p) {
        double rad = 1.0;
        for (const Bump& bump : bumps)
            rad += bump.amp * std::exp((glm::dot(v, bump.c) - 1.0) / (bump.width * bump.width));
        v *= std::max(rad, 0.35) * stretch;  // a positive scaling keeps the surface star-shaped
    }
    const Material mat = object_material(r);
    return finish(b, r, r.range(36.0f, 44.0f), false, mat);
}

}  // namespace

const std::vector<std::string>& mesh_families() {
    static const std::vector<std::string> f = {"knot", "superquadric", "blob"};
    return f;
}

bool is_mesh_family(const std::string& family) {
    const auto& f = mesh_families();
    return std::find(f.begin(), f.end(), family) != f.end();
}

LoadedMesh generate_mesh_object(const std::string& family, std::uint32_t seed) {
    if (family == "knot") return knot(seed);
    if (family == "superquadric") return superquadric(seed);
    if (family == "blob") return blob(seed);
    throw InputError("unknown mesh family '" + family + "'");
}

VoxelScene mesh_family_scene(const std::string& family, std::uint32_t seed, bool floor, const std::string& name) {
    return mesh_scene(generate_mesh_object(family, seed), name, floor);
}

}  // namespace ngi::detail

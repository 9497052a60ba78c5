// Surround screen-space GI (pipeline/ssgi.*, kernels/ssgi.cl) against the double-precision reference
// (tests/reference_ssgi.hpp): random frames of random sizes (odd ones too), cluster levels, views and bounces; the
// physics it exists for (a camera inside a closed emissive box receives E = pi L, indirect = L); extremes (NaN and
// infinite buffers, HDR light past 65504, surfaces beyond 1000 m, an all-sky frame); the rung as a model file run
// through the pipeline; and bad input.
#include <cfloat>
#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "io_test_support.hpp"
#include "ngi/pipeline.hpp"
#include "pipeline/ssgi.hpp"
#include "reference_ssgi.hpp"
#include "test_support.hpp"

using namespace ngi;
using Catch::Matchers::Contains;

namespace {

constexpr float kSkyDepth = 1e4f;  // what the renderer writes where the primary ray escapes

// Random raw planes of `faces` faces: surfaces at 0.3-30 m with random unit normals, 10% sky, albedo in [0, 1],
// direct light in [0, 3], emission on a fifth of the texels.
std::vector<float> random_planes(std::mt19937& rng, int faces, int n) {
    const std::size_t npix = std::size_t(n) * n;
    std::vector<float> planes(std::size_t(faces) * kFramePlanes * npix, 0.0f);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int f = 0; f < faces; ++f)
        for (std::size_t pix = 0; pix < npix; ++pix) {
            auto at = [&](int plane) -> float& { return planes[(f * kFramePlanes + plane) * npix + pix]; };
            if (u(rng) < 0.1f) {
                at(frame_plane(Feature::Depth)) = kSkyDepth;  // normal stays 0
                continue;
            }
            at(frame_plane(Feature::Depth)) = 0.3f + 29.7f * u(rng);
            float m[3] = {g(rng), g(rng), g(rng)};
            const float len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) + 1e-3f;
            for (int k = 0; k < 3; ++k) {
                at(frame_plane(Feature::Normal) + k) = m[k] / len;
                at(frame_plane(Feature::Albedo) + k) = u(rng);
                at(frame_plane(Feature::Direct) + k) = 3.0f * u(rng);
                at(frame_plane(Feature::Emission) + k) = u(rng) < 0.2f ? 5.0f * u(rng) : 0.0f;
            }
        }
    return planes;
}

struct SsgiRun {
    std::vector<float> lightmap;  // [3][n][n]
};

SsgiRun run_ssgi(const std::vector<float>& planes, int faces, int n, bool has_emission, glm::vec3 look, glm::vec3 up,
                 const ModelConfig::Ssgi& p) {
    auto& ctx = test::ctx();
    detail::Ssgi op(ctx);
    const detail::Buffer in = test::upload(planes);
    detail::Buffer out = ctx.alloc(3 * std::size_t(n) * n * sizeof(float), "ssgi test lightmap");
    op.enqueue(ctx, in.get(), faces, n, has_emission, CameraCluster::from_look_up(look, up), p, out.get());
    return {test::download(out, 3 * std::size_t(n) * n)};
}

// Largest |got - ref| over the front texels that are not borderline, relative to the largest reference value (+1),
// less the light of the terms whose visibility the reference found within rounding of a decision.
double worst_error(const SsgiRun& got, const test::SsgiRefResult& ref, int n) {
    double peak = 1.0, worst = 0.0;
    for (double v : ref.lightmap) peak = std::max(peak, std::abs(v));
    const std::size_t npix = std::size_t(n) * n;
    for (int k = 0; k < 3; ++k)
        for (std::size_t pix = 0; pix < npix; ++pix) {
            if (ref.borderline[pix]) continue;
            const float v = got.lightmap[k * npix + pix];
            if (!std::isfinite(v)) return INFINITY;
            const double diff = std::abs(double(v) - ref.lightmap[k * npix + pix]) - ref.uncertain[pix];
            worst = std::max(worst, std::max(diff, 0.0) / peak);
        }
    return worst;
}

// Writes an ssgi rung's model file: a safetensors header with the config and no tensors.
std::string write_ssgi_model(const std::string& path, const nlohmann::json& config) {
    nlohmann::json header;
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string bytes(8, '\0');
    for (int i = 0; i < 8; ++i) bytes[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    bytes += h;
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

// A frame seen from the centre of a closed cube room of half-size h whose walls emit radiance `emission` (albedo 0,
// no direct light): every face texel sees its own wall at planar depth h, with the wall's normal facing the camera.
std::vector<float> box_planes(int n, float h, float emission, glm::vec3 look, glm::vec3 up) {
    const std::size_t npix = std::size_t(n) * n;
    std::vector<float> planes(kFaceCount * kFramePlanes * npix, 0.0f);
    const CameraCluster cluster = CameraCluster::from_look_up(look, up);
    const Face order[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};
    for (int f = 0; f < kFaceCount; ++f) {
        const glm::vec3 nrm = -cluster.face(order[f]).look;
        for (std::size_t pix = 0; pix < npix; ++pix) {
            auto at = [&](int plane) -> float& { return planes[(f * kFramePlanes + plane) * npix + pix]; };
            at(frame_plane(Feature::Depth)) = h;
            for (int k = 0; k < 3; ++k) {
                at(frame_plane(Feature::Normal) + k) = nrm[k];
                at(frame_plane(Feature::Emission) + k) = emission;
            }
        }
    }
    return planes;
}

}  // namespace

TEST_CASE("SSGI: random frames, sizes, cluster levels, views and bounces against the reference", "[ssgi]") {
    std::mt19937 rng(20261206);
    double worst = 0;
    int texels = 0, borderline = 0;
    const int sizes[] = {2, 3, 5, 8, 12, 16, 7, 10};
    for (int trial = 0; trial < 24; ++trial) {
        const int n = sizes[trial % 8];
        ModelConfig::Ssgi p;
        p.view = trial % 3 == 2 ? "front" : "surround";
        int level = int(rng() % 4);
        while (n % (1 << level)) --level;  // odd and non-power-of-two sizes: the levels that divide them
        p.cluster_level = level;
        p.bounces = trial % 5 == 4 ? 2 : 1;
        p.near_factor = std::array<float, 3>{0.0f, 2.0f, 4.0f}[trial % 3];
        p.min_distance = trial % 2 ? 0.5f : 0.0f;
        const int faces = p.view == "front" && trial % 2 ? 1 : kFaceCount;
        const bool emission = trial % 4 != 3;
        const glm::vec3 look(test::random_vector(3, rng)[0], -0.3f, -1.0f), up(0.1f, 1.0f, 0.2f);
        const std::vector<float> planes = random_planes(rng, faces, n);
        const test::SsgiRefResult ref = test::ssgi_reference(planes, faces, n, emission, look, up, p);
        const SsgiRun got = run_ssgi(planes, faces, n, emission, look, up, p);
        INFO("trial " << trial << ": N " << n << ", view " << p.view << ", level " << p.cluster_level << ", bounces "
                      << p.bounces << ", near " << p.near_factor << ", min distance " << p.min_distance);
        // Tolerance: float sums of up to 6 x 16^2 terms (each a product of a few rounded factors) against double,
        // relative to the frame's largest value. Observed: below 2e-6.
        const double e = worst_error(got, ref, n);
        CHECK(e < 1e-4);
        worst = std::max(worst, e);
        texels += n * n;
        for (char b : ref.borderline) borderline += b;
    }
    WARN("SSGI vs reference: worst error " << worst << " of the peak over " << texels << " front texels ("
                                           << borderline << " borderline refine decisions skipped)");
}

TEST_CASE("SSGI: visibility marched through the faces' depth against the reference", "[ssgi]") {
    std::mt19937 rng(20261207);
    double worst = 0, uncertain = 0, light = 0;
    int texels = 0;
    const int sizes[] = {3, 8, 5, 12, 16, 7, 10, 4};
    for (int trial = 0; trial < 16; ++trial) {
        const int n = sizes[trial % 8];
        ModelConfig::Ssgi p;
        p.view = trial % 4 == 3 ? "front" : "surround";
        int level = int(rng() % 4);
        while (n % (1 << level)) --level;
        p.cluster_level = level;
        p.bounces = trial % 5 == 4 ? 2 : 1;
        p.near_factor = trial % 2 ? 4.0f : 2.0f;
        p.min_distance = 0.2f;
        p.visibility_steps = std::array<int, 4>{1, 4, 8, 3}[trial % 4];
        p.thickness = std::array<float, 3>{0.0f, 2.0f, 0.5f}[trial % 3];
        const int faces = p.view == "front" && trial % 2 ? 1 : kFaceCount;
        const glm::vec3 look(test::random_vector(3, rng)[0], 0.2f, -1.0f), up(-0.1f, 1.0f, 0.1f);
        const std::vector<float> planes = random_planes(rng, faces, n);
        const test::SsgiRefResult ref = test::ssgi_reference(planes, faces, n, true, look, up, p);
        const SsgiRun got = run_ssgi(planes, faces, n, true, look, up, p);
        INFO("trial " << trial << ": N " << n << ", view " << p.view << ", level " << p.cluster_level << ", bounces "
                      << p.bounces << ", steps " << p.visibility_steps << ", thickness " << p.thickness);
        // Tolerance as for the gather without visibility: every decision away from rounding is the reference's, so
        // the rest is float sums against double.
        const double e = worst_error(got, ref, n);
        CHECK(e < 1e-4);
        worst = std::max(worst, e);
        texels += n * n;
        for (std::size_t pix = 0; pix < std::size_t(n) * n; ++pix) {
            uncertain += ref.uncertain[pix];
            light += ref.lightmap[pix];
        }
        // The test must block something: the light differs from the unoccluded gather's (a blocked pair takes its
        // blocker's light, which may be more or less).
        ModelConfig::Ssgi open = p;
        open.visibility_steps = 0;
        const test::SsgiRefResult unblocked = test::ssgi_reference(planes, faces, n, true, look, up, open);
        double with = 0, without = 0;
        for (std::size_t i = 0; i < ref.indirect.size(); ++i) {
            with += ref.indirect[i];
            without += unblocked.indirect[i];
        }
        // (Unless the bias, 4 / N of the depth at small N, is thicker than the surfaces: then nothing can block.)
        if (p.view == "surround" && (p.thickness == 0.0f || p.thickness > 2.0f * detail::kSsgiVisSlope / n))
            CHECK(with != without);
    }
    WARN("SSGI with visibility vs reference: worst error " << worst << " of the peak over " << texels
                                                           << " front texels; light of terms within rounding of a "
                                                              "visibility decision: "
                                                           << uncertain / std::max(light, 1e-30) << " of the total");
}

// A room [-3, 3]^3 whose ceiling (y = 3) emits radiance 1, with an opaque shelf [-2, 2] x [0.8, 1.6] x [-3, -0.5]
// under it against the front wall, seen from the origin (look -z): every face texel ray-cast exactly (albedo 0, no
// direct light, so one bounce of the ceiling's light is all there is).
struct ShelfRoom {
    glm::vec3 lo{-2.0f, 0.8f, -3.0f}, hi{2.0f, 1.6f, -0.5f};
    // Ray from the origin along d: the nearest hit's parameter and normal; the room is hit from inside.
    float cast(glm::vec3 d, glm::vec3* nrm) const {
        float t = INFINITY;
        for (int a = 0; a < 3; ++a)  // the room's walls
            if (d[a] != 0.0f) {
                const float ta = (d[a] > 0 ? 3.0f : -3.0f) / d[a];
                if (ta < t) {
                    t = ta;
                    *nrm = glm::vec3(0.0f);
                    (*nrm)[a] = d[a] > 0 ? -1.0f : 1.0f;
                }
            }
        float t0 = 0.0f, t1 = INFINITY;  // the shelf (slabs)
        int axis = -1;
        for (int a = 0; a < 3; ++a) {
            if (d[a] == 0.0f) {
                if (0.0f < lo[a] || 0.0f > hi[a]) return t;
                continue;
            }
            float ta = lo[a] / d[a], tb = hi[a] / d[a];
            if (ta > tb) std::swap(ta, tb);
            if (ta > t0) {
                t0 = ta;
                axis = a;
            }
            t1 = std::min(t1, tb);
        }
        if (axis >= 0 && t0 <= t1 && t0 < t) {
            t = t0;
            *nrm = glm::vec3(0.0f);
            (*nrm)[axis] = d[axis] > 0 ? -1.0f : 1.0f;
        }
        return t;
    }
    // Whether the segment a -> b crosses the shelf (slab test on its open interior).
    bool blocked(glm::dvec3 a, glm::dvec3 b) const {
        double t0 = 0.0, t1 = 1.0;
        for (int k = 0; k < 3; ++k) {
            const double d = b[k] - a[k];
            if (std::abs(d) < 1e-12) {
                if (a[k] <= lo[k] || a[k] >= hi[k]) return false;
                continue;
            }
            double ta = (lo[k] - a[k]) / d, tb = (hi[k] - a[k]) / d;
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        return t1 - t0 > 1e-9;
    }
};

TEST_CASE("SSGI: visibility brings the gather toward the exactly occluded sum in a room with a shelf", "[ssgi]") {
    const int n = 24;
    const std::size_t npix = std::size_t(n) * n;
    const glm::vec3 look(0, 0, -1), up(0, 1, 0);
    const CameraCluster cluster = CameraCluster::from_look_up(look, up);
    const Face order[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};
    const ShelfRoom room;
    std::vector<float> planes(kFaceCount * kFramePlanes * npix, 0.0f);
    struct Patch {
        glm::dvec3 pos, nrm;
        double area, emission;
    };
    std::vector<Patch> patches;
    std::vector<Patch> front(npix);
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cluster.face(order[f]);
        for (std::size_t pix = 0; pix < npix; ++pix) {
            const glm::vec3 d = face_pixel_direction(b, int(pix % n), int(pix / n), n);
            glm::vec3 nrm(0.0f);
            const float t = room.cast(d, &nrm);
            const glm::vec3 pos = t * d;
            const float emission = nrm.y < -0.5f && pos.y > 2.99f ? 1.0f : 0.0f;
            auto at = [&](int plane) -> float& { return planes[(f * kFramePlanes + plane) * npix + pix]; };
            at(frame_plane(Feature::Depth)) = t;
            for (int k = 0; k < 3; ++k) {
                at(frame_plane(Feature::Normal) + k) = nrm[k];
                at(frame_plane(Feature::Emission) + k) = emission;
            }
            // The texel's area as the convention defines it (solid angle x |p|^2 / cos with the ray).
            const double len = glm::length(glm::dvec3(d));
            const double c = std::max(std::abs(glm::dot(glm::dvec3(nrm), glm::dvec3(d))) / len, double(detail::kSsgiMinCos));
            const double area = (2.0 / n) * (2.0 / n) * glm::dot(glm::dvec3(pos), glm::dvec3(pos)) / (len * len * len) / c;
            patches.push_back({glm::dvec3(pos), glm::dvec3(nrm), area, emission});
            if (f == 0) front[pix] = patches.back();
        }
    }
    // The exact sum: every texel a patch (as cluster level 0 gathers them), visibility by the shelf's geometry.
    ModelConfig::Ssgi p;
    p.cluster_level = 0;
    p.min_distance = 0.5f;
    std::vector<double> exact(npix, 0.0);
    for (std::size_t r = 0; r < npix; ++r)
        for (const Patch& q : patches) {
            if (q.emission == 0.0) continue;
            const glm::dvec3 w = q.pos - front[r].pos;
            const double d2 = glm::dot(w, w);
            if (d2 < double(p.min_distance) * p.min_distance) continue;
            const double cp = glm::dot(front[r].nrm, w) / std::sqrt(d2), cq = -glm::dot(q.nrm, w) / std::sqrt(d2);
            if (cp <= 0 || cq <= 0 || room.blocked(front[r].pos, q.pos)) continue;
            exact[r] += q.emission * cp * cq * q.area / d2 / M_PI;
        }
    auto mean_error = [&](const ModelConfig::Ssgi& s) {
        const SsgiRun got = run_ssgi(planes, kFaceCount, n, true, look, up, s);
        double err = 0;
        for (std::size_t r = 0; r < npix; ++r) err += std::abs(double(got.lightmap[r]) - exact[r]) / double(npix);
        return err;
    };
    double exact_mean = 0;
    for (double v : exact) exact_mean += v / double(npix);
    const double open = mean_error(p);
    ModelConfig::Ssgi vis = p;
    vis.visibility_steps = 16;
    const double unbounded = mean_error(vis);
    vis.thickness = 1.0f;  // the shelf, 0.8 m thick, is seen from 0.8 m and more
    const double thick = mean_error(vis);
    WARN("shelf room at N = " << n << ": exact indirect mean " << exact_mean << "; mean |error| without visibility "
                              << open << ", with 16 samples " << unbounded << " (thickness 1 x depth: " << thick << ")");
    // Without visibility the shelf's shadow is lit by the whole ceiling; the march must remove most of that error.
    CHECK(open > 0.1 * exact_mean);
    CHECK(unbounded < 0.5 * open);
    CHECK(thick < 0.5 * open);
}

TEST_CASE("SSGI: a camera inside a closed emissive box receives E = pi L (indirect = L)", "[ssgi]") {
    // Every front texel's hemisphere is covered by the other five walls, so the exact one-bounce irradiance is pi L
    // and the indirect lighting (E / pi) is L. The discrete sum misses the pairs closer than min_distance (near the
    // room's edges) and approximates each texel by a point; clustering adds its own error. Observed at N = 32,
    // h = 5 m: centre texels 1.0005 / 1.002 / 1.007 / 1.031 at cluster levels 0-3 (level 3: 4 x 4 clusters a face),
    // face means 0.959-0.966 (min_distance 0.5 m drops the pairs across the room's edges).
    const int n = 32;
    const glm::vec3 look(0.3f, -0.2f, -1.0f), up(0.0f, 1.0f, 0.0f);
    const std::vector<float> planes = box_planes(n, 5.0f, 1.0f, look, up);
    for (int level : {0, 1, 2, 3}) {
        ModelConfig::Ssgi p;
        p.cluster_level = level;
        const SsgiRun got = run_ssgi(planes, kFaceCount, n, true, look, up, p);
        const std::size_t npix = std::size_t(n) * n;
        double mean = 0, centre = 0, lo = INFINITY, hi = 0;
        for (std::size_t pix = 0; pix < npix; ++pix) {
            const double v = got.lightmap[pix];  // red; the walls are grey
            mean += v / double(npix);
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            const int row = int(pix / n), col = int(pix % n);
            if (std::abs(row - n / 2 + 0.5) < 4 && std::abs(col - n / 2 + 0.5) < 4) centre += v / 64.0;
            CHECK(got.lightmap[npix + pix] == got.lightmap[pix]);
        }
        INFO("cluster level " << level << ": mean " << mean << ", centre " << centre << ", range " << lo << ".." << hi);
        CHECK(std::abs(centre - 1.0) < (level < 3 ? 0.01 : 0.04));
        CHECK(std::abs(mean - 1.0) < 0.06);
        CHECK(hi < 1.1);
        WARN("closed emissive box, cluster level " << level << ": indirect mean " << mean << ", centre " << centre
                                                    << " (exact 1)");
        // Inside a convex room every segment between two walls is free: the visibility test (any thickness)
        // blocks nothing, the light is the same bit for bit.
        for (float thickness : {0.0f, 1.0f}) {
            ModelConfig::Ssgi v = p;
            v.visibility_steps = 8;
            v.thickness = thickness;
            CHECK(run_ssgi(planes, kFaceCount, n, true, look, up, v).lightmap == got.lightmap);
        }
    }
    // The front face alone sees nothing of the room but its own (coplanar) wall: no light (up to the rounding of a
    // cosine that is 0 in exact arithmetic).
    ModelConfig::Ssgi front;
    front.view = "front";
    const SsgiRun f = run_ssgi(planes, kFaceCount, n, true, look, up, front);
    CHECK(*std::max_element(f.lightmap.begin(), f.lightmap.end()) < 1e-6f);
}

TEST_CASE("SSGI: non-finite buffers, HDR light, surfaces past 1000 m and an all-sky frame", "[ssgi]") {
    std::mt19937 rng(7);
    const int n = 8;
    const glm::vec3 look(0, 0, -1), up(0, 1, 0);
    ModelConfig::Ssgi p;
    p.cluster_level = 1;
    p.bounces = 2;
    const std::size_t npix = std::size_t(n) * n;
    SECTION("NaN and infinities in every feature: finite, non-negative light; the reference agrees") {
        std::vector<float> planes = random_planes(rng, kFaceCount, n);
        const float bad[] = {NAN, INFINITY, -INFINITY};
        for (std::size_t i = 0; i < planes.size(); i += 7) planes[i] = bad[(i / 7) % 3];
        const SsgiRun got = run_ssgi(planes, kFaceCount, n, true, look, up, p);
        const test::SsgiRefResult ref = test::ssgi_reference(planes, kFaceCount, n, true, look, up, p);
        for (float v : got.lightmap) {
            CHECK(std::isfinite(v));
            CHECK(v >= 0.0f);
        }
        // +Inf direct light is FLT_MAX in the lightmap (compose's rule); elsewhere the values match the reference.
        CHECK(worst_error(got, ref, n) < 1e-4);
    }
    SECTION("HDR light far past 65504 saturates at FLT_MAX, never NaN") {
        std::vector<float> planes = random_planes(rng, kFaceCount, n);
        for (int f = 0; f < kFaceCount; ++f)
            for (std::size_t pix = 0; pix < npix; ++pix)
                for (int k = 0; k < 3; ++k) {
                    planes[(f * kFramePlanes + frame_plane(Feature::Direct) + k) * npix + pix] = 3e38f;
                    planes[(f * kFramePlanes + frame_plane(Feature::Emission) + k) * npix + pix] = 1e37f;
                }
        const SsgiRun got = run_ssgi(planes, kFaceCount, n, true, look, up, p);
        for (float v : got.lightmap) {
            CHECK(std::isfinite(v));
            CHECK(v >= 65504.0f);
        }
    }
    SECTION("an all-sky frame and surfaces beyond 1000 m add nothing: the lightmap is the direct light") {
        std::vector<float> planes = random_planes(rng, kFaceCount, n);
        for (int f = 0; f < kFaceCount; ++f)
            for (std::size_t pix = 0; pix < npix; ++pix)
                planes[(f * kFramePlanes + frame_plane(Feature::Depth)) * npix + pix] = f % 2 ? kSkyDepth : 2e3f;
        const SsgiRun got = run_ssgi(planes, kFaceCount, n, true, look, up, p);
        for (int k = 0; k < 3; ++k)
            for (std::size_t pix = 0; pix < npix; ++pix)
                CHECK(got.lightmap[k * npix + pix] == planes[(frame_plane(Feature::Direct) + k) * npix + pix]);
    }
}

TEST_CASE("SSGI: small random case for the simulators", "[ssgi][oclgrind]") {
    std::mt19937 rng(11);
    const int n = 4;
    const glm::vec3 look(0.2f, 0.1f, -1.0f), up(0, 1, 0);
    ModelConfig::Ssgi p;
    p.cluster_level = 1;
    p.bounces = 2;
    const std::vector<float> planes = random_planes(rng, kFaceCount, n);
    const test::SsgiRefResult ref = test::ssgi_reference(planes, kFaceCount, n, true, look, up, p);
    CHECK(worst_error(run_ssgi(planes, kFaceCount, n, true, look, up, p), ref, n) < 1e-4);
    p.visibility_steps = 4;  // the march's scattered depth reads
    p.thickness = 1.0f;
    const test::SsgiRefResult vis = test::ssgi_reference(planes, kFaceCount, n, true, look, up, p);
    CHECK(worst_error(run_ssgi(planes, kFaceCount, n, true, look, up, p), vis, n) < 1e-4);
}

TEST_CASE("SSGI: the rung as a model file runs through the pipeline, and bad files and frames are refused", "[ssgi]") {
    test::TempDir dir("ssgi");
    const int n = 8;
    std::mt19937 rng(5);
    Frame frame;
    frame.n = n;
    frame.look = glm::vec3(0.3f, -0.1f, -1.0f);
    const std::vector<float> planes = random_planes(rng, kFaceCount, n);
    const Face order[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};
    const std::size_t npix = std::size_t(n) * n;
    for (int f = 0; f < kFaceCount; ++f)
        for (Feature feat : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct, Feature::Emission}) {
            const int ch = feat == Feature::Depth ? 1 : 3;
            Image img(n, n, ch);
            for (int k = 0; k < ch; ++k)
                for (std::size_t pix = 0; pix < npix; ++pix)
                    img.data[k * npix + pix] = planes[(f * kFramePlanes + frame_plane(feat) + k) * npix + pix];
            frame.get(feat, order[f]) = img;
        }
    const nlohmann::json config = {{"family", "ssgi"}, {"view", "surround"}, {"cluster_level", 1}, {"bounces", 1}};
    Model model = Model::load(test::device(), write_ssgi_model(dir / "ssgi.safetensors", config));
    CHECK(model.config().family == "ssgi");
    CHECK(model.config().output_mode == "indirect");
    SurroundPipeline pipe(test::device(), n);
    PreprocessStats stats;
    const FrameImages out = pipe.run(model, frame, true, true, false, {}, &stats);
    ModelConfig::Ssgi p;
    p.cluster_level = 1;
    const SsgiRun direct = run_ssgi(planes, kFaceCount, n, true, frame.look, frame.up, p);
    CHECK(out.lightmap.data == direct.lightmap);  // the pipeline runs the same gather, bit for bit
    CHECK(out.final_image.data == pipe.compose(out.lightmap, frame).data);
    CHECK(stats.total_nonfinite() == 0);
    // Transfers as for a network: run() uploads the planes and downloads the outputs once (plus the counters when
    // stats are asked for); enqueue() on device buffers moves nothing through the host (the camera is a kernel
    // argument). A NaN in the frame is counted when stats are asked for.
    HostTransfers t0 = test::device().host_transfers();
    pipe.run(model, frame, true, true, false);
    HostTransfers t1 = test::device().host_transfers();
    CHECK(t1.uploads - t0.uploads == 1);
    CHECK(t1.downloads - t0.downloads == 1);
    const std::vector<float> packed = pack_frame_planes(frame, kFaceCount);
    DeviceBuffer in = DeviceBuffer::allocate(test::device(), packed.size() * sizeof(float));
    in.upload(packed.data(), packed.size() * sizeof(float));
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(test::device(), 3 * npix * sizeof(float));
    t0 = test::device().host_transfers();
    pipe.enqueue(model, in, FrameDesc::of(frame, kFaceCount), outs);
    test::device().finish();
    t1 = test::device().host_transfers();
    CHECK(t1.uploads == t0.uploads);
    CHECK(t1.downloads == t0.downloads);
    Frame nan_frame = frame;
    nan_frame.get(Feature::Albedo, Face::Back).data[3] = NAN;
    pipe.run(model, nan_frame, true, false, false, {}, &stats);
    CHECK(stats.nonfinite[int(Feature::Albedo)] == 1);

    CHECK_THROWS_WITH(model.run(Tensor({1, 12, 8, 8})), Contains("family ssgi has no network"));
    // A rung that gathers from six faces refuses a front-only frame.
    std::vector<float> front(planes.begin(), planes.begin() + std::ptrdiff_t(kFramePlanes * npix));
    CHECK_THROWS_WITH(pipe.run(model, front.data(), front.size() * sizeof(float), FrameDesc{1, true, false}, true,
                               false, false),
                      Contains("gathers from all 6 faces"));
    // A cluster level that does not divide the face size.
    Model coarse = Model::load(test::device(),
                               write_ssgi_model(dir / "coarse.safetensors", {{"family", "ssgi"}, {"cluster_level", 4}}));
    CHECK_THROWS_WITH(pipe.run(coarse, frame, true, false, false), Contains("does not divide the face size N = 8"));
    // Bad config fields name the field.
    for (const auto& [edit, fragment] : std::vector<std::pair<nlohmann::json, std::string>>{
             {{{"view", "back"}}, "field 'view'"},
             {{{"cluster_level", 9}}, "field 'cluster_level'"},
             {{{"bounces", 0}}, "field 'bounces'"},
             {{{"near_factor", -1}}, "field 'near_factor'"},
             {{{"min_distance", 1e-300}}, "field 'min_distance'"},
             {{{"visibility_steps", 65}}, "field 'visibility_steps'"},
             {{{"visibility_steps", 2.5}}, "field 'visibility_steps'"},
             {{{"thickness", -0.5}}, "field 'thickness'"},
             {{{"thickness", "thick"}}, "field 'thickness'"},
             {{{"output_mode", "lightmap"}}, "field 'output_mode'"},
             {{{"ngf", 16}}, "'ngf' is not a field of family ssgi"}}) {
        nlohmann::json c = config;
        c.update(edit);
        CHECK_THROWS_WITH(Model::load(test::device(), write_ssgi_model(dir / "bad.safetensors", c)), Contains(fragment));
    }
}

// Synthetic scenes for joint bilateral upsampling: planar regions of the unit image square, seen at any resolution
// (the guides: normals and world positions at pixel centres), random ones among them. Used by tests/test_jbu.cpp and
// the op harness's JBU rows (tests/op_harness/op_cases.cpp, no Catch2).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace ngi::test::jbu_scene {

// A planar region of the synthetic scene: the image-space rectangle [u0, u1) x [v0, v1) of the unit square shows
// the plane through `origin` spanned by t1, t2 (orthonormal, normal = t1 x t2); zero normal = no surface.
struct Region {
    double u0, v0, u1, v1;
    std::array<double, 3> origin, t1, t2, normal;
};

// Regions are tried in order; the last one should cover the whole square.
struct Scene {
    std::vector<Region> regions;
    double scale = 2.0;  // metres per unit of image space
};

inline const Region* region_at(const Scene& s, double u, double v) {
    for (const Region& r : s.regions)
        if (u >= r.u0 && u < r.u1 && v >= r.v0 && v < r.v1) return &r;
    return nullptr;
}

// The guides of a w x h view of the scene (pixel centres), and each pixel's region index (-1: none).
struct Guides {
    std::vector<float> normal, position;
    std::vector<int> region;
};

inline Guides render_guides(const Scene& s, int w, int h) {
    const std::size_t plane = std::size_t(w) * h;
    Guides g;
    g.normal.assign(3 * plane, 0.0f);
    g.position.assign(3 * plane, 0.0f);
    g.region.assign(plane, -1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double u = (x + 0.5) / w, v = (y + 0.5) / h;
            const Region* r = region_at(s, u, v);
            if (!r) continue;
            const std::size_t i = std::size_t(y) * w + x;
            g.region[i] = int(r - s.regions.data());
            for (int k = 0; k < 3; ++k) {
                g.normal[k * plane + i] = float(r->normal[k]);
                g.position[k * plane + i] = float(r->origin[k] + s.scale * (u * r->t1[k] + v * r->t2[k]));
            }
        }
    return g;
}

inline std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

inline std::array<double, 3> unit(std::array<double, 3> a) {
    const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (double& x : a) x /= l;
    return a;
}

// A region on a random plane (an axis-aligned one half of the time, as voxel faces are).
inline Region random_region(std::mt19937& rng, double u0, double v0, double u1, double v1) {
    std::uniform_real_distribution<double> d(-1.0, 1.0);
    Region r{u0, v0, u1, v1, {d(rng) * 3, d(rng) * 3, d(rng) * 3}, {}, {}, {}};
    std::array<double, 3> n;
    if (rng() % 2) {
        n = {0, 0, 0};
        n[rng() % 3] = rng() % 2 ? 1.0 : -1.0;
    } else {
        n = unit({d(rng), d(rng), d(rng)});
    }
    // A tangent frame: any vector not parallel to n, made orthogonal.
    const std::array<double, 3> a = std::abs(n[0]) < 0.9 ? std::array<double, 3>{1, 0, 0} : std::array<double, 3>{0, 1, 0};
    r.t1 = unit(cross(n, a));
    r.t2 = cross(n, r.t1);
    r.normal = cross(r.t1, r.t2);
    return r;
}

// Several random rectangles over a random background plane; sometimes a surfaceless (sky) rectangle.
inline Scene random_scene(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Scene s;
    const int k = 1 + int(rng() % 4);
    for (int i = 0; i < k; ++i) {
        const double a = u(rng), b = u(rng), c = u(rng), d = u(rng);
        s.regions.push_back(random_region(rng, std::min(a, b), std::min(c, d), std::max(a, b), std::max(c, d)));
    }
    if (rng() % 2) {
        const double a = u(rng), c = u(rng);
        s.regions.insert(s.regions.begin(), Region{a, c, a + 0.2, c + 0.3, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}});
    }
    s.regions.push_back(random_region(rng, 0, 0, 1, 1));
    return s;
}

}  // namespace ngi::test::jbu_scene

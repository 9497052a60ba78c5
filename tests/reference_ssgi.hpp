// Naive double-precision reference of surround screen-space GI (kernels/ssgi.cl, docs/CONVENTIONS.md section 19),
// written from the convention, not from the kernel: every texel of the sender faces as a patch, clusters as sums
// over their blocks, one loop over every receiver and every sender record.
#pragma once
#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <vector>

#include "ngi/camera.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"
#include "pipeline/frame_planes.hpp"
#include "pipeline/ssgi.hpp"

namespace ngi::test {

struct SsgiRefResult {
    std::vector<double> lightmap;   // [3][n][n]: clean(direct) + E / pi of the front face
    std::vector<double> indirect;   // [3][n][n]: E / pi
    std::vector<char> borderline;   // per front texel: a cluster's refine test within 1% of its threshold (the float
                                    // kernel may decide the other way there)
};

// planes: raw frame planes ([face][16][n][n], ngi/pipeline.hpp) of `faces` faces.
inline SsgiRefResult ssgi_reference(const std::vector<float>& planes, int faces, int n, bool has_emission,
                                    glm::vec3 look, glm::vec3 up, const ModelConfig::Ssgi& p) {
    using V = std::array<double, 3>;
    auto dot = [](const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    const int senders = p.view == "front" ? 1 : kFaceCount;
    const std::size_t npix = std::size_t(n) * n;
    const CameraCluster cluster = CameraCluster::from_look_up(look, up);
    const Face order[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};
    auto at = [&](int f, int plane, std::size_t pix) { return double(planes[(f * kFramePlanes + plane) * npix + pix]); };
    auto light = [](double v) {  // compose's cleaning, then the sender cap
        if (std::isnan(v)) return 0.0;
        return std::clamp(v, 0.0, double(FLT_MAX));
    };
    (void)faces;

    struct Texel {
        bool surface = false;
        V pos{}, normal{};
        double area = 0;
    };
    std::vector<Texel> tex(senders * npix);
    for (int f = 0; f < senders; ++f) {
        const FaceBasis b = cluster.face(order[f]);
        for (std::size_t pix = 0; pix < npix; ++pix) {
            Texel& t = tex[f * npix + pix];
            const double depth = at(f, frame_plane(Feature::Depth), pix);
            V m{at(f, 3, pix), at(f, 4, pix), at(f, 5, pix)};
            if (!(depth > 0 && depth <= detail::kMaxSurfaceDepth)) continue;
            if (!std::isfinite(m[0]) || !std::isfinite(m[1]) || !std::isfinite(m[2])) continue;
            const double big = std::max({std::abs(m[0]), std::abs(m[1]), std::abs(m[2])});
            if (!(big >= 1e-6)) continue;
            const double len = std::sqrt(dot(m, m));
            for (double& c : m) c /= len;
            const int row = int(pix / n), col = int(pix % n);
            const double u = 2.0 * (col + 0.5) / n - 1.0, v = 1.0 - 2.0 * (row + 0.5) / n;
            V d;
            for (int k = 0; k < 3; ++k) d[k] = double(b.look[k]) + u * b.right[k] + v * b.up[k];
            const double dl = std::sqrt(dot(d, d));
            t.surface = true;
            t.normal = m;
            for (int k = 0; k < 3; ++k) t.pos[k] = depth * d[k];
            // Solid angle (2/n)^2 / |d|^3 times |p|^2, over the cosine with the camera ray (at least kSsgiMinCos).
            const double c = std::max(std::abs(dot(m, d)) / dl, double(detail::kSsgiMinCos));
            t.area = (2.0 / n) * (2.0 / n) * dot(t.pos, t.pos) / (dl * dl * dl) / c;
        }
    }
    // Records: {area, sum A n, sum A L, sum A p, sum A |p|^2}.
    struct Rec {
        double a = 0, spread = 0;
        V an{}, al{}, ap{};
    };
    const int b = 1 << p.cluster_level, s = n / b;
    auto term = [&](const Rec& r, const V& x, const V& nx, double& e0, double& e1, double& e2) {
        if (!(r.a > 0)) return;
        V w;
        for (int k = 0; k < 3; ++k) w[k] = r.ap[k] / r.a - x[k];
        const double d2 = dot(w, w);
        if (!(d2 >= double(p.min_distance) * p.min_distance) || d2 <= 0) return;
        const double inv = 1 / std::sqrt(d2), cp = dot(nx, w) * inv, proj = -dot(r.an, w) * inv;
        if (cp <= 0 || proj <= 0) return;
        const double g = cp * proj / d2 / r.a;
        e0 += r.al[0] * g;
        e1 += r.al[1] * g;
        e2 += r.al[2] * g;
    };

    std::vector<double> bounce;  // E / pi per sender texel, [face][3][n][n], of the previous bounce
    SsgiRefResult out;
    for (int bounce_i = 1; bounce_i <= p.bounces; ++bounce_i) {
        std::vector<Rec> fine(senders * npix);
        for (int f = 0; f < senders; ++f)
            for (std::size_t pix = 0; pix < npix; ++pix) {
                const Texel& t = tex[f * npix + pix];
                if (!t.surface || !(t.area > 0)) continue;
                Rec& r = fine[f * npix + pix];
                r.a = t.area;
                for (int k = 0; k < 3; ++k) {
                    double albedo = at(f, frame_plane(Feature::Albedo) + k, pix);
                    albedo = std::isnan(albedo) ? 0.0 : std::clamp(albedo, 0.0, 1.0);
                    double incoming = std::min(light(at(f, frame_plane(Feature::Direct) + k, pix)), double(detail::kSsgiMaxRadiance));
                    if (bounce_i > 1) incoming = std::min(incoming + bounce[(f * 3 + k) * npix + pix], double(detail::kSsgiMaxRadiance));
                    double l = albedo * incoming;
                    if (has_emission) l += std::min(light(at(f, frame_plane(Feature::Emission) + k, pix)), double(detail::kSsgiMaxRadiance));
                    l = std::min(l, double(detail::kSsgiMaxRadiance));
                    r.an[k] = t.area * t.normal[k];
                    r.al[k] = t.area * l;
                    r.ap[k] = t.area * t.pos[k];
                }
                r.spread = t.area * dot(t.pos, t.pos);
            }
        // Clusters of b x b texels and their quarters of bm x bm, summed straight from the texels.
        const int bm = b > 1 ? b / 2 : 1, sm = n / bm;
        auto sum_blocks = [&](int side) {
            const int per = n / side;
            std::vector<Rec> out(senders * std::size_t(per) * per);
            for (int f = 0; f < senders; ++f)
                for (int y = 0; y < n; ++y)
                    for (int x = 0; x < n; ++x) {
                        const Rec& r = fine[f * npix + std::size_t(y) * n + x];
                        Rec& c = out[(f * std::size_t(per) + y / side) * per + x / side];
                        c.a += r.a;
                        c.spread += r.spread;
                        for (int k = 0; k < 3; ++k) {
                            c.an[k] += r.an[k];
                            c.al[k] += r.al[k];
                            c.ap[k] += r.ap[k];
                        }
                    }
            return out;
        };
        const std::vector<Rec> coarse = sum_blocks(b), quarters = sum_blocks(bm);
        const bool last = bounce_i == p.bounces;
        const int receivers = last ? 1 : senders;
        std::vector<double> e(receivers * 3 * npix, 0.0);
        if (last) out.borderline.assign(npix, 0);
        const double near2 = double(p.near_factor) * p.near_factor;
        for (int f = 0; f < receivers; ++f)
            for (std::size_t pix = 0; pix < npix; ++pix) {
                const Texel& t = tex[f * npix + pix];
                if (!t.surface) continue;
                double e0 = 0, e1 = 0, e2 = 0;
                // Whether record c (sums) must be replaced by its children; marks the texel borderline when the test
                // is within 1% of its threshold (the kernel's variance is a difference of float sums).
                auto refine = [&](const Rec& c) {
                    if (!(c.a > 0) || near2 <= 0) return false;
                    V mean, w;
                    for (int k = 0; k < 3; ++k) {
                        mean[k] = c.ap[k] / c.a;
                        w[k] = mean[k] - t.pos[k];
                    }
                    const double var = std::max(c.spread / c.a - dot(mean, mean), 0.0), d2 = dot(w, w);
                    const double tol = 0.01 * near2 * var + near2 * 4e-6 * dot(mean, mean);
                    if (last && std::abs(d2 - near2 * var) < tol) out.borderline[pix] = 1;
                    return d2 < near2 * var;
                };
                for (std::size_t ci = 0; ci < coarse.size(); ++ci) {
                    const Rec& c = coarse[ci];
                    if (b == 1 || !refine(c)) {
                        term(c, t.pos, t.normal, e0, e1, e2);
                        continue;
                    }
                    const int cf = int(ci / (std::size_t(s) * s)), cc = int(ci % (std::size_t(s) * s));
                    const int by = cc / s, bx = cc % s;
                    for (int qy = 2 * by; qy < 2 * by + 2; ++qy)
                        for (int qx = 2 * bx; qx < 2 * bx + 2; ++qx) {
                            const Rec& q = quarters[(cf * std::size_t(sm) + qy) * sm + qx];
                            if (bm == 1 || !refine(q)) {
                                term(q, t.pos, t.normal, e0, e1, e2);
                                continue;
                            }
                            for (int y = qy * bm; y < qy * bm + bm; ++y)
                                for (int x = qx * bm; x < qx * bm + bm; ++x)
                                    term(fine[cf * npix + std::size_t(y) * n + x], t.pos, t.normal, e0, e1, e2);
                        }
                }
                const double inv_pi = 1.0 / M_PI;
                e[(f * 3 + 0) * npix + pix] = std::min(e0 * inv_pi, double(FLT_MAX));
                e[(f * 3 + 1) * npix + pix] = std::min(e1 * inv_pi, double(FLT_MAX));
                e[(f * 3 + 2) * npix + pix] = std::min(e2 * inv_pi, double(FLT_MAX));
            }
        if (!last) {
            bounce = std::move(e);
            continue;
        }
        out.indirect = e;
        out.lightmap.assign(3 * npix, 0.0);
        for (int k = 0; k < 3; ++k)
            for (std::size_t pix = 0; pix < npix; ++pix)
                out.lightmap[k * npix + pix] =
                    std::min(light(at(0, frame_plane(Feature::Direct) + k, pix)) + e[k * npix + pix], double(FLT_MAX));
    }
    return out;
}

}  // namespace ngi::test

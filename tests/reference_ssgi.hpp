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
    std::vector<double> uncertain;  // per front texel: the light (E / pi, largest channel) of the terms whose
                                    // visibility was near a decision (a face edge, a texel edge, the bias or the
                                    // thickness), which the float kernel may count or not, also through earlier bounces
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
        double a = 0, spread = 0, au = 0;  // au: sum of A x the radiance that is uncertain (earlier bounces)
        V an{}, al{}, ap{};
    };
    const int b = 1 << p.cluster_level, s = n / b;
    // Visibility (docs/CONVENTIONS.md section 19): the segment from receiver x toward a record's mean position, cut
    // short by its positions' spread (at most halfway), sampled at the centres of visibility_steps equal parts; a
    // sample is seen by the face whose look axis is nearest its direction (ties to the first in Face order) and
    // blocks when it lies behind that face's surface (depth d) by more than d * slope * 2 / n and less than
    // thickness * d.
    // Faces not in the frame (view "front") and no-surface texels block nothing. A blocked pair's light is the
    // blocking texel's (the first blocking sample's), as screen-space ray tracing takes the surface it hits.
    // Returns that texel (face * n^2 + pixel) or -1 when free. *near: a sample's decision would
    // change on the other side of a face edge or texel edge it lies within rounding of, or at the bias or thickness.
    const double thickness = p.thickness > 0 ? double(p.thickness) : INFINITY;
    const glm::vec3 axes[3] = {cluster.alpha, cluster.beta, cluster.gamma};
    // Whether a sample at cluster coordinates c, seen by face g at texel (col, row), blocks; *near at the thresholds.
    auto blocks = [&](const V& c, int g, int col, int row, bool* near) {
        if (g >= senders) return false;
        const glm::vec3 l = cluster_face_basis(order[g]).look;
        const double t = c[0] * l.x + c[1] * l.y + c[2] * l.z;
        if (!(t > 0)) return false;
        col = std::clamp(col, 0, n - 1);
        row = std::clamp(row, 0, n - 1);
        const double d = at(g, frame_plane(Feature::Depth), std::size_t(row) * n + col);
        if (!(d > 0 && d <= detail::kMaxSurfaceDepth)) return false;
        const double behind = t - d, bias = d * detail::kSsgiVisSlope * 2.0 / n, tol = 1e-4 * std::max(t, 1.0);
        if (std::abs(behind - bias) < tol || std::abs(behind - thickness * d) < tol) *near = true;
        return behind > bias && behind < thickness * d;
    };
    const std::vector<Rec>* texel_recs = nullptr;  // this bounce's texel records (a blocker's light)
    // Largest channel of texel i's mean radiance.
    auto texel_light = [&](long i) {
        const Rec& h = (*texel_recs)[std::size_t(i)];
        return h.a > 0 ? std::max({h.al[0], h.al[1], h.al[2]}) / h.a : 0.0;
    };
    // *near_light: with *near, the largest light of any texel that may block instead.
    auto blocker = [&](const V& x, const V& w, double variance, bool* near, double* near_light) {
        const double len = std::sqrt(dot(w, w));
        if (!(len > 0)) return -1L;
        const double reach = 1.0 - std::min(std::sqrt(std::max(variance, 0.0)) / len, 0.5);
        long hit = -1;
        for (int k = 0; k < p.visibility_steps && hit < 0; ++k) {
            const double t = reach * (k + 0.5) / p.visibility_steps;
            V world, c;
            for (int i = 0; i < 3; ++i) world[i] = x[i] + t * w[i];
            for (int i = 0; i < 3; ++i) c[i] = world[0] * axes[i].x + world[1] * axes[i].y + world[2] * axes[i].z;
            // Every (face, texel) the float kernel may pick: faces within rounding of the best, texels within
            // rounding of the one hit.
            double best = -INFINITY;
            for (int g = 0; g < kFaceCount; ++g) {
                const glm::vec3 l = cluster_face_basis(order[g]).look;
                best = std::max(best, c[0] * l.x + c[1] * l.y + c[2] * l.z);
            }
            const double scale = std::sqrt(dot(c, c));
            int votes = 0, candidates = 0, picked = -1;
            bool picked_blocks = false;
            long picked_texel = -1;
            for (int g = 0; g < kFaceCount; ++g) {
                const FaceBasis fb = cluster_face_basis(order[g]);
                const double tg = c[0] * fb.look.x + c[1] * fb.look.y + c[2] * fb.look.z;
                if (tg < best - 1e-4 * scale || !(tg > 0)) continue;
                const double u = (c[0] * fb.right.x + c[1] * fb.right.y + c[2] * fb.right.z) / tg;
                const double v = (c[0] * fb.up.x + c[1] * fb.up.y + c[2] * fb.up.z) / tg;
                const double fc = (u + 1) * 0.5 * n, fr = (1 - v) * 0.5 * n;
                const int c0 = int(std::floor(fc - 1e-3)), c1 = int(std::floor(fc + 1e-3));
                const int r0 = int(std::floor(fr - 1e-3)), r1 = int(std::floor(fr + 1e-3));
                for (int rr = r0; rr <= r1; ++rr)
                    for (int cc = c0; cc <= c1; ++cc) {
                        const bool bl = blocks(c, g, cc, rr, near);
                        votes += bl;
                        if (bl)
                            *near_light = std::max(*near_light, texel_light(long(g) * long(npix) +
                                                                            long(std::clamp(rr, 0, n - 1)) * n +
                                                                            std::clamp(cc, 0, n - 1)));
                        ++candidates;
                        if (picked < 0 && tg == best && cc == int(std::floor(fc)) && rr == int(std::floor(fr))) {
                            picked = g;
                            picked_blocks = bl;
                            picked_texel = long(g) * long(npix) + long(std::clamp(rr, 0, n - 1)) * n +
                                           std::clamp(cc, 0, n - 1);
                        }
                    }
            }
            if ((votes != 0 && votes != candidates) || (votes > 0 && candidates > 1)) *near = true;
            if (picked >= 0 && picked_blocks) hit = picked_texel;
        }
        return hit;
    };
    double* vis_unc = nullptr;  // the current receiver's uncertain irradiance
    auto term = [&](const Rec& r, const V& x, const V& nx, double& e0, double& e1, double& e2) {
        if (!(r.a > 0)) return;
        V w;
        for (int k = 0; k < 3; ++k) w[k] = r.ap[k] / r.a - x[k];
        const double d2 = dot(w, w);
        if (!(d2 >= double(p.min_distance) * p.min_distance) || d2 <= 0) return;
        const double inv = 1 / std::sqrt(d2), cp = dot(nx, w) * inv, proj = -dot(r.an, w) * inv;
        if (cp <= 0 || proj <= 0) return;
        if (p.visibility_steps > 0) {
            V mean;
            for (int k = 0; k < 3; ++k) mean[k] = r.ap[k] / r.a;
            bool near = false;
            double near_light = 0;  // the largest mean radiance of a texel that may block instead
            const long hit = blocker(x, w, std::max(r.spread / r.a - dot(mean, mean), 0.0), &near, &near_light);
            const double g = cp * proj / d2 / r.a;
            if (hit >= 0) {
                const Rec& h = (*texel_recs)[std::size_t(hit)];
                // a blocked pair: the blocker's radiance through the sender's form factor
                if (h.a > 0) {
                    e0 += h.al[0] / h.a * r.a * g;
                    e1 += h.al[1] / h.a * r.a * g;
                    e2 += h.al[2] / h.a * r.a * g;
                }
                *vis_unc += g * (h.au / std::max(h.a, 1e-300)) * r.a;
            }
            if (near) *vis_unc += g * std::max({r.al[0], r.al[1], r.al[2], near_light * r.a});
            *vis_unc += g * r.au;
            if (hit >= 0) return;
        }
        const double g = cp * proj / d2 / r.a;
        e0 += r.al[0] * g;
        e1 += r.al[1] * g;
        e2 += r.al[2] * g;
    };

    std::vector<double> bounce;  // E / pi per sender texel, [face][3][n][n], of the previous bounce
    std::vector<double> bounce_unc;  // its uncertain part per sender texel, [face][n][n]
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
                if (bounce_i > 1) r.au = t.area * bounce_unc[f * npix + pix];
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
                        c.au += r.au;
                        for (int k = 0; k < 3; ++k) {
                            c.an[k] += r.an[k];
                            c.al[k] += r.al[k];
                            c.ap[k] += r.ap[k];
                        }
                    }
            return out;
        };
        const std::vector<Rec> coarse = sum_blocks(b), quarters = sum_blocks(bm);
        texel_recs = &fine;
        const bool last = bounce_i == p.bounces;
        const int receivers = last ? 1 : senders;
        std::vector<double> e(receivers * 3 * npix, 0.0);
        std::vector<double> unc(receivers * npix, 0.0);
        if (last) out.borderline.assign(npix, 0);
        const double near2 = double(p.near_factor) * p.near_factor;
        for (int f = 0; f < receivers; ++f)
            for (std::size_t pix = 0; pix < npix; ++pix) {
                const Texel& t = tex[f * npix + pix];
                if (!t.surface) continue;
                double e0 = 0, e1 = 0, e2 = 0;
                double receiver_unc = 0;
                vis_unc = &receiver_unc;
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
                unc[f * npix + pix] = receiver_unc * inv_pi;
                e[(f * 3 + 0) * npix + pix] = std::min(e0 * inv_pi, double(FLT_MAX));
                e[(f * 3 + 1) * npix + pix] = std::min(e1 * inv_pi, double(FLT_MAX));
                e[(f * 3 + 2) * npix + pix] = std::min(e2 * inv_pi, double(FLT_MAX));
            }
        if (!last) {
            bounce = std::move(e);
            bounce_unc = std::move(unc);
            continue;
        }
        out.uncertain = unc;
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

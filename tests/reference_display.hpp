// Naive double-precision reference of the display view (kernels/display.cl, ngi/display.hpp; docs/CONVENTIONS.md
// section 20), written from the convention: guides, the N x N indirect light, joint bilateral upsampling
// (reference_jbu.hpp), the temporal pass and compose, one pixel at a time.
#pragma once
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <vector>

#include "ngi/camera.hpp"
#include "ngi/display.hpp"
#include "ngi/pipeline.hpp"
#include "reference_jbu.hpp"

namespace ngi::test {

struct DisplayRefCamera {
    double c[3], look[3], right[3], up[3];
    static DisplayRefCamera of(glm::vec3 position, glm::vec3 look, glm::vec3 up) {
        const CameraCluster k = CameraCluster::from_look_up(look, up);
        DisplayRefCamera r{};
        for (int i = 0; i < 3; ++i) {
            r.c[i] = position[i];
            r.look[i] = -k.gamma[i];
            r.right[i] = k.alpha[i];
            r.up[i] = k.beta[i];
        }
        return r;
    }
};

inline double display_ref_light(double v) { return std::isnan(v) ? 0.0 : std::clamp(v, 0.0, double(FLT_MAX)); }
inline double display_ref_signed(double v) { return std::isnan(v) ? 0.0 : std::clamp(v, -double(FLT_MAX), double(FLT_MAX)); }

// Guides of face 0 of frame planes (size x size): normals and world positions, zeros where there is no surface.
inline void display_ref_guides(const std::vector<float>& planes, int size, const DisplayRefCamera& cam,
                               std::vector<float>& normal, std::vector<float>& position) {
    const std::size_t plane = std::size_t(size) * size;
    normal.assign(3 * plane, 0.0f);
    position.assign(3 * plane, 0.0f);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const std::size_t i = std::size_t(y) * size + x;
            double n[3], len2 = 0;
            bool finite = true;
            for (int k = 0; k < 3; ++k) {
                n[k] = planes[(frame_plane(Feature::Normal) + k) * plane + i];
                finite = finite && std::isfinite(n[k]);
                len2 += n[k] * n[k];
            }
            const double d = planes[frame_plane(Feature::Depth) * plane + i];
            if (!(finite && len2 >= 0.25 && std::isfinite(d) && d > 0 && d <= 1000.0)) continue;
            const double u = 2.0 * (x + 0.5) / size - 1.0, v = 1.0 - 2.0 * (y + 0.5) / size;
            for (int k = 0; k < 3; ++k) {
                normal[k * plane + i] = float(n[k]);
                position[k * plane + i] = float(cam.c[k] + d * (cam.look[k] + u * cam.right[k] + v * cam.up[k]));
            }
        }
}

struct DisplayRefState {
    bool has_history = false;
    std::vector<double> history;     // [3][S][S]
    std::vector<double> prev_depth;  // [S][S]
    DisplayRefCamera prev{};
};

struct DisplayRefFrame {
    std::vector<double> lightmap, final_image;  // [3][S][S]
    std::vector<char> borderline;               // per pixel: a decision within a hair of its threshold
    int jbu_fallbacks = 0, disoccluded = 0, clipped = 0;
};

// One frame: low_planes (face 0, n x n), low_lightmap [3][n][n], display_planes (face 0, S x S).
inline DisplayRefFrame display_reference(DisplayRefState& st, const DisplaySettings& s, int n,
                                         const std::vector<float>& low_planes, const std::vector<float>& low_lightmap,
                                         int S, const std::vector<float>& display_planes, bool has_emission,
                                         bool has_env, const DisplayRefCamera& cam) {
    const std::size_t lp = std::size_t(n) * n, hp = std::size_t(S) * S;
    DisplayRefFrame r;
    r.borderline.assign(hp, 0);
    JbuRefImage low;
    low.width = low.height = n;
    low.channels = 3;
    display_ref_guides(low_planes, n, cam, low.normal, low.position);
    std::vector<double> low_ind(3 * lp);
    low.values.resize(3 * lp);
    for (std::size_t i = 0; i < 3 * lp; ++i) {
        low_ind[i] = display_ref_signed(display_ref_signed(low_lightmap[i]) -
                                        display_ref_light(low_planes[frame_plane(Feature::Direct) * lp + i]));
        low.values[i] = float(low_ind[i]);
    }
    std::vector<float> normal, position;
    display_ref_guides(display_planes, S, cam, normal, position);

    std::vector<double> cur(3 * hp, 0.0);
    if (s.upsampler == DisplayUpsampler::Jbu) {
        JbuRefParams p;
        p.sigma_spatial = s.sigma_spatial;
        p.normal_power = s.normal_power;
        p.sigma_plane = s.sigma_plane;
        p.radius = s.radius;
        const JbuRefResult j = jbu_reference(low, normal, position, S, S, p);
        cur = j.out;
        r.jbu_fallbacks = j.fallbacks;
        for (std::size_t i = 0; i < hp; ++i) r.borderline[i] |= j.borderline[i];
    } else {
        for (int y = 0; y < S; ++y)
            for (int x = 0; x < S; ++x) {
                const double fx = std::clamp((x + 0.5) * n / S - 0.5, 0.0, double(n - 1));
                const double fy = std::clamp((y + 0.5) * n / S - 0.5, 0.0, double(n - 1));
                const int x0 = int(fx), y0 = int(fy), x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
                const double ax = fx - x0, ay = fy - y0;
                for (int c = 0; c < 3; ++c) {
                    auto v = [&](int i, int j) { return low_ind[c * lp + std::size_t(j) * n + i]; };
                    cur[c * hp + std::size_t(y) * S + x] =
                        (1 - ay) * ((1 - ax) * v(x0, y0) + ax * v(x1, y0)) + ay * ((1 - ax) * v(x0, y1) + ax * v(x1, y1));
                }
            }
    }

    std::vector<double> ind = cur;
    if (s.temporal) {
        for (int y = 0; y < S; ++y)
            for (int x = 0; x < S; ++x) {
                const std::size_t i = std::size_t(y) * S + x;
                double nrm2 = 0;
                for (int k = 0; k < 3; ++k) nrm2 += double(normal[k * hp + i]) * normal[k * hp + i];
                if (!st.has_history || nrm2 < 0.25) continue;
                double q[3];
                for (int k = 0; k < 3; ++k) q[k] = double(position[k * hp + i]) - st.prev.c[k];
                auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
                const double z = dot(q, st.prev.look), u = dot(q, st.prev.right) / z, v = dot(q, st.prev.up) / z;
                double acc[3] = {0, 0, 0}, wsum = 0;
                if (z > 1e-6 && std::abs(u) <= 2 && std::abs(v) <= 2) {
                    const double fx = (u + 1) * 0.5 * S - 0.5, fy = (1 - v) * 0.5 * S - 0.5;
                    const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
                    const double ax = fx - x0, ay = fy - y0, tol = s.depth_rel * z + s.depth_abs;
                    for (int t = 0; t < 4; ++t) {
                        const int tx = x0 + (t & 1), ty = y0 + (t >> 1);
                        if (tx < 0 || ty < 0 || tx >= S || ty >= S) continue;
                        const std::size_t j = std::size_t(ty) * S + tx;
                        const double gap = std::abs(st.prev_depth[j] - z);
                        if (std::abs(gap - tol) <= 1e-3 * tol + 1e-5) r.borderline[i] = 1;
                        if (!(gap <= tol)) continue;
                        const double w = ((t & 1) ? ax : 1 - ax) * ((t >> 1) ? ay : 1 - ay);
                        if (w <= 0) continue;
                        for (int c = 0; c < 3; ++c) acc[c] += w * display_ref_signed(st.history[c * hp + j]);
                        wsum += w;
                    }
                }
                if (!(wsum > 1e-4)) {
                    ++r.disoccluded;
                    continue;
                }
                double h[3];
                for (int c = 0; c < 3; ++c) h[c] = acc[c] / wsum;
                if (s.clip_margin >= 0) {
                    const int cx = std::clamp(int(std::floor((x + 0.5) * n / S)), 0, n - 1);
                    const int cy = std::clamp(int(std::floor((y + 0.5) * n / S)), 0, n - 1);
                    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, sum[3] = {0, 0, 0};
                    int taps = 0;
                    for (int ty = cy - 1; ty <= cy + 1; ++ty)
                        for (int tx = cx - 1; tx <= cx + 1; ++tx) {
                            if (tx < 0 || ty < 0 || tx >= n || ty >= n) continue;
                            const std::size_t j = std::size_t(ty) * n + tx;
                            double l2 = 0;
                            for (int k = 0; k < 3; ++k) l2 += double(low.normal[k * lp + j]) * low.normal[k * lp + j];
                            if (l2 < 0.25) continue;
                            for (int c = 0; c < 3; ++c) {
                                const double v2 = low_ind[c * lp + j];
                                lo[c] = std::min(lo[c], v2);
                                hi[c] = std::max(hi[c], v2);
                                sum[c] += v2;
                            }
                            ++taps;
                        }
                    if (taps > 0) {
                        const double m = s.clip_margin * (std::abs(sum[0]) + std::abs(sum[1]) + std::abs(sum[2])) / taps / 3;
                        bool moved = false;
                        for (int c = 0; c < 3; ++c) {
                            const double cl = std::clamp(h[c], lo[c] - m, hi[c] + m);
                            if (cl != h[c]) moved = true;
                            h[c] = cl;
                        }
                        r.clipped += moved;
                    }
                }
                for (int c = 0; c < 3; ++c) ind[c * hp + i] = h[c] + s.blend * (cur[c * hp + i] - h[c]);
            }
        st.has_history = true;
        st.history = ind;
        st.prev_depth.assign(hp, 0.0);
        for (std::size_t i = 0; i < hp; ++i) st.prev_depth[i] = display_planes[frame_plane(Feature::Depth) * hp + i];
        st.prev = cam;
    }

    r.lightmap.assign(3 * hp, 0.0);
    r.final_image.assign(3 * hp, 0.0);
    for (std::size_t i = 0; i < 3 * hp; ++i) {
        const double light = std::clamp(display_ref_light(display_planes[frame_plane(Feature::Direct) * hp + i]) +
                                            display_ref_signed(ind[i]), 0.0, double(FLT_MAX));
        r.lightmap[i] = light;
        const double a = display_planes[frame_plane(Feature::Albedo) * hp + i];
        double v = (std::isnan(a) ? 0.0 : std::clamp(a, 0.0, 1.0)) * light;
        if (has_emission) v = std::min(v + display_ref_light(display_planes[frame_plane(Feature::Emission) * hp + i]), double(FLT_MAX));
        if (has_env) v = std::min(v + display_ref_light(display_planes[frame_plane(Feature::Env) * hp + i]), double(FLT_MAX));
        r.final_image[i] = v;
    }
    return r;
}

}  // namespace ngi::test

// Naive C++ references for the surround-aware pipeline's kernels (globalview.cl, gbuffer.cl, compose.cl),
// written from docs/CONVENTIONS.md, sharing no code with host/src/pipeline. Double precision where it matters.
#pragma once
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <vector>

#include "ngi/image.hpp"

namespace ngi::ref {

// Bilinear sample of one channel of an N x N face at continuous pixel coordinates (col, row) (pixel centres at
// +0.5), edge texels clamped.
inline double sample_face(const Image& face, int c, double col, double row) {
    const int n = face.width;
    const double fx = std::clamp(col - 0.5, 0.0, double(n - 1)), fy = std::clamp(row - 0.5, 0.0, double(n - 1));
    const int x0 = int(fx), y0 = int(fy), x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
    const double ax = fx - x0, ay = fy - y0;
    return (1 - ay) * ((1 - ax) * face.at(c, y0, x0) + ax * face.at(c, y0, x1)) +
           ay * ((1 - ax) * face.at(c, y1, x0) + ax * face.at(c, y1, x1));
}

// Thesis MergeToGlobalView, from the layout's description in face-image terms: the middle band copies the side
// faces; band columns walk the up (down) face's square perimeter, rows walk from that point to the centre.
// faces[f] in Face order.
inline Image merge_thesis(const Image* faces, int n) {
    const int w = 4 * n, h = 2 * n, ch = faces[0].channels;
    Image out(w, h, ch);
    // Side face segments starting at the left face's left edge (global column N/2): left, front, right, back.
    const Face seg_face[4] = {Face::Left, Face::Front, Face::Right, Face::Back};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int q = (x - n / 2 + w) % w;  // integer column from the left face's left edge
            const int k = q / n, col = q % n;
            for (int c = 0; c < ch; ++c) {
                double v;
                if (y >= n / 2 && y < 3 * n / 2) {
                    v = faces[int(seg_face[k])].at(c, y - n / 2, col);
                } else {
                    const double s = 2.0 * (col + 0.5) / n - 1.0;  // position along the side face's edge
                    // Perimeter point (u, v) of the up face (up: +z, right: +x) or the down face (up: -z).
                    const double up_u[4] = {-1, s, 1, -s}, up_v[4] = {-s, -1, s, 1};
                    const double dn_u[4] = {-1, s, 1, -s}, dn_v[4] = {s, 1, -s, -1};
                    const bool top = y < n / 2;
                    const double t = top ? (y + 0.5) / (n / 2) : (2 * n - y - 0.5) / (n / 2);
                    const double u = t * (top ? up_u[k] : dn_u[k]), vv = t * (top ? up_v[k] : dn_v[k]);
                    const Image& f = faces[int(top ? Face::Up : Face::Down)];
                    v = sample_face(f, c, (u + 1) / 2 * n, (1 - vv) / 2 * n);
                }
                out.at(c, y, x) = float(v);
            }
        }
    return out;
}

// Preprocessing of one texel (docs/CONVENTIONS.md, "Preprocessing"). Inputs are raw values; outputs in [0, 1]
// (before the model's input scaling). S rows = alpha, beta, gamma. bad counts non-finite inputs per feature.
struct PreTexel {
    float albedo[3], normal[3], depth, lum[3];
    int bad[6] = {};
    bool sky = false, far = false;
};

inline PreTexel preprocess_texel(const float albedo[3], const float normal[3], float depth, const float direct[3],
                                 const float* emission, const float* env, const float S[3][3], bool reinhard) {
    PreTexel o;
    for (int c = 0; c < 3; ++c) {
        float a = albedo[c];
        if (std::isnan(a)) { a = 0; ++o.bad[0]; }
        else if (std::isinf(a)) { a = a > 0 ? 1.f : 0.f; ++o.bad[0]; }
        o.albedo[c] = std::clamp(a, 0.0f, 1.0f);
    }
    bool finite = true;
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(normal[c])) { finite = false; ++o.bad[1]; }
    double n[3] = {normal[0], normal[1], normal[2]};
    const double m = std::max({std::abs(n[0]), std::abs(n[1]), std::abs(n[2])});
    double cl[3] = {0, 0, 0};
    if (finite && m >= 1e-6) {
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int r = 0; r < 3; ++r) cl[r] = (S[r][0] * n[0] + S[r][1] * n[1] + S[r][2] * n[2]) / len;
    } else {
        o.sky = true;
    }
    for (int c = 0; c < 3; ++c) o.normal[c] = float(std::clamp(cl[c] * 0.5 + 0.5, 0.0, 1.0));
    double d = depth;
    if (std::isnan(d) || std::isinf(d)) { ++o.bad[2]; d = (std::isnan(d) || d > 0) ? 1000.0 : 0.0; }
    o.far = d > 1000.0;
    o.depth = float(std::clamp(d / 1000.0, 0.0, 1.0));
    auto light = [&](float v, int slot) -> double {
        if (std::isnan(v)) { ++o.bad[slot]; return 0; }
        if (std::isinf(v)) { ++o.bad[slot]; return v > 0 ? double(FLT_MAX) : 0.0; }
        return std::max(double(v), 0.0);
    };
    for (int c = 0; c < 3; ++c) {
        double l = light(direct[c], 3);
        if (emission) l += light(emission[c], 4);
        if (env) l += light(env[c], 5);
        l = std::min(l, double(FLT_MAX));
        o.lum[c] = float(reinhard ? l / (1.0 + l) : std::min(l, 1.0));
    }
    return o;
}

// Model output value in [lo, hi] -> linear lightmap (inverse transfer, capped at 65504).
inline double decode_light(float v, float lo, float hi, bool reinhard) {
    double y = (double(v) - lo) / (double(hi) - lo);
    y = std::isnan(y) ? 0.0 : std::clamp(y, 0.0, 1.0);
    if (!reinhard) return y;
    return y >= 1.0 ? 65504.0 : std::min(y / (1.0 - y), 65504.0);
}

inline double clean_light(float v) { return std::isnan(v) ? 0.0 : std::clamp(double(v), 0.0, double(FLT_MAX)); }

// final = lightmap * clamp(albedo) + emission + env.
inline double compose(float light, float albedo, const float* emission, const float* env) {
    const double a = std::isnan(albedo) ? 0.0 : std::clamp(double(albedo), 0.0, 1.0);
    double v = clean_light(light) * a;
    if (emission) v += clean_light(*emission);
    if (env) v += clean_light(*env);
    return std::min(v, double(FLT_MAX));
}

// curve: 0 ACES fitted (Narkowicz), 1 Reinhard, 2 clamp; then the sRGB OETF.
inline double tonemap(float v, double scale, int curve, bool srgb) {
    double x = std::isnan(v) ? 0.0 : std::max(double(v), 0.0);
    x = std::min(x * scale, double(FLT_MAX));
    if (curve == 0) {
        x = std::min(x, 1e4);
        x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    } else if (curve == 1) {
        x = x / (1 + x);
    }
    x = std::clamp(x, 0.0, 1.0);
    if (srgb) x = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
    return std::clamp(x, 0.0, 1.0);
}

// Bilinear resize, pixel centres at +0.5 (align_corners = False), edges clamped.
inline Image resize(const Image& in, int w, int h) {
    Image out(w, h, in.channels);
    for (int c = 0; c < in.channels; ++c)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double fx = std::clamp((x + 0.5) * in.width / w - 0.5, 0.0, double(in.width - 1));
                const double fy = std::clamp((y + 0.5) * in.height / h - 0.5, 0.0, double(in.height - 1));
                const int x0 = int(fx), y0 = int(fy);
                const int x1 = std::min(x0 + 1, in.width - 1), y1 = std::min(y0 + 1, in.height - 1);
                const double ax = fx - x0, ay = fy - y0;
                out.at(c, y, x) = float((1 - ay) * ((1 - ax) * in.at(c, y0, x0) + ax * in.at(c, y0, x1)) +
                                        ay * ((1 - ax) * in.at(c, y1, x0) + ax * in.at(c, y1, x1)));
            }
    return out;
}

}  // namespace ngi::ref

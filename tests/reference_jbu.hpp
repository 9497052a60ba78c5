// Naive double-precision reference of joint bilateral upsampling (kernels/jbu.cl, docs/CONVENTIONS.md section 18),
// written from the convention, not from the kernel: loops over every output pixel and its tap window.
#pragma once
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <vector>

#include "ops/jbu.hpp"

namespace ngi::test {

struct JbuRefImage {
    int width = 0, height = 0, channels = 0;
    std::vector<float> values;    // [channels][height][width]
    std::vector<float> normal;    // [3][height][width]
    std::vector<float> position;  // [3][height][width]
};

struct JbuRefParams {
    double sigma_spatial = 0.75, normal_power = 32, sigma_plane = 0.1, fallback_ratio = 1e-6;
    int radius = 2;
};

// The op's parameters (ops/jbu.hpp) as the reference takes them, in double.
inline JbuRefParams jbu_ref_params(const detail::JbuParams& p) {
    JbuRefParams r;
    r.sigma_spatial = p.sigma_spatial;
    r.normal_power = p.normal_power;
    r.sigma_plane = p.sigma_plane;
    r.fallback_ratio = p.fallback_ratio;
    r.radius = p.radius;
    return r;
}

struct JbuRefResult {
    std::vector<double> out;       // [channels][H][W]
    std::vector<char> fallback;    // per pixel: 1 = bilinear fallback
    std::vector<char> borderline;  // per pixel: the weight sum within 1% of the fallback threshold (the float
                                   // kernel may decide the other way there)
    int fallbacks = 0;
};

inline double jbu_ref_clean(double v) {
    return std::isnan(v) ? 0.0 : std::clamp(v, -double(FLT_MAX), double(FLT_MAX));
}

// low: the low-resolution image with its guides; normal/position: the output-resolution guides [3][H][W].
inline JbuRefResult jbu_reference(const JbuRefImage& low, const std::vector<float>& normal,
                                  const std::vector<float>& position, int W, int H, const JbuRefParams& p) {
    const int w = low.width, h = low.height, C = low.channels;
    const std::size_t lo_plane = std::size_t(w) * h, hi_plane = std::size_t(W) * H;
    auto vec3 = [](const std::vector<float>& v, std::size_t i, std::size_t plane, double out[3]) {
        bool finite = true;
        for (int k = 0; k < 3; ++k) {
            out[k] = v[k * plane + i];
            finite = finite && std::isfinite(out[k]);
        }
        return finite;
    };
    auto surface = [](const double n[3], bool finite) { return finite && n[0] * n[0] + n[1] * n[1] + n[2] * n[2] >= 0.25; };
    JbuRefResult r;
    r.out.assign(C * hi_plane, 0.0);
    r.fallback.assign(hi_plane, 0);
    r.borderline.assign(hi_plane, 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const std::size_t o = std::size_t(y) * W + x;
            double nh[3], ph[3];
            const bool nf = vec3(normal, o, hi_plane, nh), pf = vec3(position, o, hi_plane, ph);
            if (!surface(nh, nf) || !pf) continue;  // no surface: 0
            // q = ((x + 0.5) w / W - 0.5, ...) as exact rationals num / (2 W): the tap window is floor(q) +- radius.
            const long nx = long(2 * x + 1) * w - W, ny = long(2 * y + 1) * h - H;
            const double qx = double(nx) / (2.0 * W), qy = double(ny) / (2.0 * H);
            const int fx0 = int(std::floor(qx)), fy0 = int(std::floor(qy));
            double spatial_sum = 0, weight_sum = 0;
            std::vector<double> acc(C, 0.0);
            for (int j = fy0 - p.radius + 1; j <= fy0 + p.radius; ++j)
                for (int i = fx0 - p.radius + 1; i <= fx0 + p.radius; ++i) {
                    if (i < 0 || j < 0 || i >= w || j >= h) continue;
                    const double spatial =
                        std::exp(-((i - qx) * (i - qx) + (j - qy) * (j - qy)) / (2 * p.sigma_spatial * p.sigma_spatial));
                    spatial_sum += spatial;
                    const std::size_t l = std::size_t(j) * w + i;
                    double nl[3], pl[3];
                    const bool lnf = vec3(low.normal, l, lo_plane, nl), lpf = vec3(low.position, l, lo_plane, pl);
                    if (!surface(nl, lnf) || !lpf) continue;
                    const double facing = std::max(0.0, nh[0] * nl[0] + nh[1] * nl[1] + nh[2] * nl[2]);
                    const double plane = nl[0] * (ph[0] - pl[0]) + nl[1] * (ph[1] - pl[1]) + nl[2] * (ph[2] - pl[2]);
                    const double wt = spatial * std::pow(facing, p.normal_power) *
                                      std::exp(-plane * plane / (2 * p.sigma_plane * p.sigma_plane));
                    weight_sum += wt;
                    for (int c = 0; c < C; ++c) acc[c] += wt * jbu_ref_clean(low.values[c * lo_plane + l]);
                }
            const double threshold = p.fallback_ratio * spatial_sum;
            r.borderline[o] = std::abs(weight_sum - threshold) <= 0.01 * threshold;
            if (weight_sum > threshold && weight_sum > 0) {
                for (int c = 0; c < C; ++c) r.out[c * hi_plane + o] = jbu_ref_clean(acc[c] / weight_sum);
                continue;
            }
            r.fallback[o] = 1;
            ++r.fallbacks;
            // Bilinear, pixel centres at +0.5, edges clamped (as the pipeline's resize_bilinear).
            const double fx = std::clamp(qx, 0.0, double(w - 1)), fy = std::clamp(qy, 0.0, double(h - 1));
            const int x0 = int(fx), y0 = int(fy), x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
            const double ax = fx - x0, ay = fy - y0;
            for (int c = 0; c < C; ++c) {
                auto v = [&](int i, int j) { return jbu_ref_clean(low.values[c * lo_plane + std::size_t(j) * w + i]); };
                const double top = (1 - ax) * v(x0, y0) + ax * v(x1, y0), bottom = (1 - ax) * v(x0, y1) + ax * v(x1, y1);
                r.out[c * hi_plane + o] = jbu_ref_clean((1 - ay) * top + ay * bottom);
            }
        }
    return r;
}

}  // namespace ngi::test

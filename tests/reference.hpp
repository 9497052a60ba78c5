// Naive C++ references for every kernel: straight loops in double precision, written from the definitions
// (PyTorch's documented semantics), sharing no code with the library.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace ngi::ref {

inline double activate(double x, int act, double alpha) {
    switch (act) {
        case 1: return x > 0 ? x : 0;
        case 2: return x >= 0 ? x : alpha * x;
        case 3: return std::tanh(x);
        case 4: return 1.0 / (1.0 + std::exp(-x));
        case 5: return std::exp(std::min(x, 88.0));
        case 6: return x > 30 ? x + std::log1p(std::exp(-x)) : std::log1p(std::exp(x));  // softplus, log(1 + e^x)
        case 7: return std::erf(x);
        default: return x;
    }
}

// y[co][oy][ox] = act(scale[co] * (sum w[co][ci][ky][kx] * in_act(x[ci][iy][ix])) + shift[co])
inline std::vector<float> conv2d(const std::vector<float>& x, int C, int H, int W, const std::vector<float>& w, int Co,
                                 int KH, int KW, int s, int p, const std::vector<float>& scale,
                                 const std::vector<float>& shift, int in_act, int act, double alpha, int& OH, int& OW) {
    OH = (H + 2 * p - KH) / s + 1;
    OW = (W + 2 * p - KW) / s + 1;
    std::vector<float> y(std::size_t(Co) * OH * OW);
    for (int co = 0; co < Co; ++co)
        for (int oy = 0; oy < OH; ++oy)
            for (int ox = 0; ox < OW; ++ox) {
                double acc = 0;
                for (int ci = 0; ci < C; ++ci)
                    for (int ky = 0; ky < KH; ++ky)
                        for (int kx = 0; kx < KW; ++kx) {
                            int iy = oy * s - p + ky, ix = ox * s - p + kx;
                            if (iy < 0 || iy >= H || ix < 0 || ix >= W) continue;
                            acc += double(w[((std::size_t(co) * C + ci) * KH + ky) * KW + kx]) *
                                   activate(x[(std::size_t(ci) * H + iy) * W + ix], in_act, alpha);
                        }
                y[(std::size_t(co) * OH + oy) * OW + ox] = float(activate(acc * scale[co] + shift[co], act, alpha));
            }
    return y;
}

// PyTorch ConvTranspose2d: w is [C][Co][KH][KW]; each input pixel scatters into the output.
inline std::vector<float> conv_transpose2d(const std::vector<float>& x, int C, int H, int W,
                                           const std::vector<float>& w, int Co, int KH, int KW, int s, int p,
                                           const std::vector<float>& scale, const std::vector<float>& shift,
                                           int in_act, int act, double alpha, int& OH, int& OW) {
    OH = (H - 1) * s - 2 * p + KH;
    OW = (W - 1) * s - 2 * p + KW;
    std::vector<double> acc(std::size_t(Co) * OH * OW, 0.0);
    for (int ci = 0; ci < C; ++ci)
        for (int iy = 0; iy < H; ++iy)
            for (int ix = 0; ix < W; ++ix) {
                double v = activate(x[(std::size_t(ci) * H + iy) * W + ix], in_act, alpha);
                for (int co = 0; co < Co; ++co)
                    for (int ky = 0; ky < KH; ++ky)
                        for (int kx = 0; kx < KW; ++kx) {
                            int oy = iy * s - p + ky, ox = ix * s - p + kx;
                            if (oy < 0 || oy >= OH || ox < 0 || ox >= OW) continue;
                            acc[(std::size_t(co) * OH + oy) * OW + ox] +=
                                v * w[((std::size_t(ci) * Co + co) * KH + ky) * KW + kx];
                        }
            }
    std::vector<float> y(acc.size());
    for (int co = 0; co < Co; ++co)
        for (int i = 0; i < OH * OW; ++i) {
            std::size_t j = std::size_t(co) * OH * OW + i;
            y[j] = float(activate(acc[j] * scale[co] + shift[co], act, alpha));
        }
    return y;
}

// Per-image batch norm: two-pass mean / biased variance in double, then act(gamma*(x-mean)/sqrt(var+eps)+beta).
inline std::vector<float> batch_norm_per_image(const std::vector<float>& x, int C, int HW,
                                               const std::vector<float>& gamma, const std::vector<float>& beta,
                                               double eps, int act, double alpha) {
    std::vector<float> y(x.size());
    for (int c = 0; c < C; ++c) {
        double mean = 0, var = 0;
        for (int i = 0; i < HW; ++i) mean += x[std::size_t(c) * HW + i];
        mean /= HW;
        for (int i = 0; i < HW; ++i) { double d = x[std::size_t(c) * HW + i] - mean; var += d * d; }
        var /= HW;
        for (int i = 0; i < HW; ++i) {
            std::size_t j = std::size_t(c) * HW + i;
            y[j] = float(activate((x[j] - mean) / std::sqrt(var + eps) * gamma[c] + beta[c], act, alpha));
        }
    }
    return y;
}

// Frequency encoding of one item (docs/CONVENTIONS.md section 13): [v if raw], then per the order the pairs
// sin(2^(e0 + b) [pi] v_c), cos(...). order 0: per component, per band (sin, cos); 1: per band, sin of every
// component then cos of every component.
inline std::vector<double> frequency_encode(const std::vector<double>& v, int bands, int e0, bool pi, bool raw,
                                            int order) {
    if (bands == 0) return v;
    std::vector<double> out;
    if (raw) out = v;
    const double kPi = 3.14159265358979323846;
    auto scale = [&](int b) { return std::ldexp(1.0, e0 + b) * (pi ? kPi : 1.0); };
    if (order == 0) {
        for (double x : v)
            for (int b = 0; b < bands; ++b) {
                out.push_back(std::sin(scale(b) * x));
                out.push_back(std::cos(scale(b) * x));
            }
    } else {
        for (int b = 0; b < bands; ++b) {
            for (double x : v) out.push_back(std::sin(scale(b) * x));
            for (double x : v) out.push_back(std::cos(scale(b) * x));
        }
    }
    return out;
}

// One dense layer: y[o] = act(sum_i w[o][i] x[i] + b[o]), w row-major [out][in].
inline std::vector<double> dense(const std::vector<double>& x, const std::vector<float>& w, const std::vector<float>& b,
                                 int out, int act, double alpha) {
    std::vector<double> y(out);
    const std::size_t in = x.size();
    for (int o = 0; o < out; ++o) {
        double s = b.empty() ? 0.0 : b[o];
        for (std::size_t i = 0; i < in; ++i) s += double(w[o * in + i]) * x[i];
        y[o] = activate(s, act, alpha);
    }
    return y;
}

// C[m][n] = act(scale[m] * sum_k a[m][k] b[k][n] + shift[m]): a row-major M x K, b row-major K x N (LeakyReLU
// slope 0.2, as the GEMM tests use).
inline std::vector<float> gemm(int M, int N, int K, const std::vector<float>& a, const std::vector<float>& b,
                               const std::vector<float>& scale, const std::vector<float>& shift, int act) {
    std::vector<float> out(std::size_t(M) * N);
    std::vector<double> row(N);
    for (int m = 0; m < M; ++m) {
        std::fill(row.begin(), row.end(), 0.0);
        for (int k = 0; k < K; ++k) {
            const double av = a[std::size_t(m) * K + k];
            const float* br = &b[std::size_t(k) * N];
            for (int n = 0; n < N; ++n) row[n] += av * br[n];
        }
        for (int n = 0; n < N; ++n)
            out[std::size_t(m) * N + n] = float(activate(row[n] * scale[m] + shift[m], act, 0.2));
    }
    return out;
}

// Real SH Y_lm with the Condon-Shortley phase from the textbook definition: theta from +z, phi = atan2(y, x);
// std::assoc_legendre omits the (-1)^m phase, so it is applied here. (x, y, z) a unit vector.
inline double sh_basis(int l, int m, double x, double y, double z) {
    const double kPi = 3.14159265358979323846;
    const double theta = std::acos(std::clamp(z, -1.0, 1.0)), phi = std::atan2(y, x);
    const int am = std::abs(m);
    double fact = 1.0;  // (l - |m|)! / (l + |m|)!
    for (int k = l - am + 1; k <= l + am; ++k) fact /= k;
    const double K = std::sqrt((2 * l + 1) / (4 * kPi) * fact);
    const double P = (am % 2 ? -1.0 : 1.0) * std::assoc_legendre(unsigned(l), unsigned(am), std::cos(theta));
    if (m == 0) return K * P;
    return std::sqrt(2.0) * K * P * (m > 0 ? std::cos(am * phi) : std::sin(am * phi));
}

// Input sanitizing (Elementwise::sanitize): NaN -> 0; beyond [lo, hi] widened by (hi - lo) / 1024 on each side
// (+-Inf included) -> the nearer end; everything else unchanged.
inline double sanitize(double v, double lo, double hi) {
    const double margin = (hi - lo) / 1024.0;
    if (std::isnan(v)) return 0.0;
    if (v > hi + margin) return hi;
    if (v < lo - margin) return lo;
    return v;
}

// Whether seeded dropout keeps flat element i (docs/MODEL_FORMAT.md: the 32-bit finalizer hash of seed, site and
// index; kept when (hash >> 8) / 2^24 >= p).
inline bool dropout_keeps(std::uint32_t seed, std::uint32_t site, std::uint32_t i, double p) {
    auto mix = [](std::uint32_t x) {
        x ^= x >> 16; x *= 0x7feb352du;
        x ^= x >> 15; x *= 0x846ca68bu;
        x ^= x >> 16;
        return x;
    };
    const std::uint32_t u = mix(mix(seed + 0x9E3779B9u * (site + 1u)) ^ i);
    return double(u >> 8) / 16777216.0 >= p;
}

// Max (or mean) per set and channel: set s holds items first[s] .. first[s+1]-1; item i's channel c at
// i * item_stride + c * channel_stride. Out [sets][channels]; an empty set pools to 0.
inline std::vector<double> set_pool(const std::vector<float>& x, int item_stride, int channel_stride, int channels,
                                    const std::vector<int>& first, bool max) {
    const int sets = int(first.size()) - 1;
    std::vector<double> out(std::size_t(sets) * channels, 0.0);
    for (int s = 0; s < sets; ++s)
        for (int c = 0; c < channels; ++c) {
            double acc = max ? -INFINITY : 0.0;
            for (int i = first[s]; i < first[s + 1]; ++i) {
                const double v = x[std::size_t(i) * item_stride + std::size_t(c) * channel_stride];
                acc = max ? std::max(acc, v) : acc + v;
            }
            const int count = first[s + 1] - first[s];
            out[std::size_t(s) * channels + c] = count == 0 ? 0.0 : max ? acc : acc / count;
        }
    return out;
}

// 2D max pooling (ONNX MaxPool, ceil_mode 0, dilation 1) of planar x [C][H][W]: the input padded with -Inf (pt, pb
// rows above and below, pl, pr columns left and right), then y[c][oy][ox] = the max of the KH x KW window at
// (oy * SH, ox * SW) of the padded plane; NaN when the window holds a NaN (PyTorch's max_pool2d). OH and OW:
// floor((H + pt + pb - KH) / SH) + 1 and the same across.
inline std::vector<float> max_pool2d(const std::vector<float>& x, int C, int H, int W, int KH, int KW, int SH, int SW,
                                     int pt, int pl, int pb, int pr, int& OH, int& OW) {
    const int PH = H + pt + pb, PW = W + pl + pr;
    OH = (PH - KH) / SH + 1;
    OW = (PW - KW) / SW + 1;
    std::vector<float> y(std::size_t(C) * OH * OW);
    for (int c = 0; c < C; ++c) {
        std::vector<float> padded(std::size_t(PH) * PW, -INFINITY);
        for (int iy = 0; iy < H; ++iy)
            for (int ix = 0; ix < W; ++ix)
                padded[std::size_t(iy + pt) * PW + ix + pl] = x[(std::size_t(c) * H + iy) * W + ix];
        for (int oy = 0; oy < OH; ++oy)
            for (int ox = 0; ox < OW; ++ox) {
                bool nan = false;
                float best = -INFINITY;
                for (int ky = 0; ky < KH; ++ky)
                    for (int kx = 0; kx < KW; ++kx) {
                        const float v = padded[std::size_t(oy * SH + ky) * PW + ox * SW + kx];
                        nan = nan || std::isnan(v);
                        if (!std::isnan(v)) best = std::max(best, v);
                    }
                y[(std::size_t(c) * OH + oy) * OW + ox] = nan ? std::numeric_limits<float>::quiet_NaN() : best;
            }
    }
    return y;
}

// 2D padding (ONNX Pad over H and W, PyTorch F.pad) of planar x [C][H][W] to [C][H + pt + pb][W + pl + pr]: the
// padded plane at (py, px) is x at (py - pt, px - pl) inside the input; outside it, mode 0 (constant) is `value`,
// mode 1 (reflect) the mirror image about the edge pixel, not repeating it (x[-k] = x[k], x[H - 1 + k] =
// x[H - 1 - k]; pads below the axis' size), mode 2 (edge) the nearest pixel of the input.
inline std::vector<float> pad2d(const std::vector<float>& x, int C, int H, int W, int pt, int pl, int pb, int pr,
                                int mode, float value) {
    const int OH = H + pt + pb, OW = W + pl + pr;
    // The input index a padded index reads along an axis of n pixels, -1 for the constant.
    auto source = [mode](int i, int n) {
        if (i >= 0 && i < n) return i;
        if (mode == 0) return -1;
        if (mode == 2) return i < 0 ? 0 : n - 1;
        return i < 0 ? -i : (n - 1) - (i - (n - 1));  // reflect: k before the first reads k, k past the last n-1-k
    };
    std::vector<float> y(std::size_t(C) * OH * OW);
    for (int c = 0; c < C; ++c)
        for (int oy = 0; oy < OH; ++oy)
            for (int ox = 0; ox < OW; ++ox) {
                const int iy = source(oy - pt, H), ix = source(ox - pl, W);
                y[(std::size_t(c) * OH + oy) * OW + ox] =
                    iy < 0 || ix < 0 ? value : x[(std::size_t(c) * H + iy) * W + ix];
            }
    return y;
}

// Bilinear resize (ONNX Resize, mode linear; PyTorch F.interpolate bilinear) of planar x [C][H][W] to [C][OH][OW],
// in double. Along an axis of `in` input and `out` output pixels, output coordinate o reads the source position
// s(o) of the coordinate transformation mode: 0 half_pixel (o + 1/2) / scale - 1/2; 1 pytorch_half_pixel, the same
// but 0 when out = 1; 2 align_corners o (in - 1) / (out - 1), 0 when out = 1; 3 asymmetric o / scale. A scale of 0
// stands for out / in (then o / scale is written o in / out, exact at integers). Taps and weights, PyTorch's
// (aten UpSample.h, compute_source_index_and_lambda): an axis with out = in and s(o) = o reads pixel o alone
// (weights 1, 0 on it twice); otherwise s is clamped below at 0, i0 = min(floor(s), in - 1), lambda = min(s - i0,
// 1), i1 = i0 + 1 below the last pixel, else i0. y = sum over the 2 x 2 taps of w_row w_col x, every product taken,
// so a NaN tap gives NaN and an infinite tap with weight 0 gives NaN (0 * Inf). Unrounded: doubles out.
inline std::vector<double> resize_bilinear(const std::vector<float>& x, int C, int H, int W, int OH, int OW,
                                           double scale_h, double scale_w, int mode) {
    struct Tap {
        int i0, i1;
        double lambda;
    };
    auto taps = [mode](int in, int out, double scale) {
        auto position = [&](int o) -> double {
            if ((mode == 1 || mode == 2) && out == 1) return 0.0;
            if (mode == 2) return double(o) * (in - 1) / (out - 1);
            if (mode == 3) return scale > 0 ? o / scale : double(o) * in / out;
            return scale > 0 ? (o + 0.5) / scale - 0.5 : (o + 0.5) * in / out - 0.5;
        };
        bool unchanged = out == in;
        for (int o = 0; o < out && unchanged; ++o) unchanged = position(o) == o;
        std::vector<Tap> t(out);
        for (int o = 0; o < out; ++o) {
            if (unchanged) {
                t[o] = {o, o, 0.0};
                continue;
            }
            const double s = std::max(position(o), 0.0);
            const int i0 = int(std::min(std::floor(s), double(in - 1)));
            t[o] = {i0, i0 < in - 1 ? i0 + 1 : i0, std::min(s - i0, 1.0)};
        }
        return t;
    };
    const std::vector<Tap> ty = taps(H, OH, scale_h), tx = taps(W, OW, scale_w);
    std::vector<double> y(std::size_t(C) * OH * OW);
    for (int c = 0; c < C; ++c)
        for (int oy = 0; oy < OH; ++oy)
            for (int ox = 0; ox < OW; ++ox) {
                const int rows[2] = {ty[oy].i0, ty[oy].i1}, cols[2] = {tx[ox].i0, tx[ox].i1};
                const double wr[2] = {1.0 - ty[oy].lambda, ty[oy].lambda}, wc[2] = {1.0 - tx[ox].lambda, tx[ox].lambda};
                double sum = 0.0;
                for (int r = 0; r < 2; ++r) {
                    double row = 0.0;
                    for (int k = 0; k < 2; ++k) row += wc[k] * double(x[(std::size_t(c) * H + rows[r]) * W + cols[k]]);
                    sum += wr[r] * row;
                }
                y[(std::size_t(c) * OH + oy) * OW + ox] = sum;
            }
    return y;
}

}  // namespace ngi::ref

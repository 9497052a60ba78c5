// Naive double-precision references for the voxel ops: seed 004's light-transition function (ops/voxel_ltf.*) and
// probe shading (ops/probe_shade.*). Straight loops over the definitions in docs/VOXEL_LTF.md, no shared code
// with the kernels beyond the constants they must agree on, which are the host's (kLtfRMin, kMaxSurfaceDepth,
// probe_neighbour_offsets(): the values the kernels are built with).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ops/probe_shade.hpp"
#include "ops/voxel_ltf.hpp"

namespace ngi::test {

// ---- light-transition function -----------------------------------------------------------------------------

// V voxels, float4 per voxel (w unused) as the op takes them; exposed: bit f = face f (0 +x, 1 -x, ... 5 -z).
struct LtfScene {
    int voxels = 0;
    std::vector<float> position, normal, albedo, direct;
    std::vector<std::uint32_t> exposed;
};

constexpr double kRefLtfRMin = ngi::detail::kLtfRMin;  // docs/VOXEL_LTF.md: r is clamped below in every 1 / r^2

inline double ref_luminance(const double* c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

// out [V][4] (w = 0) after `bounces` bounces. physical: L^{t+1}_i = d_i + sum_{j != i} V_ij G_ij rho_j L^t_j;
// otherwise E^{t+1}_i = sum_{j != i} T_ij rho_j E^t_j, out = E^0 + ... + E^t. vis: null or [V][ceil(V/32)] bits.
// energy: per iterate the luminance sum of E^t (as written) or of L^t - L^{t-1} (physical).
inline std::vector<double> ltf_reference(const LtfScene& s, int bounces, bool physical,
                                         const std::vector<std::uint32_t>* vis, std::vector<double>* energy = nullptr) {
    const int V = s.voxels, words = (V + 31) / 32;
    auto P = [&](const std::vector<float>& a, int i, int c) { return double(a[std::size_t(4) * i + c]); };
    // Pair factors, without the sender's light: G_ij (physical, already / pi) or |n_i . w| / max(r^2, r_min^2).
    auto transfer = [&](int i, int j) {
        double d[3], r2 = 0;
        for (int c = 0; c < 3; ++c) { d[c] = P(s.position, j, c) - P(s.position, i, c); r2 += d[c] * d[c]; }
        const double r = std::sqrt(r2);
        double w[3];
        for (int c = 0; c < 3; ++c) w[c] = r > 0 ? d[c] / r : 0.0;
        double cosi = 0;
        for (int c = 0; c < 3; ++c) cosi += P(s.normal, i, c) * w[c];
        const double inv_r2 = 1.0 / std::max(r2, kRefLtfRMin * kRefLtfRMin);
        if (!physical) return std::abs(cosi) * inv_r2;
        // A_j(-w): the exposed unit faces of j, each seen with max(0, n_f . (-w)).
        double area = 0;
        for (int f = 0; f < 6; ++f) {
            if (!((s.exposed[j] >> f) & 1u)) continue;
            const double nf = (f & 1) ? -1.0 : 1.0;
            area += std::max(0.0, nf * -w[f >> 1]);
        }
        return std::max(0.0, cosi) * area * inv_r2 / M_PI;
    };
    auto visible = [&](int i, int j) {
        return !vis || (((*vis)[std::size_t(i) * words + (j >> 5)] >> (j & 31)) & 1u);
    };
    std::vector<double> Z(V, 0.0);
    if (!physical)
        for (int j = 0; j < V; ++j)
            for (int k = 0; k < V; ++k) {
                if (k == j) continue;
                double r2 = 0;
                for (int c = 0; c < 3; ++c) r2 += std::pow(P(s.position, k, c) - P(s.position, j, c), 2);
                Z[j] += 1.0 / std::max(r2, kRefLtfRMin * kRefLtfRMin);
            }
    std::vector<double> cur(std::size_t(V) * 4, 0.0), total, next(cur.size());
    for (int i = 0; i < V; ++i)
        for (int c = 0; c < 3; ++c) cur[std::size_t(4) * i + c] = P(s.direct, i, c);
    total = cur;
    auto lum_sum = [&](const std::vector<double>& a, const std::vector<double>* b) {
        double e = 0;
        for (int i = 0; i < V; ++i) {
            double x[3];
            for (int c = 0; c < 3; ++c) x[c] = a[std::size_t(4) * i + c] - (b ? (*b)[std::size_t(4) * i + c] : 0.0);
            e += ref_luminance(x);
        }
        return e;
    };
    if (energy) energy->assign(1, lum_sum(cur, nullptr));
    for (int b = 1; b <= bounces; ++b) {
        for (int i = 0; i < V; ++i)
            for (int c = 0; c < 3; ++c) {
                double acc = physical ? P(s.direct, i, c) : 0.0;
                for (int j = 0; j < V; ++j) {
                    if (j == i || !visible(i, j)) continue;
                    const double scale = physical ? 1.0 : (Z[j] > 0 ? 1.0 / Z[j] : 0.0);
                    acc += transfer(i, j) * P(s.albedo, j, c) * cur[std::size_t(4) * j + c] * scale;
                }
                next[std::size_t(4) * i + c] = acc;
            }
        if (energy) energy->push_back(physical ? lum_sum(next, &cur) : lum_sum(next, nullptr));
        if (!physical)
            for (std::size_t k = 0; k < total.size(); ++k) total[k] += next[k];
        std::swap(cur, next);
    }
    return physical ? cur : total;
}

// ---- probe shading -------------------------------------------------------------------------------------------

struct ProbeRefInputs {
    int n = 0;
    std::vector<float> depth, normal;  // [n*n], [3][n*n]
    double centre[3], look[3], right[3], up[3];
    int grid[3];
    std::vector<int> index_of;
    int voxels = 0;
    bool sh = true;
    std::vector<float> field;  // [V][3][9] or [V][4]
};

struct ProbeRefResult {
    std::vector<double> lighting;  // [3][n*n]
    std::vector<int> voxel;        // [n*n]: the voxel used, -1 for none
    long no_voxel = 0, non_finite = 0;
};

inline ProbeRefResult probe_shade_reference(const ProbeRefInputs& in) {
    const int n = in.n, npix = n * n;
    const int X = in.grid[0], Y = in.grid[1], Z = in.grid[2];
    ProbeRefResult r;
    r.lighting.assign(std::size_t(3) * npix, 0.0);
    r.voxel.assign(npix, -1);
    const auto offsets = ngi::detail::probe_neighbour_offsets();
    static const double Y0 = 0.28209479177387814, Y1 = 0.48860251190291992, Y2 = 1.0925484305920792,
                        Y20 = 0.31539156525252005, Y22 = 0.54627421529603959;
    const double lobe[9] = {M_PI, 2 * M_PI / 3, 2 * M_PI / 3, 2 * M_PI / 3, M_PI / 4, M_PI / 4, M_PI / 4, M_PI / 4, M_PI / 4};
    for (int pix = 0; pix < npix; ++pix) {
        const int row = pix / n, col = pix % n;
        const double t = in.depth[pix];
        const double nr[3] = {in.normal[pix], in.normal[std::size_t(npix) + pix], in.normal[std::size_t(2) * npix + pix]};
        if (!std::isfinite(t) || !std::isfinite(nr[0]) || !std::isfinite(nr[1]) || !std::isfinite(nr[2])) {
            ++r.non_finite;
            continue;
        }
        if (t > ngi::detail::kMaxSurfaceDepth) continue;  // no surface (sky)
        const double u = 2.0 * (col + 0.5) / n - 1.0, v = 1.0 - 2.0 * (row + 0.5) / n;
        double dir[3], dl = 0;
        for (int c = 0; c < 3; ++c) { dir[c] = in.look[c] + u * in.right[c] + v * in.up[c]; dl += dir[c] * dir[c]; }
        dl = std::sqrt(dl);
        double along = 0;
        for (int c = 0; c < 3; ++c) { dir[c] /= dl; along += dir[c] * in.look[c]; }
        const double len = std::sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
        int id = -1;
        if (len > 0 && along > 0) {
            double q[3];
            for (int c = 0; c < 3; ++c) q[c] = in.centre[c] + dir[c] * (t / along) - 0.5 * nr[c];
            for (const auto& o : offsets) {
                double cell[3];
                for (int c = 0; c < 3; ++c) cell[c] = std::floor(q[c] + double(ngi::detail::kProbeNeighbourStep) * o[c]);
                if (cell[0] < 0 || cell[1] < 0 || cell[2] < 0 || cell[0] >= X || cell[1] >= Y || cell[2] >= Z) continue;
                const std::size_t lin =
                    std::size_t(cell[0]) + std::size_t(X) * (std::size_t(cell[1]) + std::size_t(Y) * std::size_t(cell[2]));
                const int k = in.index_of[lin];
                if (k >= 0 && k < in.voxels) { id = k; break; }
            }
        }
        if (id < 0) { ++r.no_voxel; continue; }
        r.voxel[pix] = id;
        for (int ch = 0; ch < 3; ++ch) {
            double L;
            if (!in.sh) {
                L = in.field[std::size_t(4) * id + ch];
            } else {
                const double x = nr[0] / len, y = nr[1] / len, z = nr[2] / len;
                const double Yk[9] = {Y0, -Y1 * y, Y1 * z, -Y1 * x, Y2 * x * y, -Y2 * y * z, Y20 * (3 * z * z - 1),
                                      -Y2 * x * z, Y22 * (x * x - y * y)};
                double s = 0;
                for (int k = 0; k < 9; ++k) s += lobe[k] * in.field[std::size_t(27) * id + 9 * ch + k] * Yk[k];
                L = std::max(0.0, s) / M_PI;
            }
            r.lighting[std::size_t(ch) * npix + pix] = L;
        }
    }
    return r;
}

}  // namespace ngi::test

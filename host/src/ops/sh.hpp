// Spherical harmonics bands 0-2 (kernels/sh.cl): radiance along a direction, or irradiance around a normal through
// the cosine-lobe convolution. Conventions: docs/CONVENTIONS.md section 14.
#pragma once
#include "runtime/context.hpp"

namespace ngi::detail {

constexpr int kShCoefficients = 9;

class ShEvaluate {
public:
    explicit ShEvaluate(Context& ctx);
    // out[i][c] = sum_k coef[i][c][k] w_k Y_k(dir_i), w_k = 1 (radiance) or A_l (irradiance: pi, 2 pi / 3, pi / 4).
    cl_event enqueue(Context& ctx, cl_mem coef, cl_mem dir, int n, int channels, bool irradiance, cl_mem out,
                     bool want_event = false);

private:
    Kernel kernel_;
};

}  // namespace ngi::detail

// Bilinear resize of planar C x H x W float32 to C x OH x OW (ONNX Resize, mode 'linear', over H and W; PyTorch
// F.interpolate(mode='bilinear')). A batch is folded into C: every plane resizes on its own.
//
// Along each axis, output coordinate o reads the source position s(o) = (a o + b) / d, a rational the host builds
// from the coordinate transformation mode (half_pixel, pytorch_half_pixel, align_corners, asymmetric) and the
// scale (host/src/ops/resize.cpp, axis_map()). It is evaluated exactly in 64-bit integers: float coordinates would
// carry an error of up to half an ulp of s (2e-6 pixels at s = 36, 3e-5 at s = 512), which times a steep
// gradient is far more than the interpolation's own rounding. Taps and weights, PyTorch's rule:
//   s is clamped below at 0; i0 = min(floor(s), n - 1); lambda = min(s - i0, 1) (so 0 past the first pixel and
//   up to 1 past the last); i1 = i0 + 1, or i0 itself at the last pixel and on an axis the resize leaves unchanged
//   (same size, s(o) = o: the host passes step 0).
// y = (1 - ly) * ((1 - lx) * x[y0][x0] + lx * x[y0][x1]) + ly * ((1 - lx) * x[y1][x0] + lx * x[y1][x1]).
// Every one of the four taps is multiplied, a weight of 0 included: 0 * NaN and 0 * Inf are NaN, so a NaN among
// the taps always gives NaN, and an Inf gives NaN where its weight is 0 (as PyTorch's CPU kernel). Only the weight
// lambda = r / d rounds (r, d integers), then the products and sums: a few ulp of max |x|.
//
// Build options, the host's (host/src/ops/resize.hpp, resize_defines()): RESIZE_LOCAL, the work-group size.
#ifndef RESIZE_LOCAL
#error "resize.cl needs RESIZE_LOCAL, the work-group size: build it through ResizeBilinear (resize_defines(), host/src/ops/resize.hpp)"
#endif

// The first tap *i0, the second *i1 and the second's weight lambda of output coordinate o along an axis of n input
// pixels whose source position is (a o + b) / d (d > 0; the host keeps a o + b and (n - 1) d within 2^62).
static inline float resize_tap(const int o, const int n, const long a, const long b, const long d, const int step,
                               int* i0, int* i1) {
    const long num = a * o + b;
    int i = 0;
    float lambda = 0.0f;
    if (num > 0) {  // s <= 0 reads pixel 0 with lambda 0
        const long q = num / d;  // floor(s), num > 0
        if (q >= n - 1) {
            i = n - 1;
            const long r = num - (long)(n - 1) * d;  // s - (n - 1) = r / d, clamped to 1
            lambda = r >= d ? 1.0f : convert_float(r) / convert_float(d);
        } else {
            i = (int)q;
            lambda = convert_float(num - q * d) / convert_float(d);
        }
    }
    *i0 = i;
    *i1 = i < n - 1 ? i + step : i;
    return lambda;
}

// Launch: 1-D over C * OH * OW outputs (rounded up to RESIZE_LOCAL; the host keeps the count below 2^31),
// work-item i = (c * OH + oy) * OW + ox. x_off, y_off: the tensors' offsets in floats. ah, bh, dh and aw, bw, dw:
// the source positions (a o + b) / d of the rows and the columns; step_h, step_w: 1, or 0 on an unchanged axis.
__kernel __attribute__((reqd_work_group_size(RESIZE_LOCAL, 1, 1)))
void resize_bilinear(__global const float* restrict x, const int x_off, const int C, const int H, const int W,
                     __global float* restrict y, const int y_off, const int OH, const int OW, const long ah,
                     const long bh, const long dh, const int step_h, const long aw, const long bw, const long dw,
                     const int step_w) {
    const int i = get_global_id(0);
    if (i >= C * OH * OW) return;
    const int ox = i % OW, t = i / OW;
    const int oy = t % OH, c = t / OH;
    int y0, y1, x0, x1;
    const float ly = resize_tap(oy, H, ah, bh, dh, step_h, &y0, &y1);
    const float lx = resize_tap(ox, W, aw, bw, dw, step_w, &x0, &x1);
    __global const float* plane = x + x_off + (size_t)c * H * W;
    __global const float* r0 = plane + (size_t)y0 * W;
    __global const float* r1 = plane + (size_t)y1 * W;
    const float t0 = (1.0f - lx) * r0[x0] + lx * r0[x1];
    const float t1 = (1.0f - lx) * r1[x0] + lx * r1[x1];
    y[y_off + i] = (1.0f - ly) * t0 + ly * t1;
}

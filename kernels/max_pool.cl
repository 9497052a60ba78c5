// 2D max pooling on planar C x H x W float32 (ONNX MaxPool, PyTorch max_pool2d; ceil_mode 0, dilation 1). A batch
// is folded into C: pooling is per plane.
//
// Output (c, oy, ox) is the max of x[c][iy][ix] over the window iy = oy * SH - PT + ky, ix = ox * SW - PL + kx,
// ky < KH, kx < KW. Padded cells count as -Inf (ONNX): padding never wins, so a window of negative values pools to
// a negative value, not 0. The host keeps every pad below its kernel side, so every window holds at least one real
// cell: the window is clamped to the plane and padding is never read.
// NaN propagates (PyTorch's rule): a window holding a NaN pools to NaN. OpenCL's fmax returns the other operand when
// one is NaN, so it is not used; max_pool_take keeps the running max m unless v is larger or NaN, and once m is NaN
// nothing is larger than it and only another NaN replaces it. Ties (+0 and -0) keep the first value in row-major
// window order, as PyTorch's CPU kernel does. Comparisons only: the result is one of the inputs, exact.
//
// Build options, the host's (host/src/ops/max_pool.hpp, max_pool_defines()): MAX_POOL_LOCAL, the work-group size.
#ifndef MAX_POOL_LOCAL
#error "max_pool.cl needs MAX_POOL_LOCAL, the work-group size: build it through MaxPool2d (max_pool_defines(), host/src/ops/max_pool.hpp)"
#endif

// The running max m after the value v: v when v > m or v is NaN, else m.
static inline float max_pool_take(const float m, const float v) { return (v > m || isnan(v)) ? v : m; }

// Launch: 1-D over C * OH * OW outputs (rounded up to MAX_POOL_LOCAL; the host keeps the count below 2^31),
// work-item i = (c * OH + oy) * OW + ox. x_off, y_off: the tensors' offsets in floats. kh, kw: the kernel; sh, sw:
// the strides; pt, pl: the top and left padding (bottom and right padding only shape OH and OW).
__kernel __attribute__((reqd_work_group_size(MAX_POOL_LOCAL, 1, 1)))
void max_pool2d(__global const float* restrict x, const int x_off, const int C, const int H, const int W,
                __global float* restrict y, const int y_off, const int OH, const int OW, const int kh, const int kw,
                const int sh, const int sw, const int pt, const int pl) {
    const int i = get_global_id(0);
    if (i >= C * OH * OW) return;
    const int ox = i % OW, t = i / OW;
    const int oy = t % OH, c = t / OH;
    // The window's rows [y0, y1) and columns [x0, x1), clamped to the plane (never empty: see above).
    const int top = oy * sh - pt, left = ox * sw - pl;
    const int y0 = max(top, 0), y1 = min(top + kh, H);
    const int x0 = max(left, 0), x1 = min(left + kw, W);
    __global const float* plane = x + x_off + (size_t)c * H * W;
    float m = -INFINITY;
    for (int iy = y0; iy < y1; ++iy) {
        __global const float* row = plane + (size_t)iy * W;
        for (int ix = x0; ix < x1; ++ix) m = max_pool_take(m, row[ix]);
    }
    y[y_off + i] = m;
}

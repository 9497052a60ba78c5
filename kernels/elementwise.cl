// Elementwise ops on a contiguous range of n floats.

// y = act(x), in place.
__kernel void activate_inplace(__global float* restrict x, const int x_off, const int n, const int act,
                               const float alpha) {
    const int i = get_global_id(0);
    if (i < n) x[x_off + i] = ngi_activate(x[x_off + i], act, alpha);
}

// Counter-based hash (a 32-bit integer finalizer): the dropout mask depends only on (seed, site, index),
// never on launch order, so a PyTorch script can reproduce it exactly (docs/MODEL_FORMAT.md).
static inline uint ngi_mix(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Inverted dropout with a seeded mask, in place: keep with probability 1-p and scale by 1/(1-p).
__kernel void dropout_seeded(__global float* restrict x, const int x_off, const int n, const uint seed,
                             const uint site, const float p) {
    const int i = get_global_id(0);
    if (i >= n) return;
    const uint u = ngi_mix(ngi_mix(seed + 0x9E3779B9u * (site + 1u)) ^ (uint)i);
    const float r = (float)(u >> 8) * (1.0f / 16777216.0f);
    x[x_off + i] = r >= p ? x[x_off + i] * (1.0f / (1.0f - p)) : 0.0f;
}

// Replaces NaN by 0 and every value beyond [below, above] (+-Inf, and finite values far outside the model's input
// range such as 3.4e38) by hi or lo, in place, and counts the replaced values (atomic counter). Runs on every graph
// input: one bad texel must not turn the whole lightmap into NaN, and a huge finite value overflows the first
// convolution's sums to Inf and then to NaN (Inf - Inf) just like an Inf would. lo/hi are the ends of the model's
// input range; below/above widen it a little (host side: 1/1024 of its width), so values that are only rounded
// past an end pass unchanged. Comparisons only: exact under any OpenCL compiler (no fast-math here).
// 16 values per work-item in one vector: a clean input is only read (a store and the atomic only
// where a lane was replaced). One value per work-item with an atomic in each branch ran one value at a time on
// PoCL (1.4 ms for a 12 x 128 x 256 generator input, ~3.5 ns per value; docs/PERFORMANCE.md "small shapes").
// The kernel is written for one float16; the host's count of work-items (kSanitizeVec) comes in as SANITIZE_VEC.
#if defined(SANITIZE_VEC) && SANITIZE_VEC != 16
#error "sanitize_inplace is written for SANITIZE_VEC 16 (host/src/ops/elementwise.cpp kSanitizeVec)"
#endif
__kernel void sanitize_inplace(__global float* restrict x, const int x_off, const int n, const float lo,
                               const float hi, const float below, const float above,
                               volatile __global int* restrict bad_count) {
    const int i0 = get_global_id(0) * 16;
    if (i0 >= n) return;
    __global float* p = x + x_off + i0;
    int bad = 0;
    if (i0 + 16 <= n) {
        const float16 v = vload16(0, p);
        const int16 nan = isnan(v), high = v > above, low = v < below;  // NaN compares false: only isnan sees it
        const int16 replaced = nan | high | low;                         // -1 in a replaced lane
        if (any(replaced)) {
            vstore16(select(select(select(v, (float16)(hi), high), (float16)(lo), low), (float16)(0.0f), nan), 0, p);
            // Counted lane by lane through private memory, not by .lo/.hi halves: oclgrind's uninitialized-value
            // plugin loses the shadow of a swizzle's shufflevector and reported the count as uninitialized.
            int lanes[16];
            vstore16(replaced, 0, lanes);
            for (int l = 0; l < 16; ++l) bad -= lanes[l];
        }
    } else {
        for (int i = 0; i < n - i0; ++i) {
            const float v = p[i];
            if (isnan(v)) { p[i] = 0.0f; ++bad; }
            else if (v > above) { p[i] = hi; ++bad; }
            else if (v < below) { p[i] = lo; ++bad; }
        }
    }
    if (bad) atomic_add(bad_count, bad);
}

// Per-channel affine into a planar tensor: y[y_off + c * n + i] = scale[c] * x(i, c) + shift[c], where item i's
// channel c of x is at x_off + i * item_stride + c * channel_stride (points [n][C]: {C, 1}; planar [C][n]: {1, n};
// docs/CONVENTIONS.md section 13), so a point list is transposed on the way. Model families standardize raw inputs
// with it (voxel_sh: x' = 2 (x - lo) / (hi - lo) - 1). Nothing is clamped: NaN stays NaN and overflow gives +-Inf,
// for the guard (sanitize_inplace) that runs on y next to replace and count them.
__kernel void channel_affine_planar(__global const float* restrict x, const int x_off, const int item_stride,
                                    const int channel_stride, const int channels, const int n,
                                    __global const float* restrict scale, __global const float* restrict shift,
                                    __global float* restrict y, const int y_off) {
    const int i = get_global_id(0), c = get_global_id(1);
    if (i >= n || c >= channels) return;
    const float v = x[x_off + (size_t)i * item_stride + (size_t)c * channel_stride];
    y[y_off + (size_t)c * n + i] = scale[c] * v + shift[c];
}

// x += y over n floats (residual connections: h = h + f(h)). x and y do not overlap.
__kernel void add_inplace(__global float* restrict x, const int x_off, __global const float* restrict y,
                          const int y_off, const int n) {
    const int i = get_global_id(0);
    if (i < n) x[x_off + i] += y[y_off + i];
}

// x *= y over n floats (an imported graph's Mul of two computed tensors, e.g. a gate). x and y do not overlap.
__kernel void mul_inplace(__global float* restrict x, const int x_off, __global const float* restrict y,
                          const int y_off, const int n) {
    const int i = get_global_id(0);
    if (i < n) x[x_off + i] *= y[y_off + i];
}

// Joint bilateral upsampling (Kopf et al. 2007, as seed 002 section 5.3 uses it): a low-resolution image (a network's
// indirect light) is brought to full resolution with weights taken from full-resolution geometry, so light does not
// bleed across depth steps and creases the low-resolution grid cannot resolve. Host side: host/src/ops/jbu.cpp;
// the weights, their parameters and why: docs/CONVENTIONS.md section 18. C++ reference: tests/reference_jbu.hpp.
//
// Pixel (x, y) of the W x H output sits at q = ((x + 0.5) w / W - 0.5, (y + 0.5) h / H - 0.5) in the w x h input
// (pixel centres at +0.5, PyTorch's align_corners=False), computed in integers. Its taps are the low-resolution pixels (i, j) with
// floor(q) - radius + 1 <= i, j <= floor(q) + radius inside the image, each weighted by
//   spatial  exp(-((i - qx)^2 + (j - qy)^2) * inv_two_sigma_s2)
//   normal   max(0, n_hi . n_lo)^normal_power
//   plane    exp(-(n_lo . (p_hi - p_lo))^2 * inv_two_sigma_p2)   (distance of p_hi from the tap's tangent plane)
// A pixel or tap without a surface (|n|^2 < 0.25, or a non-finite normal or position) has no weight. The output is
// the weighted mean of the taps; where the weights vanish (their sum < fallback_ratio x the spatial weights' sum:
// a surface the low-resolution image does not see), it is the bilinear resize of the low image (resize_bilinear in
// compose.cl) and the pixel is counted. A full-resolution pixel without a surface gets 0: there is nothing to light.
// Low values: NaN -> 0, +-Inf -> +-FLT_MAX; results saturate at +-FLT_MAX.

// Largest radius the host accepts (a 2r x 2r tap window): kJbuMaxRadius, passed by jbu_defines() (ops/jbu.hpp).
#ifndef JBU_MAX_RADIUS
#error "jbu.cl needs JBU_MAX_RADIUS: build it with jbu_defines() (host/src/ops/jbu.hpp)"
#endif
#define JBU_MAX_TAPS (4 * JBU_MAX_RADIUS * JBU_MAX_RADIUS)

// floor(a / b) for b > 0 (C's division truncates toward zero).
static inline int jbu_floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// f^np for f in [0, 1], np >= 0. An integer np (the default 32) by repeated squaring (np_int = np; -1 for others, which
// take pow()). Why: PoCL evaluates a scalar pow() one value at a time (~160 ns on this machine's CPU, once per tap),
// while the multiplications vectorize across work-items. At most 11 squarings (np <= 1024); relative error ~ 1 ulp
// per multiplication, OpenCL 1.2 allows pow() 16 ulp.
static inline float jbu_power(float f, float np, int np_int) {
    if (np_int < 0) return pow(f, np);
    float r = 1.0f, b = f;
    for (int k = np_int; k > 0; k >>= 1) {
        if (k & 1) r *= b;
        b *= b;
    }
    return r;
}

// The first tap and the weight of the second along one axis of the bilinear fallback, position num / den with
// edges clamped (pixel centres at +0.5, as resize_bilinear in compose.cl).
static inline void jbu_bilinear_tap(int num, int den, int fl, int size, int* first, float* frac) {
    if (num < 0 || fl >= size - 1) {
        *first = num < 0 ? 0 : size - 1;
        *frac = 0.0f;
    } else {
        *first = fl;
        *frac = (float)(num - fl * den) / (float)den;
    }
}

static inline float jbu_clean(float v) { return isnan(v) ? 0.0f : clamp(v, -FLT_MAX, FLT_MAX); }

static inline float3 jbu_load3(__global const float* p, int i, int plane) {
    return (float3)(p[i], p[plane + i], p[2 * plane + i]);
}

static inline int jbu_finite3(float3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

// A normal that marks a surface: finite and not (nearly) zero.
static inline int jbu_is_surface(float3 n) { return jbu_finite3(n) && dot(n, n) >= 0.25f; }

// The bilinear fallback of output pixel o at q = (num_x / den_x, num_y / den_y) (floors fx0, fy0): resize_bilinear's
// weights from the integer position, every channel.
static inline void jbu_fallback_pixel(__global const float* restrict low, const int lw, const int lh, const int nc,
                                      const int num_x, const int den_x, const int fx0, const int num_y, const int den_y,
                                      const int fy0, __global float* restrict out, const int hi_plane, const int o) {
    const int lo_plane = lw * lh;
    int x0, y0;
    float ax, ay;
    jbu_bilinear_tap(num_x, den_x, fx0, lw, &x0, &ax);
    jbu_bilinear_tap(num_y, den_y, fy0, lh, &y0, &ay);
    const int x1 = min(x0 + 1, lw - 1), y1 = min(y0 + 1, lh - 1);
    for (int c = 0; c < nc; ++c) {
        __global const float* s = low + c * lo_plane;
        // Each row clamped first: rows saturated at opposite signs must not make Inf - Inf = NaN.
        const float top = jbu_clean((1.0f - ax) * jbu_clean(s[y0 * lw + x0]) + ax * jbu_clean(s[y0 * lw + x1]));
        const float bottom = jbu_clean((1.0f - ax) * jbu_clean(s[y1 * lw + x0]) + ax * jbu_clean(s[y1 * lw + x1]));
        out[c * hi_plane + o] = clamp((1.0f - ay) * top + ay * bottom, -FLT_MAX, FLT_MAX);
    }
}

// One work-item per output pixel; launch 2-D (W, H). low [channels][h][w], low_normal and low_position [3][h][w],
// normal and position [3][H][W], out [channels][H][W] (all planar). fallbacks[0] counts bilinear fallbacks and
// must be zeroed by the host.
__kernel void jbu_upsample(__global const float* restrict low, __global const float* restrict low_normal,
                           __global const float* restrict low_position, const int w, const int h, const int channels,
                           __global const float* restrict normal, __global const float* restrict position,
                           const int W, const int H, const float inv_two_sigma_s2, const float normal_power,
                           const float inv_two_sigma_p2, const int radius, const float fallback_ratio,
                           __global float* restrict out, volatile __global uint* fallbacks) {
    // Every argument is read before the first branch (Mesa's rusticl assumes kernel-argument loads inside control
    // flow are uniform and warns that results may be wrong).
    const int x = get_global_id(0), y = get_global_id(1);
    const int lw = w, lh = h, nc = channels, ow = W, oh = H, r = clamp(radius, 1, JBU_MAX_RADIUS);
    const float s2 = inv_two_sigma_s2, np = normal_power, p2 = inv_two_sigma_p2, ratio = fallback_ratio;
    const int np_int = np == floor(np) ? (int)np : -1;
    if (x >= ow || y >= oh) return;
    const int hi_plane = ow * oh, lo_plane = lw * lh, o = y * ow + x;

    const float3 n_hi = jbu_load3(normal, o, hi_plane), p_hi = jbu_load3(position, o, hi_plane);
    if (!jbu_is_surface(n_hi) || !jbu_finite3(p_hi)) {
        for (int c = 0; c < nc; ++c) out[c * hi_plane + o] = 0.0f;
        return;
    }

    // The sample position in exact integers: q = num / den with den = 2 W, so the tap window never depends on how a
    // float rounds (at odd ratios q is often an exact integer).
    const int num_x = (2 * x + 1) * lw - ow, den_x = 2 * ow;
    const int num_y = (2 * y + 1) * lh - oh, den_y = 2 * oh;
    const int fx0 = jbu_floor_div(num_x, den_x), fy0 = jbu_floor_div(num_y, den_y);
    const int bx = fx0 - r + 1, by = fy0 - r + 1;
    float weight[JBU_MAX_TAPS];
    float spatial_sum = 0.0f, weight_sum = 0.0f;
    for (int t = 0; t < 4 * r * r; ++t) {
        const int i = bx + t % (2 * r), j = by + t / (2 * r);
        weight[t] = 0.0f;
        if (i < 0 || j < 0 || i >= lw || j >= lh) continue;
        const float dx = (float)(i * den_x - num_x) / (float)den_x, dy = (float)(j * den_y - num_y) / (float)den_y;
        const float spatial = exp(-(dx * dx + dy * dy) * s2);
        spatial_sum += spatial;
        const int l = j * lw + i;
        const float3 n_lo = jbu_load3(low_normal, l, lo_plane), p_lo = jbu_load3(low_position, l, lo_plane);
        if (!jbu_is_surface(n_lo) || !jbu_finite3(p_lo)) continue;
        const float facing = fmax(dot(n_hi, n_lo), 0.0f);
        const float plane = dot(n_lo, p_hi - p_lo);
        weight[t] = spatial * jbu_power(facing, np, np_int) * exp(-plane * plane * p2);
        weight_sum += weight[t];
    }

    if (weight_sum > ratio * spatial_sum && weight_sum > 0.0f) {
        const float inv = 1.0f / weight_sum;
        for (int c = 0; c < nc; ++c) {
            __global const float* src = low + c * lo_plane;
            float acc = 0.0f;
            for (int t = 0; t < 4 * r * r; ++t)
                if (weight[t] > 0.0f)
                    acc += (weight[t] * inv) * jbu_clean(src[(by + t / (2 * r)) * lw + bx + t % (2 * r)]);
            out[c * hi_plane + o] = clamp(acc, -FLT_MAX, FLT_MAX);
        }
        return;
    }

    atomic_inc(fallbacks);
    jbu_fallback_pixel(low, lw, lh, nc, num_x, den_x, fx0, num_y, den_y, fy0, out, hi_plane, o);
}

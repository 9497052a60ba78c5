// The front view's GI at the application's display resolution, stable from frame to frame (issue 47). The pipeline's
// N x N lightmap is split into direct light (which the engine has at display resolution) and the indirect rest; the
// rest is upsampled guided by the display's geometry (joint bilateral, kernels/jbu.cl), accumulated over frames with
// reprojection, and composed with the display-resolution direct light, albedo and emission. Host side:
// host/src/pipeline/display.cpp (ngi::DisplayView, ngi/display.hpp); definitions and defaults: docs/CONVENTIONS.md
// section 20; C++ reference: tests/reference_display.hpp.
//
// Cameras: the front camera of the cluster (ngi/camera.hpp), a 90-degree square view; a camera is its centre and its
// unit look, right, up (right = look x up), passed as four float4 arguments (w unused). Pixel (x, y) of an S x S view
// looks along look + u right + v up, u = 2 (x + 0.5) / S - 1, v = 1 - 2 (y + 0.5) / S; depth is planar (along look).
// Images are planar float32 [channel][row][col]; frame planes use the layout of ngi/pipeline.hpp (face 0 only).

#if !defined(F_ALBEDO) || !defined(F_NORMAL) || !defined(F_DEPTH) || !defined(F_DIRECT) || !defined(F_EMISSION) || \
    !defined(F_ENV) || !defined(DISPLAY_MAX_DEPTH)
#error "display.cl needs the frame planes and DISPLAY_MAX_DEPTH: build it with display_defines() (host/src/pipeline/display.cpp)"
#endif

// Light terms (direct, emission, env): NaN, negative -> 0, +Inf -> FLT_MAX (compose.cl's rule).
static inline float display_light(float v) { return isnan(v) ? 0.0f : clamp(v, 0.0f, FLT_MAX); }
// Signed values (indirect light, which a network may make negative): NaN -> 0, +-Inf -> +-FLT_MAX.
static inline float display_signed(float v) { return isnan(v) ? 0.0f : clamp(v, -FLT_MAX, FLT_MAX); }

static inline float3 display_load3(__global const float* p, int i, int plane) {
    return (float3)(p[i], p[plane + i], p[2 * plane + i]);
}

static inline void display_store3(__global float* p, int i, int plane, float3 v) {
    p[i] = v.x;
    p[plane + i] = v.y;
    p[2 * plane + i] = v.z;
}

static inline int display_finite3(float3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

// The JBU guides of face 0 of frame planes (size x size): the normal and the world position of every pixel that sees a
// surface (finite normal with |n|^2 >= 0.25, finite depth in (0, DISPLAY_MAX_DEPTH]); zeros elsewhere (jbu.cl: no
// surface). One work-item per pixel, 2-D (size, size).
__kernel void display_geometry(__global const float* restrict planes, const int size, const float4 centre,
                               const float4 look, const float4 right, const float4 up, __global float* restrict normal,
                               __global float* restrict position) {
    const int x = get_global_id(0), y = get_global_id(1), s = size;
    const float4 c = centre, l = look, r = right, u = up;
    if (x >= s || y >= s) return;
    const int plane = s * s, i = y * s + x;
    const float3 n = display_load3(planes + F_NORMAL * plane, i, plane);
    const float d = planes[F_DEPTH * plane + i];
    if (!(display_finite3(n) && dot(n, n) >= 0.25f && isfinite(d) && d > 0.0f && d <= DISPLAY_MAX_DEPTH)) {
        display_store3(normal, i, plane, (float3)(0.0f));
        display_store3(position, i, plane, (float3)(0.0f));
        return;
    }
    const float pu = 2.0f * ((float)x + 0.5f) / (float)s - 1.0f, pv = 1.0f - 2.0f * ((float)y + 0.5f) / (float)s;
    display_store3(normal, i, plane, n);
    display_store3(position, i, plane, c.xyz + d * (l.xyz + pu * r.xyz + pv * u.xyz));
}

// The low-resolution indirect light: the pipeline's lightmap minus face 0's direct light, per value (count = 3 n^2;
// the direct planes are contiguous RGB, the lightmap's own layout). Signed: a network's lightmap may lie below the
// direct light, and what it removes is removed at display resolution too.
__kernel void display_low_indirect(__global const float* restrict lightmap, __global const float* restrict planes,
                                   const int count, __global float* restrict indirect) {
    const int i = get_global_id(0), nc = count;
    if (i >= nc) return;
    const int plane = nc / 3;
    indirect[i] = display_signed(display_signed(lightmap[i]) - display_light(planes[F_DIRECT * plane + i]));
}

// Temporal accumulation of the upsampled indirect light (2-D, one work-item per display pixel):
//   history = the previous frame's accumulated indirect light, sampled bilinearly where this pixel's world point lands
//             in the previous camera; a tap counts when it is inside that view and its stored planar depth agrees with
//             the point's (|d_prev - z| <= depth_rel z + depth_abs); no valid tap (disocclusion, or the view's edge):
//             no history (counters[0] += 1);
//   clip:     the history is clamped per channel to the range of the current low-resolution indirect light over the
//             3 x 3 texels around the pixel (surface texels only), widened by clip_margin x its mean level (|r| + |g|
//             + |b|) / 3: a change of lighting (or of what the network sees) that leaves the history outside what
//             this frame's light allows resets it there instead of fading in over many frames (counters[1] += 1);
//             clip_margin < 0: no clip;
//   out     = history + blend (current - history), or current without history (also where has_history is 0, and
//             at pixels without a surface).
// normal: the display's guide (zero = no surface); low / low_normal: the n x n indirect light and its guide.
__kernel void display_temporal(__global const float* restrict current, __global const float* restrict history,
                               __global const float* restrict prev_depth, __global const float* restrict normal,
                               __global const float* restrict position, __global const float* restrict low,
                               __global const float* restrict low_normal, const int n, const int size,
                               const float4 prev_centre, const float4 prev_look, const float4 prev_right,
                               const float4 prev_up, const int has_history, const float blend, const float depth_rel,
                               const float depth_abs, const float clip_margin, __global float* restrict out,
                               volatile __global uint* counters) {
    // Every argument is read before the first branch (rusticl assumes argument loads in control flow are uniform).
    const int x = get_global_id(0), y = get_global_id(1), s = size, ln = n, hist = has_history;
    const float4 pc = prev_centre, pl = prev_look, pr = prev_right, pu = prev_up;
    const float a = blend, dr = depth_rel, da = depth_abs, margin = clip_margin;
    if (x >= s || y >= s) return;
    const int plane = s * s, i = y * s + x;
    const float3 cur = (float3)(display_signed(current[i]), display_signed(current[plane + i]),
                                display_signed(current[2 * plane + i]));
    const float3 nrm = display_load3(normal, i, plane);
    if (!hist || dot(nrm, nrm) < 0.25f) {
        display_store3(out, i, plane, cur);
        return;
    }

    // Reprojection into the previous camera.
    const float3 q = display_load3(position, i, plane) - pc.xyz;
    const float z = dot(q, pl.xyz);
    const float u = dot(q, pr.xyz) / z, v = dot(q, pu.xyz) / z;
    float3 acc = (float3)(0.0f);
    float wsum = 0.0f;
    // |u|, |v| <= 2 keeps the pixel coordinates far from int overflow; such points are outside the view anyway.
    if (z > 1e-6f && fabs(u) <= 2.0f && fabs(v) <= 2.0f) {
        const float fx = (u + 1.0f) * 0.5f * (float)s - 0.5f, fy = (1.0f - v) * 0.5f * (float)s - 0.5f;
        const int x0 = (int)floor(fx), y0 = (int)floor(fy);
        const float ax = fx - (float)x0, ay = fy - (float)y0;
        const float tol = dr * z + da;
        for (int t = 0; t < 4; ++t) {
            const int tx = x0 + (t & 1), ty = y0 + (t >> 1);
            if (tx < 0 || ty < 0 || tx >= s || ty >= s) continue;
            const int j = ty * s + tx;
            const float dp = prev_depth[j];
            if (!(fabs(dp - z) <= tol)) continue;  // also false for a NaN depth
            const float w = ((t & 1) ? ax : 1.0f - ax) * ((t >> 1) ? ay : 1.0f - ay);
            if (w <= 0.0f) continue;
            acc += w * (float3)(display_signed(history[j]), display_signed(history[plane + j]),
                                display_signed(history[2 * plane + j]));
            wsum += w;
        }
    }
    if (!(wsum > 1e-4f)) {
        atomic_inc(&counters[0]);
        display_store3(out, i, plane, cur);
        return;
    }
    float3 h = acc / wsum;

    if (margin >= 0.0f) {
        // The low-resolution texel nearest the pixel's sample position (jbu.cl's mapping, pixel centres at +0.5).
        const int cx = clamp((int)floor(((float)x + 0.5f) * (float)ln / (float)s), 0, ln - 1);
        const int cy = clamp((int)floor(((float)y + 0.5f) * (float)ln / (float)s), 0, ln - 1);
        const int lplane = ln * ln;
        float3 lo = (float3)(FLT_MAX), hi = (float3)(-FLT_MAX), sum = (float3)(0.0f);
        int taps = 0;
        for (int t = 0; t < 9; ++t) {
            const int tx = cx + t % 3 - 1, ty = cy + t / 3 - 1;
            if (tx < 0 || ty < 0 || tx >= ln || ty >= ln) continue;
            const int j = ty * ln + tx;
            const float3 ln3 = display_load3(low_normal, j, lplane);
            if (dot(ln3, ln3) < 0.25f) continue;
            const float3 l3 = (float3)(display_signed(low[j]), display_signed(low[lplane + j]),
                                       display_signed(low[2 * lplane + j]));
            lo = fmin(lo, l3);
            hi = fmax(hi, l3);
            sum += l3 / 9.0f;  // divided first: a sum of values near FLT_MAX must not overflow
            ++taps;
        }
        if (taps > 0) {
            const float3 mean = sum * (9.0f / (float)taps);
            const float m = margin * (fabs(mean.x) + fabs(mean.y) + fabs(mean.z)) / 3.0f;
            const float3 c = clamp(h, lo - m, hi + m);
            if (any(c != h)) atomic_inc(&counters[1]);
            h = c;
        }
    }
    const float3 r = h + a * (cur - h);
    display_store3(out, i, plane, clamp(r, (float3)(-FLT_MAX), (float3)(FLT_MAX)));
}

// The display-resolution outputs, per value (count = 3 size^2, one work-item each): lightmap = clean(direct) +
// indirect, at least 0; final = clamp(albedo, 0, 1) lightmap + clean(emission) + clean(env) (compose.cl's
// compose_final), each saturating at FLT_MAX. Face 0 of the display planes; has_lightmap 0: only `final` is written
// (lightmap may then alias it).
__kernel void display_compose(__global const float* restrict planes, __global const float* restrict indirect,
                              const int count, const int has_emission, const int has_env, const int has_lightmap,
                              __global float* lightmap, __global float* final_image) {
    const int i = get_global_id(0), nc = count, em = has_emission, ev = has_env, hl = has_lightmap;
    if (i >= nc) return;
    const int plane = nc / 3;
    const float light = clamp(display_light(planes[F_DIRECT * plane + i]) + display_signed(indirect[i]), 0.0f, FLT_MAX);
    if (hl) lightmap[i] = light;
    const float alb = planes[F_ALBEDO * plane + i];
    float v = (isnan(alb) ? 0.0f : clamp(alb, 0.0f, 1.0f)) * light;
    if (em) v = fmin(v + display_light(planes[F_EMISSION * plane + i]), FLT_MAX);
    if (ev) v = fmin(v + display_light(planes[F_ENV * plane + i]), FLT_MAX);
    final_image[i] = v;
}

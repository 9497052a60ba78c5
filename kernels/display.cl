// The front view's GI at the application's display resolution, stable from frame to frame (issue 47). The pipeline's
// N x N lightmap is split into direct light (which the engine has at display resolution) and the indirect rest; the
// rest is upsampled guided by the display's geometry (joint bilateral, kernels/jbu.cl), accumulated over frames with
// reprojection, and composed with the display-resolution direct light, albedo and emission. Host side:
// host/src/pipeline/display.cpp (ngi::DisplayView, ngi/display.hpp); definitions and defaults: docs/CONVENTIONS.md
// section 20; C++ reference: tests/reference_display.hpp.
//
// Cameras: the front camera of the cluster (ngi/camera.hpp), a 90-degree square view; a camera is its centre and its
// unit look, right, up (right = look x up), passed as twelve float arguments (DISPLAY_CAMERA_ARGS). Pixel (x, y) of an S x S view
// looks along look + u right + v up, u = 2 (x + 0.5) / S - 1, v = 1 - 2 (y + 0.5) / S; depth is planar (along look).
// Images are planar float32 [channel][row][col]; frame planes use the layout of ngi/pipeline.hpp (face 0 only).

#if !defined(F_ALBEDO) || !defined(F_NORMAL) || !defined(F_DEPTH) || !defined(F_DIRECT) || !defined(F_EMISSION) || \
    !defined(F_ENV) || !defined(DISPLAY_MAX_DEPTH) || !defined(DISPLAY_VEC)
#error "display.cl needs the frame planes, DISPLAY_MAX_DEPTH and DISPLAY_VEC: build it with display_defines() (host/src/pipeline/display.cpp)"
#endif

// A camera as twelve float kernel arguments (centre, look, right, up), gathered into float4s (w unused) by
// DISPLAY_CAMERA. Not float4 arguments: oclgrind ran kernels with vector arguments wrongly when it loaded the program
// from a cached binary (invalid reads, wrong results; a fresh build ran right), as ssgi.cl's camera arguments avoid.
#define DISPLAY_CAMERA_ARGS(p) const float p##cx, const float p##cy, const float p##cz, const float p##lx, \
    const float p##ly, const float p##lz, const float p##rx, const float p##ry, const float p##rz, const float p##ux, \
    const float p##uy, const float p##uz
#define DISPLAY_CAMERA(p, c, l, r, u) \
    const float4 c = (float4)(p##cx, p##cy, p##cz, 0.0f), l = (float4)(p##lx, p##ly, p##lz, 0.0f), \
                 r = (float4)(p##rx, p##ry, p##rz, 0.0f), u = (float4)(p##ux, p##uy, p##uz, 0.0f)

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
// surface). 2-D, DISPLAY_VEC = 8 pixels of a row per work-item in float8 lanes (an elementwise kernel with a branch per
// pixel ran one pixel at a time on PoCL); a row's last, partial group takes the same formulas lane by lane.
static inline void display_guide(__global const float* restrict planes, const int s, const int x, const int y,
                                 const float4 c, const float4 l, const float4 r, const float4 u,
                                 __global float* restrict normal, __global float* restrict position) {
    const int plane = s * s, i = y * s + x;
    const float3 n = display_load3(planes + F_NORMAL * plane, i, plane);
    const float d = planes[F_DEPTH * plane + i];
    const int ok = display_finite3(n) && dot(n, n) >= 0.25f && isfinite(d) && d > 0.0f && d <= DISPLAY_MAX_DEPTH;
    const float pu = 2.0f * ((float)x + 0.5f) / (float)s - 1.0f, pv = 1.0f - 2.0f * ((float)y + 0.5f) / (float)s;
    display_store3(normal, i, plane, ok ? n : (float3)(0.0f));
    display_store3(position, i, plane, ok ? c.xyz + d * (l.xyz + pu * r.xyz + pv * u.xyz) : (float3)(0.0f));
}

__kernel void display_geometry(__global const float* restrict planes, const int size, DISPLAY_CAMERA_ARGS(cam_),
                               __global float* restrict normal, __global float* restrict position) {
    const int gx = get_global_id(0), y = get_global_id(1), s = size;
    DISPLAY_CAMERA(cam_, c, l, r, u);
    const int x0 = gx * DISPLAY_VEC;
    if (x0 >= s || y >= s) return;
    if (x0 + DISPLAY_VEC > s) {
        for (int x = x0; x < s; ++x) display_guide(planes, s, x, y, c, l, r, u, normal, position);
        return;
    }
    const int plane = s * s, i = y * s + x0;
    const float8 nx = vload8(0, planes + F_NORMAL * plane + i), ny = vload8(0, planes + (F_NORMAL + 1) * plane + i),
                 nz = vload8(0, planes + (F_NORMAL + 2) * plane + i), d = vload8(0, planes + F_DEPTH * plane + i);
    const int8 ok = isfinite(nx) & isfinite(ny) & isfinite(nz) & (nx * nx + ny * ny + nz * nz >= 0.25f) & isfinite(d) &
                    (d > 0.0f) & (d <= DISPLAY_MAX_DEPTH);
    const float8 pu = 2.0f * (convert_float8(x0 + (int8)(0, 1, 2, 3, 4, 5, 6, 7)) + 0.5f) / (float)s - 1.0f;
    const float pv = 1.0f - 2.0f * ((float)y + 0.5f) / (float)s;
    const float8 zero = (float8)(0.0f);
    vstore8(select(zero, nx, ok), 0, normal + i);
    vstore8(select(zero, ny, ok), 0, normal + plane + i);
    vstore8(select(zero, nz, ok), 0, normal + 2 * plane + i);
    vstore8(select(zero, c.x + d * (l.x + pu * r.x + pv * u.x), ok), 0, position + i);
    vstore8(select(zero, c.y + d * (l.y + pu * r.y + pv * u.y), ok), 0, position + plane + i);
    vstore8(select(zero, c.z + d * (l.z + pu * r.z + pv * u.z), ok), 0, position + 2 * plane + i);
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

// The history clamp's range per low-resolution texel (n x n, one work-item each): per channel [min - m, max + m] of
// the indirect light over the 3 x 3 texels around it that are surfaces, m = clip_margin x (|mean r| + |mean g| +
// |mean b|) / 3 of those texels; no surface among them: no clamp (-FLT_MAX, FLT_MAX). box: 6 planes, lo r g b, hi r
// g b. Computed once per texel rather than per display pixel (64 display pixels share a texel at 8x).
__kernel void display_clip_box(__global const float* restrict low, __global const float* restrict low_normal,
                               const int n, const float clip_margin, __global float* restrict box) {
    const int x = get_global_id(0), y = get_global_id(1), ln = n;
    const float margin = clip_margin;
    if (x >= ln || y >= ln) return;
    const int lplane = ln * ln;
    float3 lo = (float3)(FLT_MAX), hi = (float3)(-FLT_MAX), sum = (float3)(0.0f);
    int taps = 0;
    for (int t = 0; t < 9; ++t) {
        const int tx = x + t % 3 - 1, ty = y + t / 3 - 1;
        if (tx < 0 || ty < 0 || tx >= ln || ty >= ln) continue;
        const int j = ty * ln + tx;
        const float3 m3 = display_load3(low_normal, j, lplane);
        if (dot(m3, m3) < 0.25f) continue;
        const float3 l3 = (float3)(display_signed(low[j]), display_signed(low[lplane + j]),
                                   display_signed(low[2 * lplane + j]));
        lo = fmin(lo, l3);
        hi = fmax(hi, l3);
        sum += l3 / 9.0f;  // divided first: a sum of values near FLT_MAX must not overflow
        ++taps;
    }
    const int i = y * ln + x;
    if (taps == 0) {
        display_store3(box, i, lplane, (float3)(-FLT_MAX));
        display_store3(box + 3 * lplane, i, lplane, (float3)(FLT_MAX));
        return;
    }
    const float3 mean = sum * (9.0f / (float)taps);
    const float m = margin * (fabs(mean.x) + fabs(mean.y) + fabs(mean.z)) / 3.0f;
    display_store3(box, i, lplane, lo - m);
    display_store3(box + 3 * lplane, i, lplane, hi + m);
}

// Temporal accumulation of the upsampled indirect light (2-D: DISPLAY_VEC = 8 pixels of a row per work-item, in
// float8 lanes -- PoCL runs work-items in SIMD lanes only for kernels without inner loops, and the tap loops here are
// inner loops; the inputs are gathered lane by lane without branches):
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
// normal: the display's guide (zero = no surface); box: display_clip_box's ranges of the n x n texels.
#if DISPLAY_VEC != 8
#error "display_temporal is written for DISPLAY_VEC 8 (host/src/pipeline/display.cpp kDisplayVec)"
#endif

// p[idx] in the lanes where ok (a lane mask), 0 elsewhere; the other lanes read p[0] and discard it (no branches).
// Every index is also clamped to [0, lim): a lane the masks let through can never read outside the buffer (the
// open oclgrind finding of docs/RELIABILITY.md is not explained by the index math, which bounds every tap; this
// makes that bound hold by construction).
// display_row8 reads eight neighbouring values of a row (one vector load when all are inside the row).
static inline float8 display_gather8(__global const float* p, const int8 idx, const int8 ok, const int lim) {
    const int8 k = clamp(select((int8)(0), idx, ok), (int8)(0), (int8)(lim - 1));
    return select((float8)(0.0f), (float8)(p[k.s0], p[k.s1], p[k.s2], p[k.s3], p[k.s4], p[k.s5], p[k.s6], p[k.s7]),
                  ok);
}

static inline float8 display_row8(__global const float* p, const int base, const int count, const int8 live) {
    if (count == 8) return vload8(0, p + base);
    return display_gather8(p, base + (int8)(0, 1, 2, 3, 4, 5, 6, 7), live, base + count);
}

// p[lane] or p[lane + 1] per lane (pick: a lane mask): two vector loads of nine neighbouring values.
static inline float8 display_pick8(__global const float* p, const int8 pick) {
    return select(vload8(0, p), vload8(0, p + 1), pick);
}

static inline float8 display_signed8(float8 v) { return select(clamp(v, -FLT_MAX, FLT_MAX), (float8)(0.0f), isnan(v)); }

static inline void display_store8(__global float* p, const int base, const int count, float8 v) {
    if (count == 8) {
        vstore8(v, 0, p + base);
        return;
    }
    const float a[8] = {v.s0, v.s1, v.s2, v.s3, v.s4, v.s5, v.s6, v.s7};
    for (int k = 0; k < count; ++k) p[base + k] = a[k];
}

static inline uint display_lanes(int8 m) { return (uint)(-(m.s0 + m.s1 + m.s2 + m.s3 + m.s4 + m.s5 + m.s6 + m.s7)); }

__kernel void display_temporal(__global const float* restrict current, __global const float* restrict history,
                               __global const float* restrict prev_depth, __global const float* restrict normal,
                               __global const float* restrict position, __global const float* restrict box,
                               const int n, const int size, DISPLAY_CAMERA_ARGS(prev_), const int has_history,
                               const float blend, const float depth_rel,
                               const float depth_abs, const float clip_margin, __global float* restrict out,
                               volatile __global uint* counters) {
    // Every argument is read before the first branch (rusticl assumes argument loads in control flow are uniform).
    const int gx = get_global_id(0), y = get_global_id(1), s = size, ln = n, hist = has_history;
    DISPLAY_CAMERA(prev_, pc, pl, pr, pu);
    const float a = blend, dr = depth_rel, da = depth_abs, margin = clip_margin;
    const int x0 = gx * DISPLAY_VEC;
    if (x0 >= s || y >= s) return;
    const int plane = s * s, base = y * s + x0, count = min(DISPLAY_VEC, s - x0);
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7), x = x0 + lane, live = x < s;
    const float8 c0 = display_signed8(display_row8(current, base, count, live));
    const float8 c1 = display_signed8(display_row8(current + plane, base, count, live));
    const float8 c2 = display_signed8(display_row8(current + 2 * plane, base, count, live));
    const float8 nx = display_row8(normal, base, count, live), ny = display_row8(normal + plane, base, count, live),
                 nz = display_row8(normal + 2 * plane, base, count, live);
    const int8 surface = live & (nx * nx + ny * ny + nz * nz >= 0.25f);
    if (!hist || !any(surface)) {
        display_store8(out, base, count, c0);
        display_store8(out, plane + base, count, c1);
        display_store8(out, 2 * plane + base, count, c2);
        return;
    }

    // Reprojection into the previous camera.
    const float8 qx = display_row8(position, base, count, live) - pc.x,
                 qy = display_row8(position + plane, base, count, live) - pc.y,
                 qz = display_row8(position + 2 * plane, base, count, live) - pc.z;
    const float8 z = qx * pl.x + qy * pl.y + qz * pl.z;
    const float8 u = (qx * pr.x + qy * pr.y + qz * pr.z) / z, v = (qx * pu.x + qy * pu.y + qz * pu.z) / z;
    // |u|, |v| <= 2 keeps the pixel coordinates far from int overflow; such points are outside the view anyway.
    const int8 seen = surface & (z > 1e-6f) & (fabs(u) <= 2.0f) & (fabs(v) <= 2.0f);
    const float8 fx = select((float8)(0.0f), (u + 1.0f) * 0.5f * (float)s - 0.5f, seen);
    const float8 fy = select((float8)(0.0f), (1.0f - v) * 0.5f * (float)s - 0.5f, seen);
    const float8 flx = floor(fx), fly = floor(fy);
    const int8 tx0 = convert_int8(flx), ty0 = convert_int8(fly);
    const float8 ax = fx - flx, ay = fy - fly, tol = dr * z + da;
    // Rows in place: where all eight pixels are seen, land on one row of the previous view and on columns x + k or
    // x + k + 1 (a camera that moved a little: the common case), each tap's values are two vector loads of that row and
    // a select per lane instead of eight gathered loads. The same values as the gathers, the same arithmetic.
    const int8 dx = tx0 - x;
    const int k = min(min(min(dx.s0, dx.s1), min(dx.s2, dx.s3)), min(min(dx.s4, dx.s5), min(dx.s6, dx.s7)));
    const int8 one_right = dx - k == 1;
    const int in_place = all(seen) && all(ty0 == ty0.s0) && all(dx - k <= 1) && x0 + k >= 0 && x0 + k + 10 <= s &&
                         ty0.s0 >= 0 && ty0.s0 + 1 < s;
    float8 h0 = (float8)(0.0f), h1 = h0, h2 = h0, wsum = h0;
    for (int t = 0; t < 4; ++t) {
        const int8 tx = tx0 + (t & 1), ty = ty0 + (t >> 1);
        const int8 inside = seen & (tx >= 0) & (ty >= 0) & (tx < s) & (ty < s);
        const float8 w = ((t & 1) ? ax : 1.0f - ax) * ((t >> 1) ? ay : 1.0f - ay);
        if (in_place) {
            const int at = (ty0.s0 + (t >> 1)) * s + x0 + k + (t & 1);
            const float8 dp = display_pick8(prev_depth + at, one_right);
            const int8 ok = inside & (fabs(dp - z) <= tol) & (w > 0.0f);  // also false for a NaN depth
            const float8 wk = select((float8)(0.0f), w, ok);
            h0 += wk * display_signed8(display_pick8(history + at, one_right));
            h1 += wk * display_signed8(display_pick8(history + plane + at, one_right));
            h2 += wk * display_signed8(display_pick8(history + 2 * plane + at, one_right));
            wsum += wk;
            continue;
        }
        const int8 j = ty * s + tx;
        const float8 dp = display_gather8(prev_depth, j, inside, plane);
        const int8 ok = inside & (fabs(dp - z) <= tol) & (w > 0.0f);  // also false for a NaN depth
        const float8 wk = select((float8)(0.0f), w, ok);
        h0 += wk * display_signed8(display_gather8(history, j, ok, plane));
        h1 += wk * display_signed8(display_gather8(history + plane, j, ok, plane));
        h2 += wk * display_signed8(display_gather8(history + 2 * plane, j, ok, plane));
        wsum += wk;
    }
    const int8 used = surface & (wsum > 1e-4f);
    const uint lost = display_lanes(surface & ~used);
    if (lost) atomic_add(&counters[0], lost);
    const float8 inv = select((float8)(1.0f), 1.0f / wsum, used);
    h0 *= inv;
    h1 *= inv;
    h2 *= inv;

    if (margin >= 0.0f) {
        // The clamp range of the low-resolution texel nearest each pixel's sample position (display_clip_box; jbu.cl's
        // mapping, pixel centres at +0.5).
        const int cy = clamp((int)floor(((float)y + 0.5f) * (float)ln / (float)s), 0, ln - 1);
        const int8 cx = clamp(convert_int8(floor((convert_float8(x) + 0.5f) * (float)ln / (float)s)), 0, ln - 1);
        const int lplane = ln * ln;
        const int8 j = cy * ln + cx;
        const float8 lo0 = display_gather8(box, j, used, lplane),
                     lo1 = display_gather8(box + lplane, j, used, lplane),
                     lo2 = display_gather8(box + 2 * lplane, j, used, lplane),
                     hi0 = display_gather8(box + 3 * lplane, j, used, lplane),
                     hi1 = display_gather8(box + 4 * lplane, j, used, lplane),
                     hi2 = display_gather8(box + 5 * lplane, j, used, lplane);
        const float8 k0 = clamp(h0, lo0, hi0), k1 = clamp(h1, lo1, hi1), k2 = clamp(h2, lo2, hi2);
        const int8 moved = used & ((k0 != h0) | (k1 != h1) | (k2 != h2));
        const uint clipped = display_lanes(moved);
        if (clipped) atomic_add(&counters[1], clipped);
        h0 = select(h0, k0, used);
        h1 = select(h1, k1, used);
        h2 = select(h2, k2, used);
    }
    const float8 lim = (float8)(FLT_MAX);
    display_store8(out, base, count, select(c0, clamp(h0 + a * (c0 - h0), -lim, lim), used));
    display_store8(out, plane + base, count, select(c1, clamp(h1 + a * (c1 - h1), -lim, lim), used));
    display_store8(out, 2 * plane + base, count, select(c2, clamp(h2 + a * (c2 - h2), -lim, lim), used));
}

// The display-resolution outputs, per value (count = 3 size^2; DISPLAY_VEC = 8 values per work-item in float8 lanes,
// a last partial group through the same code on lanes loaded one by one): lightmap = clean(direct) + indirect, at
// least 0; final = clamp(albedo, 0, 1) lightmap + clean(emission) + clean(env) (compose.cl's compose_final), each
// saturating at FLT_MAX; display = tonemap8(final) (kernels/tonemap.cl), so the final image need not be stored and read
// back for the display. Face 0 of the display planes. Each output is written only when its has_ flag is set (an
// unused output may be any buffer, also another output).
static inline float8 display_light8(float8 v) { return select(clamp(v, 0.0f, FLT_MAX), (float8)(0.0f), isnan(v)); }

__kernel void display_compose(__global const float* restrict planes, __global const float* restrict indirect,
                              const int count, const int has_emission, const int has_env, const int has_lightmap,
                              const int has_final, const int has_display, const float scale, const int curve,
                              const int srgb, __global float* lightmap, __global float* final_image,
                              __global float* display) {
    const int i0 = get_global_id(0) * DISPLAY_VEC, nc = count, em = has_emission, ev = has_env;
    const int hl = has_lightmap, hf = has_final, hd = has_display, cv = curve, sr = srgb;
    const float sc = scale;
    if (i0 >= nc) return;
    const int plane = nc / 3, n = min(DISPLAY_VEC, nc - i0);
    const int8 live = i0 + (int8)(0, 1, 2, 3, 4, 5, 6, 7) < nc;
    const float8 direct = display_light8(display_row8(planes + F_DIRECT * plane, i0, n, live));
    const float8 light = clamp(direct + display_signed8(display_row8(indirect, i0, n, live)), 0.0f, FLT_MAX);
    if (hl) display_store8(lightmap, i0, n, light);
    const float8 alb = display_row8(planes + F_ALBEDO * plane, i0, n, live);
    float8 v = select(clamp(alb, 0.0f, 1.0f), (float8)(0.0f), isnan(alb)) * light;
    if (em) v = fmin(v + display_light8(display_row8(planes + F_EMISSION * plane, i0, n, live)), FLT_MAX);
    if (ev) v = fmin(v + display_light8(display_row8(planes + F_ENV * plane, i0, n, live)), FLT_MAX);
    if (hf) display_store8(final_image, i0, n, v);
    if (hd) display_store8(display, i0, n, tonemap8(v, sc, cv, sr));
}

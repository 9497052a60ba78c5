// jbu_upsample8: joint bilateral upsampling (kernels/jbu.cl: the weights, the helpers, the one-pixel kernel) with
// JBU_VEC = 8 output pixels of one row per work-item, for images of 1 to 4 channels on PoCL's CPU devices. Its own
// program ("jbu_vec": jbu.cl + this file, host/src/runtime/programs.cpp), so that devices that run the one-pixel
// kernel never build it (Mesa's llvmpipe took ~65 s to). Host: JointBilateralUpsample (host/src/ops/jbu.cpp).

// Why: PoCL runs a work-group's work-items in SIMD lanes only when the kernel body has no inner loop, and the tap
// loop is one; jbu_upsample then runs one pixel at a time with scalar exp() calls (~110 ms for 512 x 512 on this
// machine's two cores). Here the lanes are explicit: eight neighbouring pixels of a row share the tap rows (j) and
// differ in their tap columns, so every weight is computed in a float8 and the inputs are gathered lane by lane. The
// arithmetic is jbu_upsample's, lane for lane (the result may differ in the last bits: the weighted sum is divided
// once at the end). Host: JointBilateralUpsample picks it for channels <= 4 (ops/jbu.cpp).
#ifndef JBU_VEC
#error "jbu_vec.cl needs JBU_VEC: build it with jbu_defines() (host/src/ops/jbu.hpp)"
#endif
#if JBU_VEC != 8
#error "jbu_upsample8 is written for JBU_VEC 8 (host/src/ops/jbu.hpp kJbuVec)"
#endif

// p[idx] in the lanes where ok (a lane mask: -1 or 0), 0 elsewhere. The other lanes read p[0] (count >= 1 values
// are readable) and discard it: loads without branches, which the compiler can issue as one gather.
static inline float8 jbu_gather8(__global const float* p, const int8 idx, const int8 ok) {
    const int8 k = select((int8)(0), idx, ok);
    const float8 v = (float8)(p[k.s0], p[k.s1], p[k.s2], p[k.s3], p[k.s4], p[k.s5], p[k.s6], p[k.s7]);
    return select((float8)(0.0f), v, ok);
}

static inline int8 jbu_finite8(float8 v) { return isfinite(v); }

static inline float8 jbu_clean8(float8 v) { return select(clamp(v, -FLT_MAX, FLT_MAX), (float8)(0.0f), isnan(v)); }

static inline float8 jbu_power8(float8 f, float np, int np_int) {
    if (np_int < 0) return pow(f, (float8)(np));
    float8 r = (float8)(1.0f), b = f;
    for (int k = np_int; k > 0; k >>= 1) {
        if (k & 1) r *= b;
        b *= b;
    }
    return r;
}

// The low-resolution taps as the shared-columns path of jbu_upsample8 reads them, made once per call by jbu_pack_taps
// (w x h work-items; every display row of a tap row reads the same texels again, ~15 times at a display view's ratio):
// per texel 12 floats, [0..7] normal xyz, position xyz, 1 if it is a tap (a surface: the gather path's test, term for
// term) else 0, 0; [8..11] its values cleaned as jbu_clean8 cleans them (channels >= nc and non-taps: 0). Two vector
// loads per tap instead of nine scalar loads and the tests.
#ifndef JBU_TAP_FLOATS
#error "jbu_vec.cl needs JBU_TAP_FLOATS: build it with jbu_defines() (host/src/ops/jbu.hpp)"
#endif
#if JBU_TAP_FLOATS != 12
#error "jbu_pack_taps writes 12 floats per texel (host/src/ops/jbu.hpp kJbuTapFloats)"
#endif
__kernel void jbu_pack_taps(__global const float* restrict low, __global const float* restrict low_normal,
                            __global const float* restrict low_position, const int w, const int h, const int channels,
                            __global float* restrict taps) {
    const int l = get_global_id(0), plane = w * h, nc = channels;
    if (l >= plane) return;
    const float3 n = jbu_load3(low_normal, l, plane), p = jbu_load3(low_position, l, plane);
    // The gather path's test, term for term (its |m|^2 sum, not dot(): the same rounding).
    const int valid = jbu_finite3(n) && n.x * n.x + n.y * n.y + n.z * n.z >= 0.25f && jbu_finite3(p);
    float4 v = (float4)(0.0f);
    if (valid) {
        v.x = jbu_clean(low[l]);
        if (nc > 1) v.y = jbu_clean(low[plane + l]);
        if (nc > 2) v.z = jbu_clean(low[2 * plane + l]);
        if (nc > 3) v.w = jbu_clean(low[3 * plane + l]);
    }
    vstore8((float8)(n, p, valid ? 1.0f : 0.0f, 0.0f), 0, taps + JBU_TAP_FLOATS * l);
    vstore4(v, 0, taps + JBU_TAP_FLOATS * l + 8);
}

// floor(a / b) per lane for b > 0.
static inline int8 jbu_floor_div8(int8 a, int b) { return select(a / b, -((-a + b - 1) / b), a < 0); }

__kernel void jbu_upsample8(__global const float* restrict low, __global const float* restrict low_normal,
                            __global const float* restrict low_position, const int w, const int h, const int channels,
                            __global const float* restrict normal, __global const float* restrict position,
                            const int W, const int H, const float inv_two_sigma_s2, const float normal_power,
                            const float inv_two_sigma_p2, const int radius, const float fallback_ratio,
                            const int shared_columns, __global const float* restrict taps, __global float* restrict out,
                            volatile __global uint* fallbacks) {
    const int gx = get_global_id(0), y = get_global_id(1);
    const int lw = w, lh = h, nc = channels, ow = W, oh = H, r = clamp(radius, 1, JBU_MAX_RADIUS);
    const float s2 = inv_two_sigma_s2, np = normal_power, p2 = inv_two_sigma_p2, ratio = fallback_ratio;
    const int share = shared_columns;
    const int np_int = np == floor(np) ? (int)np : -1;
    const int x0 = gx * JBU_VEC;
    if (x0 >= ow || y >= oh) return;
    const int hi_plane = ow * oh, lo_plane = lw * lh;
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    const int8 x = x0 + lane, live = x < ow;
    const int8 o = y * ow + x;

    const int whole = x0 + JBU_VEC <= ow;  // all lanes inside the row: one vector load per plane
    const int row = y * ow + x0;
    const float8 nx = whole ? vload8(0, normal + row) : jbu_gather8(normal, o, live),
                 ny = whole ? vload8(0, normal + hi_plane + row) : jbu_gather8(normal + hi_plane, o, live),
                 nz = whole ? vload8(0, normal + 2 * hi_plane + row) : jbu_gather8(normal + 2 * hi_plane, o, live);
    const float8 px = whole ? vload8(0, position + row) : jbu_gather8(position, o, live),
                 py = whole ? vload8(0, position + hi_plane + row) : jbu_gather8(position + hi_plane, o, live),
                 pz = whole ? vload8(0, position + 2 * hi_plane + row) : jbu_gather8(position + 2 * hi_plane, o, live);
    const int8 surface = live & jbu_finite8(nx) & jbu_finite8(ny) & jbu_finite8(nz) &
                         (nx * nx + ny * ny + nz * nz >= 0.25f) & jbu_finite8(px) & jbu_finite8(py) & jbu_finite8(pz);

    const int8 num_x = (2 * x + 1) * lw - ow;
    const int den_x = 2 * ow, num_y = (2 * y + 1) * lh - oh, den_y = 2 * oh;
    const int8 fx0 = jbu_floor_div8(num_x, den_x);
    const int fy0 = jbu_floor_div(num_y, den_y);
    const int8 bx = fx0 - r + 1;
    const int by = fy0 - r + 1;
    float8 spatial_sum = (float8)(0.0f), weight_sum = (float8)(0.0f);
    float8 acc0 = (float8)(0.0f), acc1 = acc0, acc2 = acc0, acc3 = acc0;
    // The spatial Gaussian is separable: exp(-(dx^2 + dy^2) s2) = exp(-dx^2 s2) exp(-dy^2 s2), the column factors
    // computed once per work-item (2r or 2r + 1 exps per lane instead of 4r^2), the row factor once per tap row. Both
    // paths below compute them from the same integer column, so their results are the same bits; the one-pixel kernel
    // takes one exp per tap (rounding differs).
    // Shared columns: when the live lanes' first tap columns differ by at most one (the output at least ~8x the input
    // along x, as a display view of an N = 64 lightmap is), the work-item's taps are the 2r + 1 columns bx.s0 ...
    // bx.s0 + 2r of each tap row: lanes with shift 0 use the first 2r, lanes with shift 1 the last 2r. Each column's
    // texel is read once, from jbu_pack_taps' record, and its weight computed for all lanes, masked to the lanes whose
    // window holds it: per lane the same values and arithmetic as the gathers below, in the same order (a masked column
    // adds +0), so the same bits, without 8 x 2r gathered loads per value and tap row (the gathers were the cost).
    const int8 shift = bx - bx.s0;  // lane 0 is live and has the smallest column (bx grows with x)
    if (share && all(~live | (shift <= 1))) {
        const int8 right = shift == 1;
        float8 abs_weight[2 * JBU_MAX_RADIUS + 1];  // by absolute column bx.s0 + c (the gathers' col_weight values)
        for (int c = 0; c <= 2 * r; ++c) {
            const float8 dx = convert_float8((bx.s0 + c) * den_x - num_x) / (float)den_x;
            abs_weight[c] = exp(-dx * dx * s2);
        }
        for (int tj = 0; tj < 2 * r; ++tj) {
            const int j = by + tj;
            if (j < 0 || j >= lh) continue;
            const float dy = (float)(j * den_y - num_y) / (float)den_y, row_weight = exp(-dy * dy * s2);
            for (int c = 0; c <= 2 * r; ++c) {
                const int i = bx.s0 + c;
                if (i < 0 || i >= lw) continue;  // no lane's tap: every lane's `in` is 0 there
                const int8 window = c == 0 ? ~right : c == 2 * r ? right : (int8)(-1);
                const int8 in = surface & window;
                const float8 spatial = abs_weight[c] * row_weight;
                spatial_sum += select((float8)(0.0f), spatial, in);
                __global const float* tap = taps + JBU_TAP_FLOATS * (j * lw + i);
                const float8 g = vload8(0, tap);
                const int8 ok = in & (int8)(g.s6 != 0.0f ? -1 : 0);
                if (!any(ok)) continue;
                const float4 v = vload4(0, tap + 8);
                const float8 facing = fmax(nx * g.s0 + ny * g.s1 + nz * g.s2, 0.0f);
                const float8 plane = g.s0 * (px - g.s3) + g.s1 * (py - g.s4) + g.s2 * (pz - g.s5);
                const float8 wt =
                    select((float8)(0.0f), spatial * jbu_power8(facing, np, np_int) * exp(-plane * plane * p2), ok);
                weight_sum += wt;
                acc0 += wt * v.x;
                if (nc > 1) acc1 += wt * v.y;
                if (nc > 2) acc2 += wt * v.z;
                if (nc > 3) acc3 += wt * v.w;
            }
        }
    } else {
        float8 col_weight[2 * JBU_MAX_RADIUS];  // by the lane's own tap column bx + tc
        for (int tc = 0; tc < 2 * r; ++tc) {
            const float8 dx = convert_float8((bx + tc) * den_x - num_x) / (float)den_x;
            col_weight[tc] = exp(-dx * dx * s2);
        }
        for (int t = 0; t < 4 * r * r; ++t) {
            const int j = by + t / (2 * r);
            if (j < 0 || j >= lh) continue;  // the same row for every lane
            const int8 i = bx + t % (2 * r);
            const int8 in = surface & (i >= 0) & (i < lw);
            const float dy = (float)(j * den_y - num_y) / (float)den_y;
            const float8 spatial = col_weight[t % (2 * r)] * exp(-dy * dy * s2);
            spatial_sum += select((float8)(0.0f), spatial, in);
            const int8 l = j * lw + i;
            const float8 mx = jbu_gather8(low_normal, l, in), my = jbu_gather8(low_normal + lo_plane, l, in),
                         mz = jbu_gather8(low_normal + 2 * lo_plane, l, in);
            const float8 qx = jbu_gather8(low_position, l, in), qy = jbu_gather8(low_position + lo_plane, l, in),
                         qz = jbu_gather8(low_position + 2 * lo_plane, l, in);
            const int8 ok = in & jbu_finite8(mx) & jbu_finite8(my) & jbu_finite8(mz) &
                            (mx * mx + my * my + mz * mz >= 0.25f) & jbu_finite8(qx) & jbu_finite8(qy) & jbu_finite8(qz);
            if (!any(ok)) continue;
            const float8 facing = fmax(nx * mx + ny * my + nz * mz, 0.0f);
            const float8 plane = mx * (px - qx) + my * (py - qy) + mz * (pz - qz);
            const float8 wt =
                select((float8)(0.0f), spatial * jbu_power8(facing, np, np_int) * exp(-plane * plane * p2), ok);
            weight_sum += wt;
            acc0 += wt * jbu_clean8(jbu_gather8(low, l, ok));
            if (nc > 1) acc1 += wt * jbu_clean8(jbu_gather8(low + lo_plane, l, ok));
            if (nc > 2) acc2 += wt * jbu_clean8(jbu_gather8(low + 2 * lo_plane, l, ok));
            if (nc > 3) acc3 += wt * jbu_clean8(jbu_gather8(low + 3 * lo_plane, l, ok));
        }
    }

    const int8 use = surface & (weight_sum > ratio * spatial_sum) & (weight_sum > 0.0f);
    const float8 inv = select((float8)(0.0f), 1.0f / weight_sum, use);
    const float8 res[4] = {clamp(acc0 * inv, -FLT_MAX, FLT_MAX), clamp(acc1 * inv, -FLT_MAX, FLT_MAX),
                           clamp(acc2 * inv, -FLT_MAX, FLT_MAX), clamp(acc3 * inv, -FLT_MAX, FLT_MAX)};
    // Lanes of surface pixels whose weights vanished take the bilinear fallback, one at a time (rare).
    const int8 fall = surface & ~use;
    uint falls = 0;
    for (int k = 0; k < JBU_VEC; ++k) {
        if (x0 + k >= ow) break;
        const int ok = (int)((const int*)&use)[k] != 0, fb = (int)((const int*)&fall)[k] != 0;
        const int ox = x0 + k, oi = y * ow + ox;
        if (ok) {
            for (int c = 0; c < nc; ++c) out[c * hi_plane + oi] = ((const float*)&res[c])[k];
            continue;
        }
        if (!fb) {  // no surface: nothing to light
            for (int c = 0; c < nc; ++c) out[c * hi_plane + oi] = 0.0f;
            continue;
        }
        ++falls;
        const int nxi = (2 * ox + 1) * lw - ow;
        jbu_fallback_pixel(low, lw, lh, nc, nxi, den_x, jbu_floor_div(nxi, den_x), num_y, den_y, fy0, out, hi_plane, oi);
    }
    if (falls) atomic_add(fallbacks, falls);
}

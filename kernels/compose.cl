// Output side of the surround-aware pipeline: model output -> linear lightmap, resize, final composition,
// display transform. Value rules: docs/CONVENTIONS.md ("Output side").

// Build options, the host's (compose_defines(), host/src/pipeline/compose.cpp): TRANSFER_REINHARD, TRANSFER_CLAMP
// (ngi::LuminationTransfer), CURVE_ACES, CURVE_REINHARD, CURVE_CLAMP (ngi::ToneCurve) and LIGHT_MAX.
#if !defined(TRANSFER_REINHARD) || !defined(TRANSFER_CLAMP) || !defined(CURVE_ACES) || !defined(CURVE_REINHARD) || \
    !defined(CURVE_CLAMP) || !defined(LIGHT_MAX) || !defined(TONEMAP_VEC)
#error "compose.cl needs the host's transfer and tone-curve codes: build it with compose_defines() (host/src/pipeline/compose.cpp)"
#endif

// LIGHT_MAX (a build option, kLightMax): the decoded lightmap stops at the largest half float, so it survives a
// half-float EXR.

// Light terms: NaN -> 0, negative -> 0, +Inf -> FLT_MAX.
static inline float clean_light(float v) { return isnan(v) ? 0.0f : clamp(v, 0.0f, FLT_MAX); }

// Model output v in [lo, hi] -> [0, 1] -> linear light through the inverse lumination transfer
// (Reinhard: x = y / (1 - y)), in [0, LIGHT_MAX]. NaN (a broken model output) becomes 0.
static inline float decode_light(float v, const float lo, const float hi, const int transfer) {
    float y = (v - lo) / (hi - lo);
    y = isnan(y) ? 0.0f : clamp(y, 0.0f, 1.0f);
    if (transfer == TRANSFER_REINHARD) y = y < 1.0f ? fmin(y / (1.0f - y), LIGHT_MAX) : LIGHT_MAX;
    return y;
}

// Clean light x (>= 0) -> [0, 1] through the lumination transfer -> lo + y (hi - lo): the inverse of decode_light, the
// training target's encoding and the SSGI channels' (gbuffer.cl's lum_encode gives the same bits for lumination).
static inline float encode_light(float x, const float lo, const float hi, const int transfer) {
    const float y = transfer == TRANSFER_CLAMP ? fmin(x, 1.0f) : fmin(x / (1.0f + x), 1.0f);
    return lo + y * (hi - lo);
}

// In place: the model output of an output_mode "lightmap" model (the thesis's) -> the linear lightmap.
__kernel void decode_lightmap(__global float* restrict x, const int count, const float lo, const float hi,
                              const int transfer) {
    const int i = get_global_id(0);
    if (i >= count) return;
    x[i] = decode_light(x[i], lo, hi, transfer);
}

// In place: the model output of an output_mode "indirect" model decodes (exactly as above) to indirect light only;
// the lightmap is that plus the front face's direct light, read at direct[direct_off + i] (the same planar RGB
// layout as x: the frame planes 7-9 of face 0, or an uploaded N x N x 3 image). Direct light is sanitized like
// compose_final's light terms and the sum saturates at FLT_MAX, so the lightmap is finite and >= 0 whatever the
// frame holds. A kernel of its own, so the lightmap mode's code and results stay exactly as they were.
__kernel void decode_indirect(__global float* restrict x, const int count, const float lo, const float hi,
                              const int transfer, __global const float* restrict direct, const int direct_off) {
    const int i = get_global_id(0);
    if (i >= count) return;
    x[i] = fmin(decode_light(x[i], lo, hi, transfer) + clean_light(direct[direct_off + i]), FLT_MAX);
}

// Output mode "ssgi_residual" (docs/CONVENTIONS.md section 8): a network that corrects the SSGI rung's indirect light.
// Its input holds the SSGI estimate as three more channels, encoded like a training target: v_s = lo + T(s) (hi - lo)
// with T the lumination transfer and s = the SSGI lightmap minus the front direct light (both cleaned; s >= 0). Its
// output x is a correction in that encoded domain: the indirect light is decode(v_s + x), so x = 0 gives the SSGI
// rung's light exactly (up to the transfer's rounding) and a scene with nothing to bounce starts from none.
//
// encode_ssgi_input: writes v_s at dst[dst_off + i] from the SSGI lightmap `ssgi` and the direct light at
// direct[direct_off + i] (the frame planes 7-9 of face 0). The same arithmetic as encode_lightmap.
__kernel void encode_ssgi_input(__global const float* restrict ssgi, __global const float* restrict direct,
                                const int direct_off, __global float* restrict dst, const int dst_off, const int count,
                                const float lo, const float hi, const int transfer) {
    const int i = get_global_id(0);
    if (i >= count) return;
    dst[dst_off + i] = encode_light(fmax(clean_light(ssgi[i]) - clean_light(direct[direct_off + i]), 0.0f), lo, hi,
                                    transfer);
}

// In place: x (the network's correction) -> the lightmap, decode(v_s + x) + the front direct light; v_s is read back
// from the network input (planes 10-12, at input[input_off + i]), so the decoding adds exactly what the network saw.
__kernel void decode_ssgi_residual(__global float* restrict x, const int count, const float lo, const float hi,
                                   const int transfer, __global const float* restrict input, const int input_off,
                                   __global const float* restrict direct, const int direct_off) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const float v = x[i] + input[input_off + i];
    x[i] = fmin(decode_light(v, lo, hi, transfer) + clean_light(direct[direct_off + i]), FLT_MAX);
}

// The inverse of decode_lightmap, for training targets: linear light x -> [0, 1] through the lumination transfer
// -> lo + y (hi - lo). Light is sanitized like the input's lumination (NaN and negative -> 0, +Inf -> FLT_MAX)
// and encoded exactly as gbuffer.cl's lum_encode does it, so a lightmap equal to the front face's lumination
// encodes bit for bit like the network input's lumination channels.
__kernel void encode_lightmap(__global const float* restrict src, __global float* restrict dst, const int count,
                              const float lo, const float hi, const int transfer) {
    const int i = get_global_id(0);
    if (i >= count) return;
    dst[i] = encode_light(clean_light(src[i]), lo, hi, transfer);
}

// Bilinear resize of a planar image, pixel centres at +0.5 (PyTorch align_corners=False), edges clamped.
// Launch: 2-D (dst_w, dst_h), local 8 x 8.
__kernel void resize_bilinear(__global const float* restrict src, const int src_w, const int src_h,
                              __global float* restrict dst, const int dst_w, const int dst_h, const int channels) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= dst_w || y >= dst_h) return;
    const float fx = clamp(((float)x + 0.5f) * ((float)src_w / (float)dst_w) - 0.5f, 0.0f, (float)(src_w - 1));
    const float fy = clamp(((float)y + 0.5f) * ((float)src_h / (float)dst_h) - 0.5f, 0.0f, (float)(src_h - 1));
    const int x0 = (int)fx, y0 = (int)fy;
    const int x1 = min(x0 + 1, src_w - 1), y1 = min(y0 + 1, src_h - 1);
    const float ax = fx - (float)x0, ay = fy - (float)y0;
    for (int c = 0; c < channels; ++c) {
        __global const float* s = src + c * src_w * src_h;
        const float top = (1.0f - ax) * s[y0 * src_w + x0] + ax * s[y0 * src_w + x1];
        const float bottom = (1.0f - ax) * s[y1 * src_w + x0] + ax * s[y1 * src_w + x1];
        dst[(c * dst_h + y) * dst_w + x] = (1.0f - ay) * top + ay * bottom;
    }
}

// final = lightmap * albedo + emission + env, elementwise over `count` values of planar RGB images of one size.
// Albedo is sanitized as in preprocessing (NaN -> 0, clamped to [0, 1]); the sum saturates at FLT_MAX.
__kernel void compose_final(__global const float* restrict light, __global const float* restrict albedo,
                            __global const float* restrict emission, __global const float* restrict env,
                            const int has_emission, const int has_env, __global float* restrict out,
                            const int count) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const float a = isnan(albedo[i]) ? 0.0f : clamp(albedo[i], 0.0f, 1.0f);
    float v = clean_light(light[i]) * a;
    if (has_emission) v = fmin(v + clean_light(emission[i]), FLT_MAX);
    if (has_env) v = fmin(v + clean_light(env[i]), FLT_MAX);
    out[i] = v;
}

// The display transform (tonemap8) is kernels/tonemap.cl, listed before this file in the program.
__kernel void tonemap(__global const float* restrict src, __global float* restrict dst, const int count,
                      const float scale, const int curve, const int srgb) {
    const int i0 = get_global_id(0) * TONEMAP_VEC;
    if (i0 >= count) return;
    if (i0 + TONEMAP_VEC <= count) {
        vstore8(tonemap8(vload8(0, src + i0), scale, curve, srgb), 0, dst + i0);
        return;
    }
    float lanes[TONEMAP_VEC];
    for (int l = 0; l < TONEMAP_VEC; ++l) lanes[l] = i0 + l < count ? src[i0 + l] : 0.0f;
    vstore8(tonemap8(vload8(0, lanes), scale, curve, srgb), 0, lanes);
    for (int l = 0; i0 + l < count; ++l) dst[i0 + l] = lanes[l];
}

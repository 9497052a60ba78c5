// Small per-item MLPs (seed 001's AO network, seed 004's per-voxel networks): frequency encoding and every layer of
// the network in one launch, one work-item per item (pixel or point), activations in private memory.
// Conventions (the frequency encoding's parameters, layouts): docs/CONVENTIONS.md section 13.

// Build options. MAX_WIDTH: the largest layer width (encoded input included), a multiple of 4; the host builds a
// variant per width class (16, 32, 64, 128). PARAMS_SPACE: __constant when the packed weights fit the device's
// constant buffer (cached on every GPU), else __global. The host's constants (mlp_defines(), host/src/ops/mlp.cpp):
//   ORDER_COMPONENT  tiny-cuda-nn's Frequency: per component, per band: sin, cos (FrequencyEncoding::Order)
//   ORDER_BAND       NeRF / Neural GI Eq. 3: per band: sin of every component, then cos of every component
//   D_IN, D_IN_PAD, D_OUT, D_ACT, D_W, D_B, D_SIZE   the per-layer descriptor of mlp_fused: D_SIZE ints, at these
//                    slots: inputs, inputs rounded up to 4 (the row stride of the weights; padded weights are 0),
//                    outputs, activation, offset of the weights [out][in_pad] and of the bias [out] in params
#if !defined(MAX_WIDTH) || !defined(ORDER_COMPONENT) || !defined(ORDER_BAND) || !defined(D_IN) || \
    !defined(D_IN_PAD) || !defined(D_OUT) || !defined(D_ACT) || !defined(D_W) || !defined(D_B) || !defined(D_SIZE)
#error "mlp.cl needs the host's constants: build it with mlp_defines() (host/src/ops/mlp.cpp)"
#endif
#ifndef PARAMS_SPACE
#define PARAMS_SPACE __global
#endif

// Token pasting after expansion: MLP_CAT(float, 8) -> float8 (the vector widths of the VEC and ENC_VEC knobs).
#define MLP_CAT2(a, b) a##b
#define MLP_CAT(a, b) MLP_CAT2(a, b)

// The encoding's scale of band b: 2^(first_exp + b), times pi when use_pi.
static inline float band_scale(int b, int first_exp, int use_pi) {
    const float s = ldexp(1.0f, first_exp + b);
    return use_pi ? s * M_PI_F : s;
}

// The encoding of c components: [the raw components if include_raw], then 2 * bands * c features, feature
// j (past the raw part) being encode_one(component, band, is_cos) with feature_index(j). Both kernels use these.
static inline int encoded_width(int c, int bands, int include_raw) { return (include_raw ? c : 0) + 2 * bands * c; }

static inline float encode_one(float x, int band, int is_cos, int first_exp, int use_pi) {
    const float t = band_scale(band, first_exp, use_pi) * x;
    return is_cos ? cos(t) : sin(t);
}

// Which component, band and function feature k (past the raw part) is.
static inline void feature_index(int j, int c, int bands, int order, int* comp, int* band, int* is_cos) {
    if (order == ORDER_COMPONENT) {
        *comp = j / (2 * bands);
        const int r = j - *comp * 2 * bands;
        *band = r / 2;
        *is_cos = r & 1;
    } else {
        *band = j / (2 * c);
        const int r = j - *band * 2 * c;
        *is_cos = r >= c;
        *comp = r - (*is_cos ? c : 0);
    }
}

// y = MLP(encode(x)) for n items. Item i's channel ch is x[i * x_item + ch * x_chan] (planar NCHW images: x_item 1,
// x_chan n; point lists [n, C]: x_item C, x_chan 1); the same for y. Non-finite inputs are the caller's to sanitize.
__kernel void mlp_fused(__global const float* restrict x, const int x_off, const int n, const int in_ch, const int x_item,
                        const int x_chan, PARAMS_SPACE const float* restrict params,
                        PARAMS_SPACE const int* restrict desc, const int layers, const int bands, const int first_exp,
                        const int use_pi, const int include_raw, const int order, const float alpha,
                        __global float* restrict y, const int y_off, const int y_item, const int y_chan) {
    const int i = get_global_id(0);
    if (i >= n) return;
    float v[MAX_WIDTH], a[MAX_WIDTH], b[MAX_WIDTH];
    x += x_off;
    y += y_off;
    for (int ch = 0; ch < in_ch; ++ch) v[ch] = x[(size_t)i * x_item + (size_t)ch * x_chan];
    const int raw = bands == 0 || include_raw ? in_ch : 0;
    const int width = bands == 0 ? in_ch : encoded_width(in_ch, bands, include_raw);
    for (int k = 0; k < raw; ++k) a[k] = v[k];
    for (int k = raw; k < width; ++k) {
        int comp, band, is_cos;
        feature_index(k - raw, in_ch, bands, order, &comp, &band, &is_cos);
        a[k] = encode_one(v[comp], band, is_cos, first_exp, use_pi);
    }
    for (int k = width; k < MAX_WIDTH; ++k) a[k] = 0.0f;  // the padding the unrolled dot products read

    float* src = a;
    float* dst = b;
    for (int l = 0; l < layers; ++l) {
        PARAMS_SPACE const int* d = desc + l * D_SIZE;
        const int in_pad = d[D_IN_PAD], out = d[D_OUT], act = d[D_ACT];
        PARAMS_SPACE const float* w = params + d[D_W];
        PARAMS_SPACE const float* bias = params + d[D_B];
        for (int o = 0; o < out; ++o) {
            PARAMS_SPACE const float* row = w + o * in_pad;
            // Four products per iteration: a quarter of the loop iterations (llvmpipe ends a work-item's loops
            // after 65,535 iterations in total; the host checks the count against Context::loop_limit()).
            float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f, s3 = 0.0f;
            for (int j = 0; j < in_pad; j += 4) {
                s0 = mad(row[j], src[j], s0);
                s1 = mad(row[j + 1], src[j + 1], s1);
                s2 = mad(row[j + 2], src[j + 2], s2);
                s3 = mad(row[j + 3], src[j + 3], s3);
            }
            dst[o] = ngi_activate(bias[o] + ((s0 + s1) + (s2 + s3)), act, alpha);
        }
        for (int k = out; k < ((out + 3) & ~3); ++k) dst[k] = 0.0f;
        float* t = src;
        src = dst;
        dst = t;
    }
    const int out = desc[(layers - 1) * D_SIZE + D_OUT];
    for (int o = 0; o < out; ++o) y[(size_t)i * y_item + (size_t)o * y_chan] = src[o];
}

// The frequency encoding alone, materialized for the dense (GEMM) path and for graphs (Neural GI):
// e[e_off + k * n + i] (planar, channel-major; x planar too: item i's channel c at x[c * x_chan + i]).
// Launch: 2-D (ceil(n / ENC_VEC), encoded width). Knob ENC_VEC (build option, 1 by default; the device's
// mlp_items_per_work_item): each work-item encodes ENC_VEC consecutive items in the lanes of a vector. Why: PoCL
// evaluates a scalar sin or cos one value at a time (~40 ns on this machine's CPU) but the vector forms lane-parallel
// (~5 ns per value at 8 lanes); the encoding was 34-37 % of Neural GI's device time (docs/PERFORMANCE.md). A GPU
// runs work-items in SIMD lanes already: 1 there.
#ifndef ENC_VEC
#define ENC_VEC 1
#endif
#if ENC_VEC > 1
#define encV MLP_CAT(float, ENC_VEC)
#define enc_vload MLP_CAT(vload, ENC_VEC)
#define enc_vstore MLP_CAT(vstore, ENC_VEC)
#endif
__kernel void frequency_encode_planar(__global const float* restrict x, const int x_off, const int n, const int in_ch,
                                      const int x_chan, const int bands, const int first_exp, const int use_pi,
                                      const int include_raw, const int order, __global float* restrict e,
                                      const int e_off) {
    const int i0 = get_global_id(0) * ENC_VEC, k = get_global_id(1);
    const int raw = include_raw ? in_ch : 0;
    x += x_off;
    e += e_off;
    if (i0 >= n || k >= encoded_width(in_ch, bands, include_raw)) return;
    int comp = k, band = 0, is_cos = 0;
    if (k >= raw) feature_index(k - raw, in_ch, bands, order, &comp, &band, &is_cos);
    __global const float* src = x + (size_t)comp * x_chan;
    __global float* dst = e + (size_t)k * n;
#if ENC_VEC > 1
    if (i0 + ENC_VEC <= n) {
        const encV v = enc_vload(0, src + i0);
        if (k < raw) {
            enc_vstore(v, 0, dst + i0);
        } else {
            const encV t = band_scale(band, first_exp, use_pi) * v;
            enc_vstore(is_cos ? cos(t) : sin(t), 0, dst + i0);
        }
        return;
    }
#endif
    // One item per work-item, or the last ENC_VEC - 1 or fewer items of the vector form.
    const int end = min(i0 + ENC_VEC, n);
    for (int i = i0; i < end; ++i)
        dst[i] = k < raw ? src[i] : encode_one(src[i], band, is_cos, first_exp, use_pi);
}

// ---- the same MLP with its architecture compiled in (no encoding), VEC items per work-item -----------------------
// Built per network shape (FusedMlp picks it when there is no encoding and at most 8 layers): NL layers, W0 inputs,
// layer l (1..NL) with W<l> outputs, activation A<l>, weights [W<l>][INPAD<l>] at WOFF<l> and bias at BOFF<l> in
// params (the packing of the kernel above). Every bound is a compile-time constant, so the loops unroll and the
// activations stay in registers (the generic kernel above indexes private arrays at run time, which keeps them in
// memory and stops a CPU compiler from vectorizing). Knob VEC (1, 2, 4, 8, 16; a per-device choice, see
// FusedMlp): each work-item evaluates VEC consecutive items in the lanes of a floatVEC, so every weight is loaded
// once per VEC items and the arithmetic (tanh included) runs on vectors; planar inputs load with vloadVEC. Same
// sums as the generic kernel up to the order of the additions (one chain per output here, four there).
#ifdef NL
#ifndef VEC
#define VEC 1
#endif
#if VEC == 1
#define realV float
#else
#define realV MLP_CAT(float, VEC)
#endif

NGI_DEFINE_VECTOR_ACTIVATE(realV, vec)  // ngi_activate_vec: activation.cl's activations on VEC lanes

#define MLP_DENSE(IN, INPAD, OUT, ACT, WOFF, BOFF, src, dst)                              \
    _Pragma("unroll") for (int o = 0; o < (OUT); ++o) {                                   \
        PARAMS_SPACE const float* row = params + (WOFF) + o * (INPAD);                    \
        realV s = (realV)params[(BOFF) + o];                                              \
        _Pragma("unroll") for (int j = 0; j < (IN); ++j) s = mad((realV)row[j], src[j], s); \
        dst[o] = ngi_activate_vec(s, (ACT), alpha);                                         \
    }
#define MLP_LAYER(l, p) \
    realV h##l[W##l];   \
    MLP_DENSE(W##p, INPAD##l, W##l, A##l, WOFF##l, BOFF##l, h##p, h##l)

__kernel void mlp_static(__global const float* restrict x, const int x_off, const int n, const int x_item,
                         const int x_chan, PARAMS_SPACE const float* restrict params, const float alpha,
                         __global float* restrict y, const int y_off, const int y_item, const int y_chan) {
    const int first = get_global_id(0) * VEC;
    if (first >= n) return;
    x += x_off;
    y += y_off;
    // Full vectors of a planar layout load and store whole; the last, partial one (and strided layouts) go lane by
    // lane, with lanes past n repeating item n - 1 (computed, never stored).
    const int whole = first + VEC <= n && x_item == 1;
    realV h0[W0];
    _Pragma("unroll") for (int c = 0; c < W0; ++c) {
        __global const float* src = x + (size_t)c * x_chan;
#if VEC == 1
        h0[c] = src[(size_t)first * x_item];
#else
        if (whole) {
            h0[c] = MLP_CAT(vload, VEC)(0, src + first);
        } else {
            float lanes[VEC];
            for (int v = 0; v < VEC; ++v) lanes[v] = src[(size_t)min(first + v, n - 1) * x_item];
            h0[c] = MLP_CAT(vload, VEC)(0, lanes);
        }
#endif
    }
    MLP_LAYER(1, 0)
#if NL >= 2
    MLP_LAYER(2, 1)
#endif
#if NL >= 3
    MLP_LAYER(3, 2)
#endif
#if NL >= 4
    MLP_LAYER(4, 3)
#endif
#if NL >= 5
    MLP_LAYER(5, 4)
#endif
#if NL >= 6
    MLP_LAYER(6, 5)
#endif
#if NL >= 7
    MLP_LAYER(7, 6)
#endif
#if NL >= 8
    MLP_LAYER(8, 7)
#endif
#define MLP_OUT MLP_CAT(h, NL)
#define MLP_OUT_W MLP_CAT(W, NL)
    const int store_whole = first + VEC <= n && y_item == 1;
    _Pragma("unroll") for (int o = 0; o < MLP_OUT_W; ++o) {
        __global float* dst = y + (size_t)o * y_chan;
#if VEC == 1
        dst[(size_t)first * y_item] = MLP_OUT[o];
#else
        if (store_whole) {
            MLP_CAT(vstore, VEC)(MLP_OUT[o], 0, dst + first);
        } else {
            float lanes[VEC];
            MLP_CAT(vstore, VEC)(MLP_OUT[o], 0, lanes);
            for (int v = 0; v < VEC && first + v < n; ++v) dst[(size_t)(first + v) * y_item] = lanes[v];
        }
#endif
    }
}
#endif  // NL

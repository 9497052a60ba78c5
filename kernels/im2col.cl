// im2col into the GEMM's packed B layout.
//
// B is the K x N matrix with k = (c*KH + ky)*KW + kx and n = oy*OW + ox. It is stored in panels of NR columns:
// Bp[(n / NR) * Kpad * NR + k * NR + n % NR], zero-filled for padding taps, n >= N and k >= K, so the GEMM's
// inner loop needs no bounds checks. An optional input activation (ReLU before a transposed conv in the U-Net)
// is applied while gathering. With KH = KW = 1, stride 1, pad 0 this is a plain pack of a C x (H*W) matrix.
//
// One work-item per column n walks every k. Neighbouring work-items write neighbouring floats and read
// neighbouring input pixels, and every loop bound is uniform across the work-group: PoCL vectorizes across
// work-items, GPUs coalesce. Out-of-range taps load from a clamped address and are masked to 0 (no divergence).
//
// NR is a build option (-DNR=...), shared with gemm.cl: the panel width.

__kernel void im2col_packed(__global const float* restrict x, const int x_off,
                            const int C, const int H, const int W,
                            const int KH, const int KW, const int stride, const int pad,
                            const int OH, const int OW, const int Kpad,
                            __global float* restrict bp, const int bp_off, const int in_act, const float alpha) {
    const int n = get_global_id(0);
    const int N = OH * OW;
    const int Npad = (N + NR - 1) / NR * NR;
    if (n >= Npad) return;
    __global float* dst = bp + bp_off + (size_t)(n / NR) * Kpad * NR + n % NR;
    const int valid_n = n < N;
    const int oy = valid_n ? n / OW : 0, ox = valid_n ? n - oy * OW : 0;
    const int iy0 = oy * stride - pad, ix0 = ox * stride - pad;
    __global const float* src = x + x_off;
    int k = 0;
    for (int c = 0; c < C; ++c) {
        for (int ky = 0; ky < KH; ++ky) {
            const int iy = iy0 + ky;
            const int row_ok = valid_n && iy >= 0 && iy < H;
            for (int kx = 0; kx < KW; ++kx, ++k) {
                const int ix = ix0 + kx;
                const int ok = row_ok && ix >= 0 && ix < W;
                const float v = src[ok ? ((size_t)c * H + iy) * W + ix : 0];
                dst[(size_t)k * NR] = ok ? ngi_activate(v, in_act, alpha) : 0.0f;
            }
        }
    }
    for (; k < Kpad; ++k) dst[(size_t)k * NR] = 0.0f;
}

// conv_pad: the B source of the implicit-GEMM convolution (gemm_conv in kernels/gemm.cl). Writes
//   xp[cp*CS + u*ROW + v] = act(x[c][u*S + py - PTY][v*S + px - PTX]),   cp = (c*S + py)*S + px, v < RS,
// zero where the source pixel is outside the input: a zero-padded copy (S = 1) or, for a stride-S convolution, its
// S x S polyphase split, after which the convolution has stride 1. planes x PH rows of RS floats, planar
// (CS = PH*RS, ROW = RS) or row-interleaved (CS = RS, ROW = planes*RS); then `slack` zeros at slack_off, which
// the last tiles' junk lanes read.
// The input activation is none, ReLU or LeakyReLU, as act(v) = v >= 0 ? v : slope * v (slope 1, 0 or alpha).
// One work-item per row (u, cp) writes its RS floats in three loops - zeros, the input row, zeros - the middle one
// in explicit 8-float vectors for S = 1 and S = 2 (see there), scalar for its tail and other strides. A work-item per
// element with a bounds test per element measured 4x slower than memcpy on PoCL. Loop iterations per work-item:
// RS (+ slack).
__kernel void conv_pad(__global const float* restrict x, const int x_off, const int C, const int H, const int W,
                       const int S, const int PTY, const int PTX, const int PH, const int RS, const int planes,
                       const int CS, const int ROW, __global float* restrict xp, const int xp_off, const float slope,
                       const int slack_off, const int slack) {
    // Neighbouring work-items write neighbouring rows of xp: along u when planar, along cp when row-interleaved.
    const int interleaved = CS < ROW;
    const int u = get_global_id(interleaved), cp = get_global_id(1 - interleaved);
    if (u >= PH || cp >= planes) return;
    if (u == 0 && cp == 0)
        for (int i = 0; i < slack; ++i) xp[xp_off + slack_off + i] = 0.0f;
    const int c = cp / (S * S), ph = cp - c * S * S, py = ph / S, px = ph - py * S;
    const int iy = u * S + py - PTY;
    __global float* restrict dst = xp + xp_off + (size_t)cp * CS + (size_t)u * ROW;
    // Columns v with 0 <= v*S + px - PTX < W: [v0, v1).
    const int first = PTX - px, last = W - 1 + PTX - px;  // v*S must lie in [first, last]
    int v0 = first <= 0 ? 0 : (first + S - 1) / S;
    int v1 = last < 0 ? 0 : last / S + 1;
    if (c >= C || iy < 0 || iy >= H) v0 = v1 = 0;
    v1 = min(v1, RS);
    v0 = min(v0, v1);
    // Index arithmetic, not a pointer to px - PTX < 0 before the row (that pointer could lie before the buffer).
    __global const float* restrict src = x + x_off + ((size_t)c * H + (iy < 0 ? 0 : iy)) * W;
    const int shift = px - PTX;
    for (int v = 0; v < v0; ++v) dst[v] = 0.0f;
    int v = v0;
    // Stride 2 (the U-Net's down convolutions): eight outputs from one 16-float load, its even lanes. PoCL
    // vectorizes this kernel across work-items, i.e. across rows, so the plain loop below became a gather and a
    // scatter per element: the first layer's split (12 x 128 x 256 floats) took 0.75 ms, ~2 GB/s. `v + 8 < v1`
    // keeps the load's last float, src[2 (v + 7) + shift + 1], inside the row's valid columns.
    if (S == 1)
        for (; v + 8 <= v1; v += 8) {
            const float8 val = vload8(0, src + v + shift);
            vstore8(select(slope * val, val, val >= (float8)(0.0f)), 0, dst + v);
        }
    if (S == 2)
        for (; v + 8 < v1; v += 8) {
            const float8 val = vload16(0, src + v * 2 + shift).even;
            vstore8(select(slope * val, val, val >= (float8)(0.0f)), 0, dst + v);
        }
    for (; v < v1; ++v) {
        const float val = src[v * S + shift];
        dst[v] = val >= 0.0f ? val : slope * val;
    }
    for (v = v1; v < RS; ++v) dst[v] = 0.0f;
}

// pack_panels: a row-major K x N matrix into the GEMM's packed B layout (what im2col_packed writes for a 1 x 1
// kernel, stride 1, no padding), with the input activation: Bp[(n / NR) * Kpad * NR + k * NR + n % NR].
// One work-item per (k, panel) copies NR contiguous floats to NR contiguous floats, k fastest so neighbouring
// work-items write neighbouring chunks of a panel; the none / ReLU / LeakyReLU activations go through a
// branch-free slope so the copy vectorizes. im2col_packed's one-work-item-per-column form measured ~5 GB/s here.
// Rows k >= K and columns n >= N are zero-filled. Loop iterations per work-item: NR.
__kernel void pack_panels(__global const float* restrict x, const int x_off, const int K, const int N,
                          const int Kpad, __global float* restrict bp, const int bp_off, const int act,
                          const float alpha) {
    const int k = get_global_id(0), np = get_global_id(1);
    if (k >= Kpad || np * NR >= N) return;
    __global float* restrict dst = bp + bp_off + ((size_t)np * Kpad + k) * NR;
    const int n0 = np * NR;
    const int count = k < K ? min(NR, N - n0) : 0;
    __global const float* restrict src = x + x_off + (size_t)(k < K ? k : 0) * N + n0;
    if (act == ACT_NONE || act == ACT_RELU || act == ACT_LEAKY_RELU) {
        const float slope = act == ACT_NONE ? 1.0f : act == ACT_RELU ? 0.0f : alpha;
        for (int l = 0; l < count; ++l) {
            const float v = src[l];
            dst[l] = v >= 0.0f ? v : slope * v;
        }
    } else {
        for (int l = 0; l < count; ++l) dst[l] = ngi_activate(src[l], act, alpha);
    }
    for (int l = count; l < NR; ++l) dst[l] = 0.0f;
}

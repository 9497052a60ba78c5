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

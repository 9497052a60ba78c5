// im2col into the GEMM's packed B layout.
//
// B is the K x N matrix with k = (c*KH + ky)*KW + kx and n = oy*OW + ox. It is stored in panels of NR columns:
// Bp[(n / NR) * Kpad * NR + k * NR + n % NR], zero-filled for padding taps, n >= N and k >= K, so the GEMM's
// inner loop needs no bounds checks. One work-item writes one (k, panel) row of NR values.
// An optional input activation (ReLU before a transposed conv in the U-Net) is applied while gathering.
// With KH = KW = 1, stride 1, pad 0 this is a plain pack of a C x (H*W) matrix.
//
// NR is a build option (-DNR=...), shared with gemm.cl.

__kernel void im2col_packed(__global const float* restrict x, const int x_off,
                            const int C, const int H, const int W,
                            const int KH, const int KW, const int stride, const int pad,
                            const int OH, const int OW, const int Kpad,
                            __global float* restrict bp, const int bp_off, const int in_act, const float alpha) {
    const int k = get_global_id(0);
    const int panel = get_global_id(1);
    const int K = C * KH * KW;
    if (k >= Kpad) return;
    const int N = OH * OW;
    __global float* dst = bp + bp_off + ((size_t)panel * Kpad + k) * NR;
    if (k >= K) {
        for (int j = 0; j < NR; ++j) dst[j] = 0.0f;
        return;
    }
    const int kx = k % KW;
    const int ky = (k / KW) % KH;
    const int c = k / (KW * KH);
    __global const float* src = x + x_off + (size_t)c * H * W;
    int n = panel * NR;
    int oy = n / OW, ox = n - oy * OW;
    for (int j = 0; j < NR; ++j, ++n) {
        float v = 0.0f;
        if (n < N) {
            const int iy = oy * stride - pad + ky;
            const int ix = ox * stride - pad + kx;
            if (iy >= 0 && iy < H && ix >= 0 && ix < W) v = ngi_activate(src[iy * W + ix], in_act, alpha);
        }
        dst[j] = v;
        if (++ox == OW) { ox = 0; ++oy; }
    }
}

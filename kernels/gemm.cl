// Register-tiled, vectorized SGEMM on packed operands with a fused per-row epilogue.
//
//   C[m][n] = act(scale[m] * sum_k A[m][k] * B[k][n] + shift[m])
//
// A (weights) is packed once at model load in panels of MR rows: Ap[(m / MR) * Kpad * MR + k * MR + m % MR].
// B (im2col output) is packed in panels of NR columns: Bp[(n / NR) * Kpad * NR + k * NR + n % NR].
// Both are zero-padded, so the inner loop has no bounds checks; only the epilogue masks m >= M, n >= N.
// Each work-item owns one MR x NR tile of C held in MR*NV vector registers (an outer-product micro-kernel, the
// same shape as BLAS micro-kernels): per k it loads NV vectors of B, broadcasts MR values of A and issues
// MR*NV vector multiply-adds.
//
// Knobs (build options, chosen per device in host/src/ops/gemm_params.cpp):
//   MR  rows per tile (1..16)         VW  vector width (1, 2, 4, 8, 16)         NV  vectors per row, NR = VW*NV
//   KU  k-loop unroll factor (Kpad is a multiple of KU)

#ifndef MR
#define MR 8
#endif
#ifndef VW
#define VW 16
#endif
#ifndef NV
#define NV 2
#endif
#ifndef KU
#define KU 1
#endif
#define NR (VW * NV)

#if VW == 1
#define vtype float
#define VLOAD(p) (*(p))
#else
#define vtype NGI_CAT(float, VW)
#define VLOAD(p) NGI_CAT(vload, VW)(0, (p))
#endif

__kernel void gemm_packed(const int M, const int N, const int Kpad,
                          __global const float* restrict ap, __global const float* restrict bp, const int b_off,
                          __global float* restrict c, const int c_off, const int ldc,
                          __global const float* restrict scale, __global const float* restrict shift,
                          const int act, const float alpha) {
    const int mp = get_global_id(0);
    const int np = get_global_id(1);
    if (mp * MR >= M || np * NR >= N) return;
    __global const float* a = ap + (size_t)mp * Kpad * MR;
    __global const float* b = bp + b_off + (size_t)np * Kpad * NR;

    vtype acc[MR][NV];
#pragma unroll
    for (int i = 0; i < MR; ++i)
#pragma unroll
        for (int j = 0; j < NV; ++j) acc[i][j] = (vtype)(0.0f);

    for (int k = 0; k < Kpad; k += KU) {
#pragma unroll
        for (int u = 0; u < KU; ++u) {
            vtype bv[NV];
#pragma unroll
            for (int j = 0; j < NV; ++j) bv[j] = VLOAD(b + j * VW);
#pragma unroll
            for (int i = 0; i < MR; ++i) {
                const vtype av = (vtype)(a[i]);
#pragma unroll
                for (int j = 0; j < NV; ++j) acc[i][j] = fma(av, bv[j], acc[i][j]);
            }
            a += MR;
            b += NR;
        }
    }

    // Epilogue: per-row affine (bias / folded batch norm) + activation, masked store.
#pragma unroll
    for (int i = 0; i < MR; ++i) {
        const int m = mp * MR + i;
        if (m >= M) break;
        const float s = scale[m], t = shift[m];
        __global float* row = c + c_off + (size_t)m * ldc + np * NR;
#pragma unroll
        for (int j = 0; j < NV; ++j) {
#if VW == 1
            float v[1] = {acc[i][j]};
#else
            float v[VW];
            NGI_CAT(vstore, VW)(acc[i][j], 0, v);
#endif
#pragma unroll
            for (int l = 0; l < VW; ++l) {
                const int n = np * NR + j * VW + l;
                if (n < N) row[j * VW + l] = ngi_activate(fma(v[l], s, t), act, alpha);
            }
        }
    }
}

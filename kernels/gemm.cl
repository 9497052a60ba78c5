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
// Knobs (build options, chosen per device in host/src/ops/gemm.cpp and checked at device open by
// host/src/ops/gemm_selfcheck.cpp):
//   MR  rows per tile (1..16)         VW  vector width (1, 2, 4, 8, 16)         NV  vectors per row, NR = VW*NV (1..8)
//   KU  k-loop unroll factor (1..16; Kpad is a multiple of KU)
//   UNROLL  1: the MR x NV x KU micro-kernel is unrolled by the preprocessor (default);
//           0: it is written as loops with #pragma unroll, left to the compiler.
// Why UNROLL exists: #pragma unroll is a hint. Mesa's OpenCL path (clc -> SPIR-V -> NIR) does not honour it for
// large bodies, and llvmpipe (gallivm) stops *every* loop of a kernel silently after 65,535 iterations in total
// per invocation (LP_MAX_TGSI_LOOP_ITERATIONS). With loops left in, one k step costs 1 + NV + MR*(1 + NV)
// iterations and K >= ~1,000-3,000 came out truncated on rusticl (docs/RELIABILITY.md). Unrolled by the
// preprocessor, one k step is one loop iteration: the K loop is the only loop that scales with the problem.

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
#ifndef UNROLL
#define UNROLL 1
#endif
#define NR (VW * NV)

#if VW == 1
#define vtype float
#define VLOAD(p) (*(p))
#else
#define vtype NGI_CAT(float, VW)
#define VLOAD(p) NGI_CAT(vload, VW)(0, (p))
#endif

#if UNROLL
// Repetition macros: REP_M<n>(X) and REP_K<n>(X) expand X(0) .. X(n-1); REP_N<n>(X, i) expands X(i, 0) .. X(i, n-1).
// One family per nesting level (k steps > rows > vectors), because a macro is not expanded again inside its own
// expansion.
#define REP_M1(X) X(0)
#define REP_M2(X) REP_M1(X) X(1)
#define REP_M3(X) REP_M2(X) X(2)
#define REP_M4(X) REP_M3(X) X(3)
#define REP_M5(X) REP_M4(X) X(4)
#define REP_M6(X) REP_M5(X) X(5)
#define REP_M7(X) REP_M6(X) X(6)
#define REP_M8(X) REP_M7(X) X(7)
#define REP_M9(X) REP_M8(X) X(8)
#define REP_M10(X) REP_M9(X) X(9)
#define REP_M11(X) REP_M10(X) X(10)
#define REP_M12(X) REP_M11(X) X(11)
#define REP_M13(X) REP_M12(X) X(12)
#define REP_M14(X) REP_M13(X) X(13)
#define REP_M15(X) REP_M14(X) X(14)
#define REP_M16(X) REP_M15(X) X(15)
#define REP_N1(X, i) X(i, 0)
#define REP_N2(X, i) REP_N1(X, i) X(i, 1)
#define REP_N3(X, i) REP_N2(X, i) X(i, 2)
#define REP_N4(X, i) REP_N3(X, i) X(i, 3)
#define REP_N5(X, i) REP_N4(X, i) X(i, 4)
#define REP_N6(X, i) REP_N5(X, i) X(i, 5)
#define REP_N7(X, i) REP_N6(X, i) X(i, 6)
#define REP_N8(X, i) REP_N7(X, i) X(i, 7)
#define REP_K1(X) X(0)
#define REP_K2(X) REP_K1(X) X(1)
#define REP_K3(X) REP_K2(X) X(2)
#define REP_K4(X) REP_K3(X) X(3)
#define REP_K5(X) REP_K4(X) X(4)
#define REP_K6(X) REP_K5(X) X(5)
#define REP_K7(X) REP_K6(X) X(6)
#define REP_K8(X) REP_K7(X) X(7)
#define REP_K9(X) REP_K8(X) X(8)
#define REP_K10(X) REP_K9(X) X(9)
#define REP_K11(X) REP_K10(X) X(10)
#define REP_K12(X) REP_K11(X) X(11)
#define REP_K13(X) REP_K12(X) X(12)
#define REP_K14(X) REP_K13(X) X(13)
#define REP_K15(X) REP_K14(X) X(14)
#define REP_K16(X) REP_K15(X) X(15)
#define FOR_ROWS(X) NGI_CAT(REP_M, MR)(X)
#define FOR_VECS(X, i) NGI_CAT(REP_N, NV)(X, i)
#define FOR_STEPS(X) NGI_CAT(REP_K, KU)(X)

#define ZERO(i, j) acc[i][j] = (vtype)(0.0f);
#define ZERO_ROW(i) FOR_VECS(ZERO, i)
#define LOAD_B(u, j) bv[j] = VLOAD(b + (u) * NR + (j) * VW);
#define FMA(i, j) acc[i][j] = fma(av, bv[j], acc[i][j]);
#define FMA_ROW(i) { const vtype av = (vtype)(a[i]); FOR_VECS(FMA, i) }
// One k step: NV loads of B, MR broadcasts of A, MR*NV fmas; a and b advance by one packed row.
#define STEP(u) { vtype bv[NV]; FOR_VECS(LOAD_B, u) FOR_ROWS(FMA_ROW) a += MR; }
#endif

// Stores vector x = C[m][np*NR + j*VW .. +VW) through the epilogue, masking n >= N (needs m, s, t, row in scope).
#if VW == 1
#define TO_LANES(x, v) float v[1] = {x};
#else
#define TO_LANES(x, v) float v[VW]; NGI_CAT(vstore, VW)(x, 0, v);
#endif
#define STORE_VEC(x, j)                                                               \
    {                                                                                 \
        TO_LANES(x, v)                                                                \
        for (int l = 0; l < VW; ++l) {                                                \
            const int n = np * NR + (j) * VW + l;                                     \
            if (n < N) row[(j) * VW + l] = ngi_activate(fma(v[l], s, t), act, alpha); \
        }                                                                             \
    }
#if UNROLL
#define STORE(i, j) STORE_VEC(acc[i][j], j)
#define STORE_ROW(i)                                                       \
    if (mp * MR + (i) < M) {                                               \
        const int m = mp * MR + (i);                                       \
        const float s = scale[m], t = shift[m];                            \
        __global float* row = c + c_off + (size_t)m * ldc + np * NR;       \
        FOR_VECS(STORE, i)                                                 \
    }
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
#if UNROLL
    FOR_ROWS(ZERO_ROW)
    for (int k = 0; k < Kpad; k += KU) {
        FOR_STEPS(STEP)
        b += KU * NR;
    }
#else
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
#endif

    // Epilogue: per-row affine (bias / folded batch norm) + activation, masked store. At most MR*NV*VW iterations
    // per work-item, independent of K. Unrolled over rows and vectors too, so acc is never indexed at run time
    // (a runtime index would force the accumulators out of registers into private memory).
#if UNROLL
    FOR_ROWS(STORE_ROW)
#else
#pragma unroll
    for (int i = 0; i < MR; ++i) {
        const int m = mp * MR + i;
        if (m >= M) break;
        const float s = scale[m], t = shift[m];
        __global float* row = c + c_off + (size_t)m * ldc + np * NR;
#pragma unroll
        for (int j = 0; j < NV; ++j) STORE_VEC(acc[i][j], j);
    }
#endif
}

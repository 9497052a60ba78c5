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
//   KWG  0: this kernel (gemm_packed), operands read straight from global memory (CPUs);
//        > 0: gemm_local below, the GPU-shaped variant: a work-group of L0 x L1 work-items stages K chunks of KWG
//        packed rows of its A and B panels in __local memory (L0, L1 = the work-group shape, also -D defines).
//        A program is built with one of the two kernels, never both (Mesa compiles unrolled bodies slowly).
//   IMPLICIT  1: gemm_conv below instead, the implicit-GEMM convolution (B read from a padded image; -DTH -DTW:
//             its taps when at most 4, else 0 for runtime tap loops); the convolutions take it with KWG 0 sets only
//             (host/src/ops/conv_implicit.cpp), dense layers with every set (ops/dense.cpp: KWG is then unused).
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
#ifndef KWG
#define KWG 0
#endif
#ifndef IMPLICIT
#define IMPLICIT 0
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

// The epilogue's activation on whole accumulator vectors (activation.cl): ngi_activate_vt.
NGI_DEFINE_VECTOR_ACTIVATE(vtype, vt)
#if VW == 1
#define TO_LANES(x, v) float v[1] = {x};
#define VSTORE(x, p) (*(p) = (x))
#else
#define TO_LANES(x, v) float v[VW]; NGI_CAT(vstore, VW)(x, 0, v);
#define VSTORE(x, p) NGI_CAT(vstore, VW)((x), 0, (p))
#endif
// Stores vector x = C[m][np*NR + j*VW .. +VW) through the epilogue (needs m, s, t, row in scope): the affine and the
// activation on the whole vector, then one vector store, or lane by lane masking n >= N in the last tile.
#define STORE_VEC(x, j)                                                                    \
    {                                                                                      \
        const vtype o = ngi_activate_vt(fma(x, (vtype)(s), (vtype)(t)), act, alpha);       \
        const int n0 = np * NR + (j) * VW;                                                 \
        if (n0 + VW <= N) {                                                                \
            VSTORE(o, row + (j) * VW);                                                     \
        } else {                                                                           \
            TO_LANES(o, v)                                                                 \
            for (int l = 0; l < VW; ++l)                                                   \
                if (n0 + l < N) row[(j) * VW + l] = v[l];                                  \
        }                                                                                  \
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

#if IMPLICIT
// gemm_conv: implicit-GEMM convolution. B is never materialized: it is read from xp, a zero-padded (and for
// strides > 1 polyphase-split) copy of the input that conv_pad (kernels/im2col.cl) writes: C planes, channel
// stride CS, row stride ROW. The convolution is then stride 1 with th x tw taps over xp:
//   out[m][q][r] = sum_{c, ty, tx} A[m][(c*TH + ty)*TW + tx] * xp[c*CS + (q + ty)*ROW + r + tx],
// so for a tile of NR outputs of one row, B's k-th row is NR contiguous floats at a channel offset plus a tap
// offset - the same vector loads as a packed panel, unaligned. Two tilings (host/src/ops/conv_implicit.cpp):
//   TPR = 0 (linear): xp is planar (CS = PH*ROW) and tiles run over n = q*ROW + r on the padded grid, crossing
//        rows: the columns r >= OW are computed and dropped (junk). Suits narrow layers.
//   TPR > 0 (rows): TPR tiles per output row, tile np at row np / TPR; xp is row-interleaved (CS = row length,
//        ROW = C * CS), so consecutive channels of a tile's rows are neighbours in memory (a steady stream the
//        prefetcher follows, not one page per channel). Lanes r >= OW are junk.
// Junk lanes read whatever lies next (another row or channel, or the zeroed slack after xp): always initialized,
// never stored. K = C*TH*TW; A is packed with Kpad = K (KU plays no role).
// Output element (m, q, r) goes to y[y_off + m*y_plane + q*SY*ldy + r*SX]: SY = SX = 1 for a convolution, the
// stride for one phase of a transposed convolution, whose offset is folded into y_off; with has_res, res indexed
// the same way (from res_off, plus the phase's output offset) is added after the activation (a residual block's
// h + act(W h + b)).
// A one-tap layer over a planar input can read the input itself as xp (a 1 x 1 convolution or a dense layer, no
// copy): b_limit = the plane's floats then keeps the last tile inside it (see lane0 below), where a padded copy
// has zeroed slack instead (b_limit = 0).
// Taps that fit in the knob set's KU (at most 4; the U-Net's 2 x 2 with KU 4; -DTH -DTW > 0) are expanded by the
// preprocessor, one micro-kernel step each: as a loop they measured 10-15% slower on PoCL. Otherwise (-DTH=0
// -DTW=0) runtime loops over th x tw hold one step, and every geometry shares one program per knob set: an
// expanded program is minutes of compilation on Mesa. Loop iterations per work-item: C (expanded) or C * (1 + th * (1 + tw)), plus the epilogue's (llvmpipe
// stops loops at 65,535; the host checks, ops/conv_implicit.cpp).
#define TOFF(t) (((t) / TW) * ROW + (t) % TW)
#if UNROLL
#define CLOAD_B(off, j) bv[j] = VLOAD(bc + (off) + (j) * VW);
#define CSTEP(off) { vtype bv[NV]; FOR_VECS(CLOAD_B, off) FOR_ROWS(FMA_ROW) a += MR; }
#define CSTORE(i, j) CSTORE_VEC(acc[i][j], j)
#define CSTORE_ROW(i)                                                      \
    if (mp * MR + (i) < M) {                                               \
        const int m = mp * MR + (i);                                       \
        const float s = scale[m], t = shift[m];                            \
        __global float* row = y + y0 + (size_t)m * y_plane;                \
        __global const float* rrow = res + res_off + phase_y + (size_t)m * y_plane; \
        FOR_VECS(CSTORE, i)                                                \
    }
#endif
// Lane e = j*VW + l of the tile is output (q, r): row tiles stay in row q0 (r = r0 + e); linear tiles wrap
// at ROW (a division per lane, in narrow layers only). Lanes with r >= OW or q >= OH are junk, and so are lanes
// e < lane0 of a clamped last tile (the previous tile's, stored there). No per-lane table in private memory: Mesa's
// compiler stalled for over 20 minutes on a dynamically indexed int[NR] here. A vector whose lanes are all this
// tile's real outputs in one row, contiguous in y (SX = 1: not a phase of a transposed convolution), is stored
// whole; the rest lane by lane. The affine, the activation and the residual run on the whole vector either way.
#define CSTORE_VEC(x, j)                                                                \
    {                                                                                   \
        vtype o = ngi_activate_vt(fma(x, (vtype)(s), (vtype)(t)), act, alpha);          \
        int q = q0, r = r0 + (j) * VW;                                                  \
        if (TPR == 0) {                                                                 \
            q = (base + (j) * VW) / ROW;                                                \
            r = base + (j) * VW - q * ROW;                                              \
        }                                                                               \
        if (SX == 1 && q < OH && r + VW <= OW && (j) * VW >= lane0) {                   \
            if (has_res) o += VLOAD(rrow + q * SY * ldy + r);                           \
            VSTORE(o, row + q * SY * ldy + r);                                          \
        } else {                                                                        \
            TO_LANES(o, v)                                                              \
            for (int l = 0; l < VW; ++l) {                                              \
                const int e = (j) * VW + l;                                             \
                int qq = q0, rr = r0 + e;                                               \
                if (TPR == 0) {                                                         \
                    qq = (base + e) / ROW;                                              \
                    rr = base + e - qq * ROW;                                           \
                }                                                                       \
                if (qq < OH && rr < OW && e >= lane0) {                                 \
                    const int at = qq * SY * ldy + rr * SX;                             \
                    row[at] = has_res ? v[l] + rrow[at] : v[l];                         \
                }                                                                       \
            }                                                                           \
        }                                                                               \
    }

__kernel void gemm_conv(const int M, const int C, const int Kpad,
                        __global const float* restrict ap, const int a_off,
                        __global const float* restrict xp, const int xp_off,
                        const int CS, const int ROW, const int th, const int tw, const int TPR, const int OH,
                        const int OW,
                        __global float* restrict y, const int y_off, const int y_plane, const int ldy, const int SY,
                        const int SX, __global const float* restrict scale, __global const float* restrict shift,
                        const int act, const float alpha, const int b_limit,
                        __global const float* restrict res, const int res_off, const int has_res,
                        const int phase_s, const int phase_p, const int a_phase) {
    const int mp = get_global_id(0);
    const int np = get_global_id(1);
    int q0, r0, base;  // the tile's first lane: output row and column, offset in xp
    if (TPR > 0) {
        q0 = np / TPR;
        r0 = (np - q0 * TPR) * NR;
        base = q0 * ROW + r0;
    } else {
        base = np * NR;
        q0 = base / ROW;
        r0 = base - q0 * ROW;
    }
    if (mp * MR >= M || q0 >= OH) return;
    // b_limit > 0 (linear tiles over an input read in place, with nothing readable after a plane's b_limit floats):
    // a last tile that would read past it starts NR lanes before the limit instead; its first lane0 lanes belong
    // to the previous tile and are not stored. The host guarantees b_limit >= NR.
    int lane0 = 0;
    if (b_limit > 0 && base + NR > b_limit) {
        lane0 = base - (b_limit - NR);
        base = b_limit - NR;
        q0 = base / ROW;
        r0 = base - q0 * ROW;
    }
    // The sub-pixel phases of a transposed convolution in one launch (phase_s = its stride S > 0; 0: one phase):
    // phase (py, px) = global id 2 has its own packed A (a_phase floats apart), reads xp from tap row and column
    // offset (p + P) / S - P / S (the padding in front made every offset >= 0; ops/conv_implicit.cpp up_offset)
    // and writes output pixels (S q + py, S r + px).
    int phase_b = 0, phase_y = 0, phase_a = 0;
    if (phase_s > 0) {
        const int ph = get_global_id(2), py = ph / phase_s, px = ph - py * phase_s;
        const int base_off = phase_p / phase_s;
        phase_b = ((py + phase_p) / phase_s - base_off) * ROW + (px + phase_p) / phase_s - base_off;
        phase_y = py * ldy + px;
        phase_a = ph * a_phase;
    }
    const int y0 = y_off + phase_y;  // where this phase's output plane 0 starts
    __global const float* a = ap + a_off + phase_a + (size_t)mp * Kpad * MR;
    __global const float* bc = xp + xp_off + phase_b + base;

    vtype acc[MR][NV];
#if UNROLL
    FOR_ROWS(ZERO_ROW)
    for (int c = 0; c < C; ++c) {
#if TH > 0
        CSTEP(TOFF(0))
#if TH * TW > 1
        CSTEP(TOFF(1))
#endif
#if TH * TW > 2
        CSTEP(TOFF(2))
#endif
#if TH * TW > 3
        CSTEP(TOFF(3))
#endif
#else
        for (int ty = 0; ty < th; ++ty)
            for (int tx = 0; tx < tw; ++tx) CSTEP(ty * ROW + tx)
#endif
        bc += CS;
    }
#else
#pragma unroll
    for (int i = 0; i < MR; ++i)
#pragma unroll
        for (int j = 0; j < NV; ++j) acc[i][j] = (vtype)(0.0f);
    for (int c = 0; c < C; ++c) {
#pragma unroll
        for (int u = 0; u < th * tw; ++u) {
            vtype bv[NV];
#pragma unroll
            for (int j = 0; j < NV; ++j) bv[j] = VLOAD(bc + (u / tw) * ROW + u % tw + j * VW);
#pragma unroll
            for (int i = 0; i < MR; ++i) {
                const vtype av = (vtype)(a[i]);
#pragma unroll
                for (int j = 0; j < NV; ++j) acc[i][j] = fma(av, bv[j], acc[i][j]);
            }
            a += MR;
        }
        bc += CS;
    }
#endif

#if UNROLL
    FOR_ROWS(CSTORE_ROW)
#else
#pragma unroll
    for (int i = 0; i < MR; ++i) {
        const int m = mp * MR + i;
        if (m >= M) break;
        const float s = scale[m], t = shift[m];
        __global float* row = y + y0 + (size_t)m * y_plane;
        __global const float* rrow = res + res_off + phase_y + (size_t)m * y_plane;
#pragma unroll
        for (int j = 0; j < NV; ++j) CSTORE_VEC(acc[i][j], j);
    }
#endif
}

#elif KWG == 0
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

#else  // KWG > 0

// gemm_local: the GPU-shaped variant. Same packed operands (im2col_packed and pack_a are unchanged), same register
// micro-kernel and epilogue; the operands reach the micro-kernel through __local memory.
//
// A work-group of L0 x L1 work-items computes an (L0*MR) x (L1*NR) block of C: work-item (l0, l1) owns the tile
// of A panel mp = group0*L0 + l0 and B panel np = group1*L1 + l1. Per chunk of KWG packed k rows:
//   1. copy: the block's L0 A-panel chunks (KWG*MR contiguous floats of Ap each) and L1 B-panel chunks (KWG*NR
//      each) go to __local memory. The flat work-item index flat = l1*L0 + l0 walks each span, so consecutive
//      work-items read consecutive floats (coalesced). Local memory holds the chunk k-major, al[kk][l0*MR + r]
//      and bl[kk][l1*NR + n], so at a k step the work-items of a warp read neighbouring addresses or the same one
//      (a broadcast), not addresses KWG*MR apart (one bank);
//   2. barrier; every work-item runs the micro-kernel over the chunk from local memory; barrier.
// Edges: slots of panels past the last one (edge work-groups) and of rows k >= Kpad (the last chunk when KWG does
// not divide Kpad) are zero-filled, and the micro-kernel stops at the last real row of the chunk. No work-item
// returns early: every one reaches every barrier (a return before the loop would be barrier divergence, undefined
// behaviour that oclgrind reports); only the epilogue masks m >= M, n >= N.
// Local memory: (L0*MR + L1*NR) * KWG floats; the host refuses a knob set beyond CL_DEVICE_LOCAL_MEM_SIZE.
// Loop iterations per work-item (llvmpipe's 65,535 limit, above) with UNROLL=1:
//   ceil(Kpad/KWG) * (1 + ceil(A_PER/A_CU) + ceil(B_PER/B_CU)) + Kpad/KU + the epilogue's (as gemm_packed),
// A_PER = ceil(KWG*MR/L1), B_PER = ceil(KWG*NR/L0) copies per work-item and chunk, A_CU, B_CU = up to 16 of
// them unrolled per iteration. K = 8192 with 4,4,1,1,16,16,1,16: 512 * 3 + 8192 = 9,728 (gemm_packed: 8,192);
// with 8,8,1,1,4,4,1,32: 256 * (1 + 4 + 4) + 8192 = 10,496.
#ifndef L0
#define L0 1
#endif
#ifndef L1
#define L1 1
#endif
#if KWG % KU != 0
#error "KWG must be a multiple of KU"
#endif
#define WG_ITEMS (L0 * L1)
#define A_SPAN (KWG * MR)        // one A panel's chunk: contiguous in Ap
#define B_SPAN (KWG * NR)
#define A_BLOCK (L0 * A_SPAN)    // the work-group's chunk of A, in floats of local memory
#define B_BLOCK (L1 * B_SPAN)
#define A_PER ((A_BLOCK + WG_ITEMS - 1) / WG_ITEMS)  // copies per work-item and chunk
#define B_PER ((B_BLOCK + WG_ITEMS - 1) / WG_ITEMS)
#if A_PER >= 16
#define A_CU 16
#elif A_PER >= 8
#define A_CU 8
#elif A_PER >= 4
#define A_CU 4
#elif A_PER >= 2
#define A_CU 2
#else
#define A_CU 1
#endif
#if B_PER >= 16
#define B_CU 16
#elif B_PER >= 8
#define B_CU 8
#elif B_PER >= 4
#define B_CU 4
#elif B_PER >= 2
#define B_CU 2
#else
#define B_CU 1
#endif
// A copy index can pass the block only where the work-items do not divide it or the unrolled groups overshoot.
#if (A_BLOCK % WG_ITEMS) || (A_PER % A_CU)
#define A_IN(f) ((f) < A_BLOCK)
#else
#define A_IN(f) 1
#endif
#if (B_BLOCK % WG_ITEMS) || (B_PER % B_CU)
#define B_IN(f) ((f) < B_BLOCK)
#else
#define B_IN(f) 1
#endif

// Copy number x of this work-item: flat index f = flat + x*WG_ITEMS into the block, panel i = f / SPAN, offset
// w = f % SPAN = kk*MR + r inside the panel's chunk (contiguous in global memory), stored k-major in local memory.
#define COPY_A(x)                                                                                      \
    {                                                                                                  \
        const int f = flat + (x) * WG_ITEMS;                                                              \
        if (A_IN(f)) {                                                                                 \
            const int i = f / A_SPAN, w = f - i * A_SPAN, kk = w / MR;                                 \
            float v = 0.0f;                                                                            \
            if (mp0 + i < a_panels && k0 + kk < Kpad) v = ap[((size_t)(mp0 + i) * Kpad + k0) * MR + w]; \
            al[kk * (L0 * MR) + i * MR + (w - kk * MR)] = v;                                           \
        }                                                                                              \
    }
#define COPY_B(x)                                                                                        \
    {                                                                                                    \
        const int f = flat + (x) * WG_ITEMS;                                                                \
        if (B_IN(f)) {                                                                                   \
            const int i = f / B_SPAN, w = f - i * B_SPAN, kk = w / NR;                                   \
            float v = 0.0f;                                                                              \
            if (np0 + i < b_panels && k0 + kk < Kpad) v = bsrc[((size_t)(np0 + i) * Kpad + k0) * NR + w]; \
            bl[kk * (L1 * NR) + i * NR + (w - kk * NR)] = v;                                             \
        }                                                                                                \
    }

#if UNROLL
#define COPY_A_AT(u) COPY_A(x + (u))
#define COPY_B_AT(u) COPY_B(x + (u))
// One k step from local memory: rows of the chunk are L0*MR (A) and L1*NR (B) floats apart.
#define LLOAD_B(u, j) bv[j] = VLOAD(b + (u) * (L1 * NR) + (j) * VW);
#define LSTEP(u) { vtype bv[NV]; FOR_VECS(LLOAD_B, u) FOR_ROWS(FMA_ROW) a += L0 * MR; }
#endif

__kernel __attribute__((reqd_work_group_size(L0, L1, 1)))
void gemm_local(const int M, const int N, const int Kpad,
                __global const float* restrict ap, __global const float* restrict bp, const int b_off,
                __global float* restrict c, const int c_off, const int ldc,
                __global const float* restrict scale, __global const float* restrict shift,
                const int act, const float alpha) {
    __local float al[A_BLOCK];  // al[kk * (L0*MR) + l0*MR + r]
    __local float bl[B_BLOCK];  // bl[kk * (L1*NR) + l1*NR + n]
    const int l0 = get_local_id(0), l1 = get_local_id(1);
    const int flat = l1 * L0 + l0;  // consecutive work-items (local id 0 fastest) copy consecutive floats
    const int mp = get_global_id(0), np = get_global_id(1);  // this work-item's panels: may be past the last one
    const int mp0 = get_group_id(0) * L0, np0 = get_group_id(1) * L1;
    const int a_panels = (M + MR - 1) / MR, b_panels = (N + NR - 1) / NR;
    __global const float* bsrc = bp + b_off;

    vtype acc[MR][NV];
#if UNROLL
    FOR_ROWS(ZERO_ROW)
#else
#pragma unroll
    for (int i = 0; i < MR; ++i)
#pragma unroll
        for (int j = 0; j < NV; ++j) acc[i][j] = (vtype)(0.0f);
#endif

    for (int k0 = 0; k0 < Kpad; k0 += KWG) {
#if UNROLL
        for (int x = 0; x < A_PER; x += A_CU) { NGI_CAT(REP_K, A_CU)(COPY_A_AT) }
        for (int x = 0; x < B_PER; x += B_CU) { NGI_CAT(REP_K, B_CU)(COPY_B_AT) }
#else
#pragma unroll
        for (int x = 0; x < A_PER; ++x) COPY_A(x)
#pragma unroll
        for (int x = 0; x < B_PER; ++x) COPY_B(x)
#endif
        barrier(CLK_LOCAL_MEM_FENCE);
        const int rows = min(KWG, Kpad - k0);  // a multiple of KU (so are KWG and Kpad); less in a partial chunk
        __local const float* a = al + l0 * MR;
        __local const float* b = bl + l1 * NR;
#if UNROLL
        for (int kk = 0; kk < rows; kk += KU) {
            FOR_STEPS(LSTEP)
            b += KU * (L1 * NR);
        }
#else
        for (int kk = 0; kk < rows; kk += KU) {
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
                a += L0 * MR;
                b += L1 * NR;
            }
        }
#endif
        barrier(CLK_LOCAL_MEM_FENCE);  // the next chunk's copy overwrites what this one read
    }

    // Epilogue, as gemm_packed's: work-items past the last panel store nothing.
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
#endif  // KWG

// col2im in gather form for transposed convolution (no atomics), with the fused epilogue.
//
// cols is the GEMM result: (Cout*KH*KW) x (IH*IW), row m = (co*KH + ky)*KW + kx, row stride ldc.
// Output pixel (oy, ox) of a transposed conv receives cols[(co,ky,kx)][iy*IW+ix] for every tap with
// oy = iy*stride - pad + ky (same for x). We gather those taps, then y = act(sum*scale[co] + shift[co]).
//
// The taps of one output pixel are ky = (oy + PAD) % STRIDE + i*STRIDE, i < ceil(KH/STRIDE): the trip count is
// the same for every work-item (only the start differs), and out-of-range taps are masked, so PoCL vectorizes
// across work-items and GPUs do not diverge. The geometry is compile-time (-DKH -DKW -DSTRIDE -DPAD): division
// by a constant stride becomes a shift, which vectorizes (x86 has no SIMD integer division), and the tap loops
// unroll. One program per geometry; a U-Net has one.

__kernel void col2im_gather(__global const float* restrict cols, const int cols_off, const int ldc,
                            const int Cout, const int IH, const int IW, const int OH, const int OW,
                            __global float* restrict y, const int y_off,
                            __global const float* restrict scale, __global const float* restrict shift,
                            const int act, const float alpha) {
    const int ox = get_global_id(0);
    const int oy = get_global_id(1);
    const int co = get_global_id(2);
    if (ox >= OW || oy >= OH || co >= Cout) return;
    const int ty = oy + PAD, tx = ox + PAD;
    __global const float* base = cols + cols_off + (size_t)co * KH * KW * ldc;
    float sum = 0.0f;
#pragma unroll
    for (int i = 0; i < (KH + STRIDE - 1) / STRIDE; ++i) {
        const int ky = ty % STRIDE + i * STRIDE;
        const int iy = (ty - ky) / STRIDE;  // exact: ty - ky is a multiple of STRIDE
        const int row_ok = ky < KH && ty >= ky && iy < IH;
#pragma unroll
        for (int j = 0; j < (KW + STRIDE - 1) / STRIDE; ++j) {
            const int kx = tx % STRIDE + j * STRIDE;
            const int ix = (tx - kx) / STRIDE;
            const int ok = row_ok && kx < KW && tx >= kx && ix < IW;
            const float v = base[ok ? (size_t)(ky * KW + kx) * ldc + iy * IW + ix : 0];
            sum += ok ? v : 0.0f;
        }
    }
    y[y_off + ((size_t)co * OH + oy) * OW + ox] = ngi_activate(sum * scale[co] + shift[co], act, alpha);
}

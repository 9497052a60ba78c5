// col2im in gather form for transposed convolution (no atomics), with the fused epilogue.
//
// cols is the GEMM result: (Cout*KH*KW) x (IH*IW), row m = (co*KH + ky)*KW + kx, row stride ldc.
// Output pixel (oy, ox) of a transposed conv receives cols[(co,ky,kx)][iy*IW+ix] for every tap with
// oy = iy*stride - pad + ky (same for x). We gather those taps, then y = act(sum*scale[co] + shift[co]).

__kernel void col2im_gather(__global const float* restrict cols, const int cols_off, const int ldc,
                            const int Cout, const int IH, const int IW,
                            const int KH, const int KW, const int stride, const int pad,
                            const int OH, const int OW,
                            __global float* restrict y, const int y_off,
                            __global const float* restrict scale, __global const float* restrict shift,
                            const int act, const float alpha) {
    const int ox = get_global_id(0);
    const int oy = get_global_id(1);
    const int co = get_global_id(2);
    if (ox >= OW || oy >= OH || co >= Cout) return;
    float sum = 0.0f;
    // Taps ky with (oy + pad - ky) divisible by stride, and iy = (oy + pad - ky) / stride inside [0, IH).
    const int ty = oy + pad, tx = ox + pad;
    for (int ky = ty % stride; ky < KH; ky += stride) {
        const int iy = (ty - ky) / stride;
        if (iy < 0) break;
        if (iy >= IH) continue;
        for (int kx = tx % stride; kx < KW; kx += stride) {
            const int ix = (tx - kx) / stride;
            if (ix < 0) break;
            if (ix >= IW) continue;
            sum += cols[cols_off + (size_t)((co * KH + ky) * KW + kx) * ldc + iy * IW + ix];
        }
    }
    y[y_off + ((size_t)co * OH + oy) * OW + ox] = ngi_activate(sum * scale[co] + shift[co], act, alpha);
}

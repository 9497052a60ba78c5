// MergeToGlobalView (thesis eq. 4.1) and front-view extraction, as one gather through a lookup table.
// The host builds the table once per face size (host/src/pipeline/global_view.cpp): for every output pixel
// four source texel indices and four bilinear weights. Copied pixels carry weights (1, 0, 0, 0).

// dst[c * dst_plane + p] = sum_k w[p].k * src[c * src_plane + idx[p].k] for every channel c < channels.
// One work-item per output pixel loops over the channels, so each table entry is read once per launch.
// Zero-weight taps are skipped, not multiplied: a copy is then bit-exact (1 * v, even for -0).
// The host builds the table with every index inside the source (checked there), so no clamping here.
__kernel void lut_gather(__global const float* restrict src, const int src_plane,
                         __global const int4* restrict idx, __global const float4* restrict w, const int npix,
                         const int channels, __global float* restrict dst, const int dst_plane) {
    const int p = get_global_id(0);
    if (p >= npix) return;
    const int4 i = idx[p];
    const float4 k = w[p];
    for (int c = 0; c < channels; ++c) {
        __global const float* s = src + c * src_plane;
        float acc = k.s0 * s[i.s0];
        if (k.s1 != 0.0f) acc += k.s1 * s[i.s1];
        if (k.s2 != 0.0f) acc += k.s2 * s[i.s2];
        if (k.s3 != 0.0f) acc += k.s3 * s[i.s3];
        dst[c * dst_plane + p] = acc;
    }
}

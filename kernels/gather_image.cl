// Engine-shaped inputs (ngi/image_desc.hpp): one application image (any of the formats, strides and row orders an
// image descriptor describes) gathered into the pipeline's float32 frame planes, where preprocessing reads it.
// Values are decoded, then scaled and biased; nothing is sanitized here (NaN and Inf from F32 or F16 images pass
// through to the preprocessing, which replaces and counts them per feature: docs/CONVENTIONS.md section 6).

// Format codes: the host passes ngi::PixelFormat's values as build options (host/src/pipeline/image_desc.cpp), so
// they are defined once.
#if !defined(FMT_F32) || !defined(FMT_F16) || !defined(FMT_U8_UNORM) || !defined(FMT_U8_SRGB)
#error "gather_image.cl needs -DFMT_F32 -DFMT_F16 -DFMT_U8_UNORM -DFMT_U8_SRGB (ngi::PixelFormat)"
#endif

// Launch: 1-D over n * n pixels (rounded up to the local size), local 64. Byte offsets are 64-bit (ulong: size_t is
// not a legal kernel argument type), so an image anywhere in a large application buffer is addressed exactly.
// src: the image's memory from byte 0; offset: the first stored row's pixel 0; bottom_up: stored row 0 is the
// image's bottom row. dst: float planes; channel c of pixel p goes to dst[dst_offset + c * dst_channel_stride + p].
// The host checked alignment (offset and strides are multiples of the format's size) and bounds. srgb_table: the
// linear value of each of the 256 U8 sRGB codes (the sRGB EOTF, IEC 61966-2-1, the inverse of compose.cl's tone-map
// OETF), computed by the host in double (ops/gather_image.cpp says why a table).
__kernel void gather_image(__global const uchar* restrict src, const ulong offset, const ulong pixel_stride,
                           const ulong row_stride, const ulong channel_stride, const int format,
                           const int channels, const int n, const int bottom_up, const float scale,
                           const float bias, __constant float* restrict srgb_table, __global float* restrict dst,
                           const int dst_offset,
                           const int dst_channel_stride) {
    const int p = get_global_id(0);
    if (p >= n * n) return;
    const int row = p / n, col = p - row * n;
    const int stored_row = bottom_up ? n - 1 - row : row;
    const ulong at = offset + (ulong)stored_row * row_stride + (ulong)col * pixel_stride;
    for (int c = 0; c < channels; ++c) {
        const ulong byte = at + (ulong)c * channel_stride;
        float v;
        if (format == FMT_F32) v = *(__global const float*)(src + byte);
        else if (format == FMT_F16) v = vload_half(0, (__global const half*)(src + byte));
        else if (format == FMT_U8_SRGB) v = srgb_table[src[byte]];
        else v = (float)src[byte] * (1.0f / 255.0f);
        dst[dst_offset + c * dst_channel_stride + p] = v * scale + bias;
    }
}

// Engine-shaped inputs (ngi/image_desc.hpp): one application image (any of the formats, strides, row orders and
// encodings an image descriptor describes) gathered into the pipeline's float32 frame planes, where preprocessing
// reads it. Values are decoded, then scaled and biased, then (normals, depth) turned from the engine's encoding into
// the frame's: unit world-space normals, planar depth in metres. Nothing is sanitized here (NaN and Inf from F32, F16
// or R11G11B10F images pass through to the preprocessing, which replaces and counts them per feature:
// docs/CONVENTIONS.md section 6).

// Codes: the host passes ngi::PixelFormat's, NormalEncoding's and DepthEncoding's values and the tracer's sky depth as
// build options (host/src/ops/gather_image.cpp), so they are defined once.
#if !defined(FMT_F32) || !defined(FMT_F16) || !defined(FMT_U8_UNORM) || !defined(FMT_U8_SRGB) || \
    !defined(FMT_U16_UNORM) || !defined(FMT_S16_SNORM) || !defined(FMT_R11G11B10F) || !defined(FMT_RGB10A2_UNORM) || \
    !defined(NORMAL_OCTAHEDRAL) || !defined(DEPTH_PERSPECTIVE) || !defined(SKY_DEPTH)
#error "gather_image.cl needs the -DFMT_* codes (ngi::PixelFormat), NORMAL_OCTAHEDRAL, DEPTH_PERSPECTIVE and SKY_DEPTH"
#endif

// An unsigned small float of a packed R11G11B10F word: 5 exponent bits (bias 15) above `mbits` mantissa bits, no sign
// (the GL / D3D / Vulkan B10G11R11_UFLOAT layout). Exponent 31: Inf (mantissa 0) or NaN.
static inline float ufloat_small(const uint bits, const int mbits) {
    const uint e = bits >> mbits, m = bits & ((1u << mbits) - 1u);
    const float frac = (float)m / (float)(1u << mbits);
    if (e == 0u) return ldexp(frac, -14);
    if (e == 31u) return m ? NAN : INFINITY;
    return ldexp(1.0f + frac, (int)e - 15);
}

// Channel c of one stored pixel whose channel c starts at byte `byte` (packed formats: the pixel's word is at byte
// `word`).
static inline float decode(__global const uchar* src, const ulong byte, const ulong word, const int c, const int format,
                           __constant float* srgb_table) {
    if (format == FMT_F32) return *(__global const float*)(src + byte);
    if (format == FMT_F16) return vload_half(0, (__global const half*)(src + byte));
    if (format == FMT_U8_SRGB) return srgb_table[src[byte]];
    if (format == FMT_U8_UNORM) return (float)src[byte] * (1.0f / 255.0f);
    if (format == FMT_U16_UNORM) return (float)*(__global const ushort*)(src + byte) * (1.0f / 65535.0f);
    // SNORM: -32768 and -32767 both mean -1 (the GL, D3D and Vulkan rule).
    if (format == FMT_S16_SNORM) return fmax((float)*(__global const short*)(src + byte) * (1.0f / 32767.0f), -1.0f);
    const uint w = *(__global const uint*)(src + word);
    if (format == FMT_R11G11B10F)  // R bits 0-10, G 11-21, B 22-31
        return c == 0 ? ufloat_small(w & 0x7ffu, 6) : c == 1 ? ufloat_small((w >> 11) & 0x7ffu, 6)
                                                            : ufloat_small(w >> 22, 5);
    // FMT_RGB10A2_UNORM: R bits 0-9, G 10-19, B 20-29, A 30-31
    return c < 3 ? (float)((w >> (10 * c)) & 0x3ffu) * (1.0f / 1023.0f) : (float)(w >> 30) * (1.0f / 3.0f);
}

// Launch: 1-D over n * n pixels (rounded up to the local size), local 64. Byte offsets are 64-bit (ulong: size_t is
// not a legal kernel argument type), so an image anywhere in a large application buffer is addressed exactly.
// src: the image's memory from byte 0; offset: the first stored row's pixel 0; bottom_up: stored row 0 is the
// image's bottom row. dst: float planes; channel c of pixel p goes to dst[dst_offset + c * dst_channel_stride + p].
// The host checked alignment (offset and strides are multiples of the format's value size) and bounds. srgb_table:
// the linear value of each of the 256 U8 sRGB codes (the sRGB EOTF, IEC 61966-2-1, the inverse of compose.cl's
// tone-map OETF), computed by the host in double (ops/gather_image.cpp says why a table).
// channels: what is read (a feature's 3, or 1 for depth; an octahedral normal reads 2 and writes 3).
// normal_encoding: NORMAL_OCTAHEDRAL decodes (x, y) in [-1, 1] (after scale and bias) to a unit vector; with rotate,
// the 3 x 3 matrix m (row r, column c: m<r><c>) then takes the normal from view to world space. The octahedral map
// has no code for "no surface": with sky_from >= 0 (the face's depth, gathered before, at dst[sky_from + p]) a pixel
// whose depth is SKY_DEPTH or beyond (or NaN) gets the zero vector, as the tracer writes there.
// depth_encoding: DEPTH_PERSPECTIVE reads window depth d of a perspective projection with near and far planes (far
// = +Inf: an infinite far plane), reversed or not, and writes planar depth z in metres; d at or past the far plane
// (the cleared value) is "no surface", written as SKY_DEPTH like the tracer's escaped rays.
__kernel void gather_image(__global const uchar* restrict src, const ulong offset, const ulong pixel_stride,
                           const ulong row_stride, const ulong channel_stride, const int format,
                           const int channels, const int n, const int bottom_up, const float scale,
                           const float bias, __constant float* restrict srgb_table, __global float* restrict dst,
                           const int dst_offset, const int dst_channel_stride, const int normal_encoding,
                           const int rotate, const float m00, const float m01, const float m02, const float m10,
                           const float m11, const float m12, const float m20, const float m21, const float m22,
                           const int depth_encoding, const float near_m, const float far_m, const int reversed_z,
                           const int sky_from) {
    const int p = get_global_id(0);
    if (p >= n * n) return;
    const int row = p / n, col = p - row * n;
    const int stored_row = bottom_up ? n - 1 - row : row;
    const ulong at = offset + (ulong)stored_row * row_stride + (ulong)col * pixel_stride;
    if (depth_encoding == DEPTH_PERSPECTIVE) {
        const float x = decode(src, at, at, 0, format, srgb_table) * scale + bias;
        const float r = isinf(far_m) ? 0.0f : near_m / far_m;
        float z;
        if (isnan(x)) z = x;  // passed on: the preprocessing replaces and counts it
        else if (reversed_z)  // x = (near / z - r) / (1 - r), r = near / far: read without forming 1 - x, so
            z = x <= 0.0f ? SKY_DEPTH : near_m / (x * (1.0f - r) + r);  // reversed Z keeps its precision far away
        else  // x = (1 - near / z) / (1 - r)
            z = x >= 1.0f ? SKY_DEPTH : near_m / (1.0f - x * (1.0f - r));
        dst[dst_offset + p] = z;
        return;
    }
    float v[4];
    const int read = normal_encoding == NORMAL_OCTAHEDRAL ? 2 : channels;
    for (int c = 0; c < read; ++c)
        v[c] = decode(src, at + (ulong)c * channel_stride, at, c, format, srgb_table) * scale + bias;
    if (normal_encoding == NORMAL_OCTAHEDRAL && sky_from >= 0 && !(dst[sky_from + p] < SKY_DEPTH)) {
        for (int c = 0; c < 3; ++c) dst[dst_offset + c * dst_channel_stride + p] = 0.0f;  // no surface: no normal
        return;
    }
    if (normal_encoding == NORMAL_OCTAHEDRAL) {  // Cigolle et al. 2014, "A survey of efficient representations..."
        float3 u = (float3)(v[0], v[1], 1.0f - fabs(v[0]) - fabs(v[1]));
        if (u.z < 0.0f) {
            const float ux = u.x;
            u.x = (1.0f - fabs(u.y)) * (ux >= 0.0f ? 1.0f : -1.0f);
            u.y = (1.0f - fabs(ux)) * (u.y >= 0.0f ? 1.0f : -1.0f);
        }
        u = normalize(u);
        v[0] = u.x;
        v[1] = u.y;
        v[2] = u.z;
    }
    if (rotate) {  // a view-space normal (3 channels here, checked by the host) to world space
        const float x = v[0], y = v[1], z = v[2];
        v[0] = m00 * x + m01 * y + m02 * z;
        v[1] = m10 * x + m11 * y + m12 * z;
        v[2] = m20 * x + m21 * y + m22 * z;
    }
    const int written = normal_encoding == NORMAL_OCTAHEDRAL ? 3 : channels;
    for (int c = 0; c < written; ++c) dst[dst_offset + c * dst_channel_stride + p] = v[c];
}

// Naive reference of an application image's storage (ngi/image_desc.hpp; what kernels/gather_image.cl reads): a
// layout's byte addressing, each pixel format's encoding and decoding (packed formats from the GL spec's bit
// layouts), the octahedral normal map, perspective depth, and an image stored under a layout with noise in the bytes
// it does not cover. Written from the descriptor's documentation, sharing no code with the kernel.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "base/half.hpp"
#include "ngi/image.hpp"
#include "ngi/image_desc.hpp"
#include "ops/gather_image.hpp"

namespace ngi::test {

// binary32 -> binary16 by truncation of the mantissa (normal range and zero only: the tests' values). The tests
// decode the same bits on both sides, so the rounding mode does not matter.
inline std::uint16_t to_half(float v) {
    std::uint32_t b;
    std::memcpy(&b, &v, 4);
    const std::uint32_t sign = (b >> 16) & 0x8000u;
    const int exp = int((b >> 23) & 0xff) - 127 + 15;
    if (exp <= 0) return std::uint16_t(sign);
    if (exp >= 31) return std::uint16_t(sign | 0x7c00u);
    return std::uint16_t(sign | std::uint32_t(exp) << 10 | ((b >> 13) & 0x3ffu));
}

// The sRGB EOTF (IEC 61966-2-1) in double; the kernel reads the same values, rounded once, from the host's table.
inline double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// An unsigned small float (no sign bit): `exp_bits` exponent bits with bias 2^(exp_bits-1) - 1 above `man_bits`
// mantissa bits (OpenGL 4.6 section 2.3.4.4, "Unsigned 11-Bit / 10-Bit Floating-Point Numbers").
inline float small_ufloat(std::uint32_t bits, int man_bits) {
    const std::uint32_t e = bits >> man_bits, m = bits & ((1u << man_bits) - 1u);
    if (e == 31) return m ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    if (e == 0) return float(std::ldexp(double(m), -14 - man_bits));           // denormal: m / 2^man x 2^-14
    return float(std::ldexp(double((1u << man_bits) + m), int(e) - 15 - man_bits));  // (1 + m / 2^man) x 2^(e - 15)
}
// The nearest small unsigned float to v >= 0 below its largest finite value (round to nearest via double search).
inline std::uint32_t to_small_ufloat(float v, int man_bits) {
    std::uint32_t best = 0;
    double err = 1e300;
    for (std::uint32_t b = 0; b < (31u << man_bits); ++b) {
        const double d = std::abs(double(small_ufloat(b, man_bits)) - double(v));
        if (d < err) err = d, best = b;
    }
    return best;
}
inline std::uint32_t word_at(const std::vector<unsigned char>& mem, std::size_t byte) {
    std::uint32_t w;
    std::memcpy(&w, &mem[byte], 4);
    return w;
}

// Channel c of one stored value at `byte` of `mem` decoded as the kernel does (before scale and bias). For a packed
// format `byte` is the pixel's word and c picks the field.
inline float decode(const std::vector<unsigned char>& mem, std::size_t byte, PixelFormat f, int c = 0) {
    switch (f) {
        case PixelFormat::F32: { float v; std::memcpy(&v, &mem[byte], 4); return v; }
        case PixelFormat::F16: { std::uint16_t h; std::memcpy(&h, &mem[byte], 2); return detail::half_to_float(h); }
        case PixelFormat::U8Unorm: return float(mem[byte]) * (1.0f / 255.0f);
        case PixelFormat::U8Srgb: return float(srgb_to_linear(mem[byte] / 255.0));
        case PixelFormat::U16Unorm: { std::uint16_t u; std::memcpy(&u, &mem[byte], 2); return float(u / 65535.0); }
        case PixelFormat::S16Snorm: {
            std::int16_t i;
            std::memcpy(&i, &mem[byte], 2);
            return std::max(float(i / 32767.0), -1.0f);
        }
        case PixelFormat::R11G11B10F: {
            const std::uint32_t w = word_at(mem, byte);
            return c == 0 ? small_ufloat(w & 2047u, 6) : c == 1 ? small_ufloat((w >> 11) & 2047u, 6)
                                                                : small_ufloat(w >> 22, 5);
        }
        case PixelFormat::RGB10A2Unorm: {
            const std::uint32_t w = word_at(mem, byte);
            return c == 3 ? float((w >> 30) / 3.0) : float(((w >> (10 * c)) & 1023u) / 1023.0);
        }
    }
    return 0;
}

// Writes value v as format f at `byte` (a packed format: into field c of the word there).
inline void encode(std::vector<unsigned char>& mem, std::size_t byte, PixelFormat f, float v, int c = 0) {
    switch (f) {
        case PixelFormat::F32: std::memcpy(&mem[byte], &v, 4); break;
        case PixelFormat::F16: { const std::uint16_t h = to_half(v); std::memcpy(&mem[byte], &h, 2); break; }
        case PixelFormat::U16Unorm: {
            const auto u = std::uint16_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 65535.0f));
            std::memcpy(&mem[byte], &u, 2);
            break;
        }
        case PixelFormat::S16Snorm: {
            const auto i = std::int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
            std::memcpy(&mem[byte], &i, 2);
            break;
        }
        case PixelFormat::R11G11B10F:
        case PixelFormat::RGB10A2Unorm: {
            std::uint32_t w = word_at(mem, byte);
            const int shift = f == PixelFormat::R11G11B10F ? 11 * c : 10 * c;
            const int width = f == PixelFormat::R11G11B10F ? (c == 2 ? 10 : 11) : (c == 3 ? 2 : 10);
            const std::uint32_t field =
                f == PixelFormat::R11G11B10F
                    ? to_small_ufloat(std::max(v, 0.0f), c == 2 ? 5 : 6)
                    : std::uint32_t(std::lround(std::clamp(v, 0.0f, 1.0f) * double((1u << width) - 1u)));
            const std::uint32_t mask = ((1u << width) - 1u) << shift;
            w = (w & ~mask) | (field << shift);
            std::memcpy(&mem[byte], &w, 4);
            break;
        }
        default: mem[byte] = std::uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); break;
    }
}

// The octahedral map of a unit vector and its inverse (Cigolle et al. 2014, listings 1 and 2), in double.
inline glm::dvec2 octahedral_encode(glm::dvec3 n) {
    n /= std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
    if (n.z >= 0) return {n.x, n.y};
    return {(1 - std::abs(n.y)) * (n.x >= 0 ? 1 : -1), (1 - std::abs(n.x)) * (n.y >= 0 ? 1 : -1)};
}
inline glm::dvec3 octahedral_decode(glm::dvec2 e) {
    glm::dvec3 v(e.x, e.y, 1 - std::abs(e.x) - std::abs(e.y));
    if (v.z < 0) v = {(1 - std::abs(e.y)) * (e.x >= 0 ? 1 : -1), (1 - std::abs(e.x)) * (e.y >= 0 ? 1 : -1), v.z};
    return glm::normalize(v);
}

// Planar depth (metres) from window depth d of a perspective projection (GL with glDepthRange(0, 1), D3D, Vulkan):
// standard d = far / (far - near) (1 - near / z), reversed d = near (far - z) / (z (far - near)); infinite far plane:
// d = 1 - near / z, reversed near / z. At or past the far plane: no surface (kNoSurfaceDepth). In double.
inline double perspective_depth(double d, double near_m, double far_m, bool reversed) {
    if (reversed) d = 1 - d;
    if (std::isnan(d)) return d;
    if (d >= 1) return detail::kNoSurfaceDepth;
    return std::isinf(far_m) ? near_m / (1 - d) : near_m * far_m / (far_m - d * (far_m - near_m));
}
// The window depth of planar depth z (the inverse of perspective_depth below the far plane).
inline double window_depth(double z, double near_m, double far_m, bool reversed) {
    const double d = std::isinf(far_m) ? 1 - near_m / z : far_m / (far_m - near_m) * (1 - near_m / z);
    return reversed ? 1 - d : d;
}

struct Layout {
    PixelFormat format;
    int channels;
    std::size_t offset, pixel_stride, row_stride, channel_stride;
    bool bottom_up;
    float scale, bias;
    NormalEncoding normal_encoding = NormalEncoding::Xyz;
    glm::mat3 normal_to_world{1.0f};
    DepthEncoding depth_encoding = DepthEncoding::Linear;
    float near_m = 0.0f, far_m = 0.0f;
    bool reversed_z = false;
};

// How a test hands a layout to the op (ops/gather_image.hpp): the image's bytes start base_offset bytes into memory.
inline detail::GatherSource gather_source(const Layout& l, cl_mem memory, std::size_t base_offset = 0) {
    detail::GatherSource gs;
    gs.memory = memory;
    gs.offset = base_offset + l.offset;
    gs.pixel_stride = l.pixel_stride;
    gs.row_stride = l.row_stride;
    gs.channel_stride = l.channel_stride;
    gs.format = l.format;
    gs.bottom_up = l.bottom_up;
    gs.scale = l.scale;
    gs.bias = l.bias;
    gs.normal_encoding = l.normal_encoding;
    gs.normal_to_world = l.normal_to_world;
    gs.depth_encoding = l.depth_encoding;
    gs.near_m = l.near_m;
    gs.far_m = l.far_m;
    gs.reversed_z = l.reversed_z;
    return gs;
}

// The byte of channel c of image pixel (row, col) under a layout (row 0 = top).
inline std::size_t byte_of(const Layout& l, int n, int row, int col, int c) {
    const int stored = l.bottom_up ? n - 1 - row : row;
    return l.offset + std::size_t(stored) * l.row_stride + std::size_t(col) * l.pixel_stride +
           std::size_t(c) * l.channel_stride;
}

// An image of `images` (n x n x channels, planar float, row 0 = top) stored under a layout into fresh memory, with
// noise in every byte the layout does not cover (padding must never be read).
inline std::vector<unsigned char> store(const Layout& l, int n, const Image& image, std::mt19937& rng) {
    const std::size_t elem = pixel_format_bytes(l.format);
    const std::size_t end = byte_of(l, n, l.bottom_up ? 0 : n - 1, n - 1, l.channels - 1) + elem;
    std::vector<unsigned char> mem(end + 13);
    for (auto& b : mem) b = std::uint8_t(rng());
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col)
            for (int c = 0; c < l.channels; ++c)  // packed formats: channel_stride 0, c picks the word's field
                encode(mem, byte_of(l, n, row, col, c), l.format,
                       c < image.channels ? image.data[(std::size_t(c) * n + row) * n + col] : 0.25f, c);
    return mem;
}

}  // namespace ngi::test

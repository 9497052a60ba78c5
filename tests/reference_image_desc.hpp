// Naive reference of an application image's storage (ngi/image_desc.hpp; what kernels/gather_image.cl reads): a
// layout's byte addressing, each pixel format's encoding and decoding, and an image stored under a layout with
// noise in the bytes it does not cover. Written from the descriptor's documentation, sharing no code with the kernel.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
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

// One stored value at `byte` of `mem` decoded as the kernel does (before scale and bias).
inline float decode(const std::vector<unsigned char>& mem, std::size_t byte, PixelFormat f) {
    switch (f) {
        case PixelFormat::F32: { float v; std::memcpy(&v, &mem[byte], 4); return v; }
        case PixelFormat::F16: { std::uint16_t h; std::memcpy(&h, &mem[byte], 2); return detail::half_to_float(h); }
        case PixelFormat::U8Unorm: return float(mem[byte]) * (1.0f / 255.0f);
        case PixelFormat::U8Srgb: return float(srgb_to_linear(mem[byte] / 255.0));
    }
    return 0;
}

// Writes value v as format f at `byte`.
inline void encode(std::vector<unsigned char>& mem, std::size_t byte, PixelFormat f, float v) {
    switch (f) {
        case PixelFormat::F32: std::memcpy(&mem[byte], &v, 4); break;
        case PixelFormat::F16: { const std::uint16_t h = to_half(v); std::memcpy(&mem[byte], &h, 2); break; }
        default: mem[byte] = std::uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); break;
    }
}

struct Layout {
    PixelFormat format;
    int channels;
    std::size_t offset, pixel_stride, row_stride, channel_stride;
    bool bottom_up;
    float scale, bias;
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
            for (int c = 0; c < l.channels; ++c)
                encode(mem, byte_of(l, n, row, col, c), l.format,
                       c < image.channels ? image.data[(std::size_t(c) * n + row) * n + col] : 0.25f);
    return mem;
}

}  // namespace ngi::test

// IEEE 754 binary16 -> binary32, in software (no fp16 hardware or compiler support assumed).
#pragma once
#include <cstdint>
#include <cstring>
#include <vector>

namespace ngi::detail {

inline float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16;
    std::uint32_t exp = (h >> 10) & 0x1f, mant = h & 0x3ffu, bits;
    if (exp == 0x1f) {
        bits = sign | 0x7f800000u | (mant << 13);  // Inf / NaN
    } else if (exp == 0) {
        if (mant == 0) {
            bits = sign;  // +-0
        } else {  // subnormal: normalize
            int e = -1;
            do { ++e; mant <<= 1; } while ((mant & 0x400u) == 0);
            bits = sign | std::uint32_t(127 - 15 - e) << 23 | (mant & 0x3ffu) << 13;
        }
    } else {
        bits = sign | (exp + 112) << 23 | mant << 13;
    }
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

// n binary16 values at src (unaligned, little-endian as safetensors and .npy store them) -> dst, through a table
// of all 65,536 values made once by half_to_float: a lookup per value instead of its branches, ~4x faster on
// the ~10 M weights of a generator file (model load is part of every `ngi lightmap` command). Returns the index of
// the first value that is Inf or NaN, or n when all are finite.
inline std::size_t halves_to_floats(const unsigned char* src, std::size_t n, float* dst) {
    static const std::vector<float> table = [] {
        std::vector<float> t(65536);
        for (std::uint32_t h = 0; h < 65536; ++h) t[h] = half_to_float(std::uint16_t(h));
        return t;
    }();
    std::size_t first_bad = n;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t h = std::uint32_t(src[2 * i]) | std::uint32_t(src[2 * i + 1]) << 8;
        dst[i] = table[h];
        if ((h & 0x7c00u) == 0x7c00u && first_bad == n) first_bad = i;  // exponent all ones: Inf or NaN
    }
    return first_bad;
}

}  // namespace ngi::detail

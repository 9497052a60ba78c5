// Sizes computed from untrusted file headers: products that must neither overflow nor exceed what the file
// can hold. Library-internal.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

namespace ngi::detail {

// Product of `dims` times `elem_bytes`, or nullopt when a dimension is negative or the product exceeds `limit`
// (checked at every step, so [2^30, 2^30, 16] cannot wrap around to a small number).
inline std::optional<std::uint64_t> checked_byte_count(const std::vector<int>& dims, std::uint64_t elem_bytes,
                                                       std::uint64_t limit) {
    std::uint64_t n = elem_bytes;
    if (n > limit) return std::nullopt;
    for (int d : dims) {
        if (d < 0 || __builtin_mul_overflow(n, std::uint64_t(d), &n) || n > limit) return std::nullopt;
    }
    return n;
}

}  // namespace ngi::detail

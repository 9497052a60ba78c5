// Deterministic random numbers for scene and camera-path generation. Library-internal.
// std::mt19937 is fully specified by the standard; the standard distributions are not (implementation-defined),
// so these helpers are our own: same seed, same scene on every platform and compiler.
#pragma once
#include <cstdint>
#include <random>
#include <vector>

namespace ngi::detail {

struct Rand {
    std::mt19937 g;
    Rand(std::uint32_t seed, std::uint32_t stream) : g(make(seed, stream)) {}
    float uniform() { return float(g() >> 8) * (1.0f / 16777216.0f); }  // [0, 1)
    float range(float a, float b) { return a + (b - a) * uniform(); }
    int irange(int lo, int hi) { return lo + int(g() % std::uint32_t(hi - lo + 1)); }  // inclusive
    bool chance(float p) { return uniform() < p; }
    template <class T>
    const T& pick(const std::vector<T>& v) { return v[g() % v.size()]; }

private:
    static std::mt19937 make(std::uint32_t seed, std::uint32_t stream) {
        std::seed_seq s{seed, stream, 0x6e6769u};
        return std::mt19937(s);
    }
};

}  // namespace ngi::detail

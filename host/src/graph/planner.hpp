// Lifetime-based memory planner (OIDN's arena planner, simplified): allocations whose lifetimes overlap get
// disjoint address ranges; the others may share. Pure function of sizes and lifetimes, so it is unit-tested alone.
#pragma once
#include <cstddef>
#include <vector>

namespace ngi::detail {

struct Allocation {
    std::size_t size = 0;  // in floats
    int first = 0;         // first step that touches it (write or read)
    int last = 0;          // last step that touches it (inclusive)
};

struct ArenaPlan {
    std::vector<std::size_t> offsets;  // per allocation, in floats, each a multiple of `alignment`
    std::size_t arena_size = 0;        // floats: the peak the arena needs
    std::size_t naive_size = 0;        // floats: what one buffer per allocation would take
};

// Largest allocations first, each at the lowest aligned offset that does not collide with an already placed
// allocation whose lifetime overlaps its own.
ArenaPlan plan_arena(const std::vector<Allocation>& allocs, std::size_t alignment = 64);

}  // namespace ngi::detail

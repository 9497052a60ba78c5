#include "graph/planner.hpp"

#include <algorithm>
#include <numeric>

namespace ngi::detail {

ArenaPlan plan_arena(const std::vector<Allocation>& allocs, std::size_t alignment) {
    ArenaPlan plan;
    plan.offsets.assign(allocs.size(), 0);
    std::vector<std::size_t> order(allocs.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return allocs[a].size > allocs[b].size; });

    auto align = [&](std::size_t x) { return (x + alignment - 1) / alignment * alignment; };
    std::vector<std::size_t> placed;
    for (std::size_t i : order) {
        const Allocation& a = allocs[i];
        plan.naive_size += align(a.size);
        // Address ranges of live-overlapping allocations, sorted by offset; take the first gap that fits.
        std::vector<std::pair<std::size_t, std::size_t>> busy;
        for (std::size_t j : placed) {
            const Allocation& b = allocs[j];
            if (a.first <= b.last && b.first <= a.last) busy.emplace_back(plan.offsets[j], plan.offsets[j] + b.size);
        }
        std::sort(busy.begin(), busy.end());
        std::size_t offset = 0;
        for (const auto& [begin, end] : busy) {
            if (offset + a.size <= begin) break;
            offset = std::max(offset, align(end));
        }
        plan.offsets[i] = offset;
        plan.arena_size = std::max(plan.arena_size, offset + a.size);
        placed.push_back(i);
    }
    return plan;
}

}  // namespace ngi::detail

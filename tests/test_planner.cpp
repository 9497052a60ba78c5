// The arena planner: no two allocations that are alive at the same step may overlap in memory.
#include <catch2/catch.hpp>
#include <random>

#include "graph/planner.hpp"

using namespace ngi::detail;

TEST_CASE("planner never overlaps live allocations and reuses dead ones", "[planner]") {
    std::mt19937 rng(11);
    for (int trial = 0; trial < 200; ++trial) {
        std::uniform_int_distribution<int> n_d(1, 30), step(0, 40), size(1, 5000);
        std::vector<Allocation> a(n_d(rng));
        for (auto& x : a) {
            int s0 = step(rng), s1 = step(rng);
            x = {std::size_t(size(rng)), std::min(s0, s1), std::max(s0, s1)};
        }
        const ArenaPlan p = plan_arena(a, 16);
        for (std::size_t i = 0; i < a.size(); ++i) {
            REQUIRE(p.offsets[i] % 16 == 0);
            REQUIRE(p.offsets[i] + a[i].size <= p.arena_size);
            for (std::size_t j = i + 1; j < a.size(); ++j) {
                const bool live_together = a[i].first <= a[j].last && a[j].first <= a[i].last;
                const bool disjoint = p.offsets[i] + a[i].size <= p.offsets[j] || p.offsets[j] + a[j].size <= p.offsets[i];
                if (live_together) REQUIRE(disjoint);
            }
        }
        REQUIRE(p.arena_size <= p.naive_size);
    }
}

TEST_CASE("planner: a chain of short-lived tensors needs two buffers, not n", "[planner]") {
    std::vector<Allocation> chain;
    for (int i = 0; i < 10; ++i) chain.push_back({1000, i, i + 1});  // each read only by the next step
    const ArenaPlan p = plan_arena(chain, 8);
    CHECK(p.arena_size <= 2 * 1008);
    CHECK(p.naive_size == 10 * 1000);
}

#include "ops/set_pool.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

namespace {
constexpr int kPoolLocal = 64;  // the work-group size of set_pool.cl (LOCAL)
// The build options of kernels/set_pool.cl.
const std::string kPoolDefines = join_defines({define("LOCAL", kPoolLocal), define("POOL_MAX", int(PoolMode::Max)),
                                               define("POOL_MEAN", int(PoolMode::Mean))});
}

SetPool::SetPool(Context& ctx)
    : pool_(ctx.kernel("set_pool", "set_pool", kPoolDefines)),
      broadcast_(ctx.kernel("set_pool", "set_broadcast_concat", kPoolDefines)),
      pool_planar_(ctx.kernel("set_pool", "set_pool_planar", kPoolDefines)) {}

cl_event SetPool::pool(Context& ctx, cl_mem x, int channels, cl_mem first, int sets, PoolMode mode, cl_mem pooled,
                       bool want_event) {
    if (sets <= 0 || channels <= 0) return nullptr;
    pool_.args(x, channels, first, int(mode), pooled);
    const std::size_t g[2] = {std::size_t(sets) * kPoolLocal, std::size_t(channels)};
    const std::size_t l[2] = {std::size_t(kPoolLocal), 1};
    return ctx.launch(pool_, 2, g, l, want_event);
}

cl_event SetPool::broadcast_concat(Context& ctx, cl_mem x, int cx, cl_mem pooled, int cp, cl_mem set_of, int n,
                                   cl_mem y, bool want_event) {
    if (n <= 0 || cx + cp <= 0) return nullptr;
    static const std::size_t l[2] = {64, 1};
    broadcast_.args(x, cx, pooled, cp, set_of, n, y);
    const std::size_t g[2] = {std::size_t(n), std::size_t(cx + cp)};
    return ctx.launch(broadcast_, 2, g, l, want_event);
}

void SetPool::pool_planar(Context& ctx, cl_mem x, std::size_t x_off, int channels, int ld, int begin, int end,
                          PoolMode mode, cl_mem pooled, std::size_t pooled_off, int max_items_per_launch) {
    if (channels <= 0) return;
    if (begin < 0 || end < begin || end > ld)
        throw InputError("set pool: items [" + std::to_string(begin) + ", " + std::to_string(end) +
                         ") are not within a row of " + std::to_string(ld));
    // Per work-item: one strided pass over its share of the chunk, then log2(kPoolLocal) tree steps; keep the
    // chunk's pass below the loop limit with room for the tree.
    long chunk = std::numeric_limits<int>::max();
    if (const long limit = ctx.loop_limit(); limit > 0) chunk = std::max(1L, limit - 64) * kPoolLocal;
    if (max_items_per_launch > 0) chunk = std::min<long>(chunk, max_items_per_launch);
    const int count = end - begin;
    const std::size_t g[2] = {std::size_t(kPoolLocal), std::size_t(channels)};
    const std::size_t l[2] = {std::size_t(kPoolLocal), 1};
    int lo = begin;
    do {
        const int hi = int(std::min<long>(end, lo + chunk));
        pool_planar_.args(x, int(x_off), ld, lo, hi, count, int(mode), int(lo != begin), pooled, int(pooled_off));
        ctx.launch(pool_planar_, 2, g, l);
        lo = hi;
    } while (lo < end);
}

}  // namespace ngi::detail

#include "ops/set_pool.hpp"

namespace ngi::detail {

namespace {
constexpr int kPoolLocal = 64;  // must match -DLOCAL
}

SetPool::SetPool(Context& ctx)
    : pool_(ctx.kernel("set_pool", "set_pool", "-DLOCAL=" + std::to_string(kPoolLocal))),
      broadcast_(ctx.kernel("set_pool", "set_broadcast_concat", "-DLOCAL=" + std::to_string(kPoolLocal))) {}

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

}  // namespace ngi::detail

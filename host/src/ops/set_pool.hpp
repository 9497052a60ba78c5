// Set pooling (kernels/set_pool.cl): per-set max or mean over a variable-length list of items, and the pooled
// features broadcast back to every item (concatenated after its own). Seed 004's "adjustable pool layer".
#pragma once
#include "runtime/context.hpp"

namespace ngi::detail {

enum class PoolMode : int { Max = 0, Mean = 1 };  // kernels/set_pool.cl POOL_* (build options)

class SetPool {
public:
    explicit SetPool(Context& ctx);
    // x [items][channels] (points layout); first [sets + 1] item offsets (non-decreasing); pooled [sets][channels].
    // An empty set pools to 0.
    cl_event pool(Context& ctx, cl_mem x, int channels, cl_mem first, int sets, PoolMode mode, cl_mem pooled,
                  bool want_event = false);
    // y [n][cx + cp] = [x[i] | pooled[set_of[i]]].
    cl_event broadcast_concat(Context& ctx, cl_mem x, int cx, cl_mem pooled, int cp, cl_mem set_of, int n, cl_mem y,
                              bool want_event = false);
    // Planar layout, one set: pooled[pooled_off + c] = max or mean over the items [begin, end) of channel c of x
    // ([channels][ld] from x_off floats; ld >= end). An empty set pools to 0. The items are split over several
    // launches when one launch would exceed the device's loop limit (Context::loop_limit), or beyond
    // max_items_per_launch when that is > 0 (tests force the split with it).
    void pool_planar(Context& ctx, cl_mem x, std::size_t x_off, int channels, int ld, int begin, int end,
                     PoolMode mode, cl_mem pooled, std::size_t pooled_off, int max_items_per_launch = 0);

private:
    Kernel pool_, broadcast_, pool_planar_;
};

}  // namespace ngi::detail

// Set pooling with broadcast back (seed 004's "adjustable pool layer"): a per-set max or mean of per-item
// features, concatenated to every item of the set. Layouts: docs/CONVENTIONS.md section 14.

// Set pooling: pooled[s][c] = max or mean of x[i][c] over the items i in [first[s], first[s + 1]) of set s.
// One work-group of LOCAL work-items per (set, channel): each strides over the set, then a tree in local memory.
// An empty set pools to 0. Mean: per-work-item partial sums, then the tree (pairwise: no long serial sum).
// Build options, the host's (host/src/ops/set_pool.cpp): LOCAL, the work-group size (kPoolLocal); POOL_MAX,
// POOL_MEAN, the pooling codes (ngi::detail::PoolMode).
#if !defined(LOCAL) || !defined(POOL_MAX) || !defined(POOL_MEAN)
#error "set_pool.cl needs LOCAL, POOL_MAX and POOL_MEAN: build it through SetPool (host/src/ops/set_pool.cpp)"
#endif
__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void set_pool(__global const float* restrict x, const int channels, __global const int* restrict first,
              const int mode, __global float* restrict pooled) {
    __local float part[LOCAL];
    const int lid = get_local_id(0), c = get_group_id(1), s = get_group_id(0);
    const int lo = first[s], hi = first[s + 1];
    float acc = mode == POOL_MAX ? -INFINITY : 0.0f;
    for (int i = lo + lid; i < hi; i += LOCAL) {
        const float v = x[(size_t)i * channels + c];
        acc = mode == POOL_MAX ? fmax(acc, v) : acc + v;
    }
    part[lid] = acc;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int w = LOCAL / 2; w > 0; w /= 2) {
        if (lid < w) part[lid] = mode == POOL_MAX ? fmax(part[lid], part[lid + w]) : part[lid] + part[lid + w];
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0) {
        const int count = hi - lo;
        pooled[(size_t)s * channels + c] = count <= 0 ? 0.0f : mode == POOL_MAX ? part[0] : part[0] / (float)count;
    }
}

// The pooled features broadcast back and concatenated: y[i] = [x[i][0..cx) | pooled[set_of[i]][0..cp)].
__kernel void set_broadcast_concat(__global const float* restrict x, const int cx, __global const float* restrict pooled,
                                   const int cp, __global const int* restrict set_of, const int n,
                                   __global float* restrict y) {
    const int i = get_global_id(0), k = get_global_id(1);
    if (i >= n || k >= cx + cp) return;
    y[(size_t)i * (cx + cp) + k] = k < cx ? x[(size_t)i * cx + k] : pooled[(size_t)set_of[i] * cp + (k - cx)];
}

// Planar set pooling over one set, or a chunk of one: pooled[pooled_off + c] = max or mean over the items
// i in [lo, hi) of x[x_off + c * ld + i] (x planar [C][ld], the dense layers' layout). One work-group of LOCAL
// work-items per channel, the same stride-then-tree as set_pool. A set too long for one launch's loop budget
// (Context::loop_limit) is pooled in chunks: `accumulate` combines the chunk with what pooled already holds (max:
// fmax; mean: adds the chunk's sum / count, where count is the size of the whole set). An empty set pools to 0.
__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void set_pool_planar(__global const float* restrict x, const int x_off, const int ld, const int lo, const int hi,
                     const int count, const int mode, const int accumulate, __global float* restrict pooled,
                     const int pooled_off) {
    __local float part[LOCAL];
    const int lid = get_local_id(0), c = get_group_id(1);
    __global const float* row = x + x_off + (size_t)c * ld;
    float acc = mode == POOL_MAX ? -INFINITY : 0.0f;
    for (int i = lo + lid; i < hi; i += LOCAL) {
        const float v = row[i];
        acc = mode == POOL_MAX ? fmax(acc, v) : acc + v;
    }
    part[lid] = acc;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int w = LOCAL / 2; w > 0; w /= 2) {
        if (lid < w) part[lid] = mode == POOL_MAX ? fmax(part[lid], part[lid + w]) : part[lid] + part[lid + w];
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0) {
        float v = count <= 0 ? 0.0f : mode == POOL_MAX ? part[0] : part[0] / (float)count;
        if (accumulate && count > 0) v = mode == POOL_MAX ? fmax(pooled[pooled_off + c], v) : pooled[pooled_off + c] + v;
        pooled[pooled_off + c] = v;
    }
}

// Per-image batch normalization (pix2pix's default test mode: BatchNorm in training mode, batch 1).
//
// channel_stats: one work-group per channel. Each work-item computes the exact two-pass statistics of its own
// part of the channel (sum, then sum of squared deviations from that part's mean: no division per element and
// no E[x^2] - E[x]^2 cancellation), then the work-group merges the (count, mean, M2) triples pairwise with Chan et
// al.'s formula in a tree. Constant channels give exactly zero variance. The data are shifted by K = the
// channel's first value, so a large mean with a small spread (HDR lighting, depth in metres) keeps its
// precision: mean = K + m with m small, while K + m itself would round to the ulp of K.
// Writes stats[c] = {K, m, 1/sqrt(var + eps)} with the biased variance, like PyTorch's forward.
//
// CHUNKED=1 gives each work-item a contiguous range (cache-friendly on CPUs); CHUNKED=0 interleaves work-items
// (coalesced on GPUs).
//
// channel_affine_act: y = act(((x - K) - m) * (rstd * gamma) + beta), in place.
// channel_norm: both in one launch for small planes (below).
//
// LOCAL is a build option, the host's kStatsLocal (host/src/ops/norm.cpp): the work-group size, a power of two.

#ifndef LOCAL
#error "norm.cl needs LOCAL, the work-group size: build it through BatchNormPerImage (host/src/ops/norm.cpp)"
#endif
#ifndef CHUNKED
#define CHUNKED 1
#endif

// The statistics of one channel's HW values at p by the work-group (work-item t of LOCAL): on return every
// work-item sees the merged count, mean of (x - shift) and M2 in l_n[0], l_mean[0], l_m2[0].
static inline void work_group_channel_stats(__global const float* restrict p, const int HW, const float shift,
                                            const int t, __local float* l_n, __local float* l_mean,
                                            __local float* l_m2) {
#if CHUNKED
    const int per = (HW + LOCAL - 1) / LOCAL;
    const int begin = min(t * per, HW), end = min(begin + per, HW), step = 1;
#else
    const int begin = t, end = HW, step = LOCAL;
#endif
    const float n = (float)((end - begin + step - 1) / step);
#if CHUNKED
    // Eight independent partial sums (one float8): a single running sum is a chain of dependent adds, one
    // add latency per element, which made this kernel latency-bound on CPUs (~6 GB/s). Lanes hold interleaved
    // elements of the work-item's range; the scalar tail covers what is left of it.
    float8 acc = (float8)(0.0f);
    int i = begin;
    for (; i + 8 <= end; i += 8) acc += vload8(0, p + i) - shift;
    float sum = ((acc.s0 + acc.s1) + (acc.s2 + acc.s3)) + ((acc.s4 + acc.s5) + (acc.s6 + acc.s7));
    for (; i < end; ++i) sum += p[i] - shift;
    const float mean = n > 0.0f ? sum / n : 0.0f;
    float8 acc2 = (float8)(0.0f);
    i = begin;
    for (; i + 8 <= end; i += 8) {
        const float8 d = (vload8(0, p + i) - shift) - mean;
        acc2 = fma(d, d, acc2);
    }
    float m2 = ((acc2.s0 + acc2.s1) + (acc2.s2 + acc2.s3)) + ((acc2.s4 + acc2.s5) + (acc2.s6 + acc2.s7));
    for (; i < end; ++i) {
        const float d = (p[i] - shift) - mean;
        m2 += d * d;
    }
#else
    float sum = 0.0f;
    for (int i = begin; i < end; i += step) sum += p[i] - shift;
    const float mean = n > 0.0f ? sum / n : 0.0f;
    float m2 = 0.0f;
    for (int i = begin; i < end; i += step) {
        const float d = (p[i] - shift) - mean;
        m2 += d * d;
    }
#endif
    l_n[t] = n; l_mean[t] = mean; l_m2[t] = m2;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int s = LOCAL / 2; s > 0; s >>= 1) {
        if (t < s) {
            const float na = l_n[t], nb = l_n[t + s];
            const float nab = na + nb;
            if (nb > 0.0f) {
                const float d = l_mean[t + s] - l_mean[t];
                const float f = nb / nab;
                l_mean[t] = l_mean[t] + d * f;
                l_m2[t] = l_m2[t] + l_m2[t + s] + d * d * na * f;
                l_n[t] = nab;
            }
        }
        barrier(CLK_LOCAL_MEM_FENCE);
    }
}

static inline float rstd_of(const float n, const float m2, const float eps) {
    return rsqrt(fmax(m2 / fmax(n, 1.0f), 0.0f) + eps);
}

// y = act(((x - K) - m) * (rstd * gamma) + beta): (x - mean) * s + beta, not x * s + (beta - mean * s), which
// rounds mean * s, huge when the channel has a large mean and a tiny variance (s = gamma / sqrt(var + eps) ~ 300
// for a constant channel). none / ReLU / LeakyReLU as a branch-free slope (the common cases; vectorizes across
// work-items), the rest through ngi_activate's switch.
static inline float normalize_one(const float x, const float k, const float m, const float s, const float beta,
                                  const int act, const float alpha) {
    const float v = fma((x - k) - m, s, beta);
    if (act == ACT_NONE || act == ACT_RELU || act == ACT_LEAKY_RELU) {
        const float slope = act == ACT_NONE ? 1.0f : act == ACT_RELU ? 0.0f : alpha;
        return v >= 0.0f ? v : slope * v;
    }
    return ngi_activate(v, act, alpha);
}

__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void channel_stats(__global const float* restrict x, const int x_off, const int HW, const float eps,
                   __global float* restrict stats, const int stats_off /* [C][3]: K, m, rstd */) {
    __local float l_n[LOCAL], l_mean[LOCAL], l_m2[LOCAL];
    const int c = get_group_id(0);
    const int t = get_local_id(0);
    __global const float* p = x + x_off + (size_t)c * HW;
    const float shift = p[0];
    work_group_channel_stats(p, HW, shift, t, l_n, l_mean, l_m2);
    if (t == 0) {
        stats[stats_off + 3 * c] = shift;
        stats[stats_off + 3 * c + 1] = l_mean[0];
        stats[stats_off + 3 * c + 2] = rstd_of(l_n[0], l_m2[0], eps);
    }
}

// channel_norm: statistics and normalization of a channel in one launch, one work-group per channel, for planes
// small enough that the second read comes from cache (BatchNormPerImage picks it on CPUs, and on GPUs up to
// kFusedNormPlaneMax values): the same
// arithmetic as channel_stats followed by channel_affine_act, so the same results, with half the launches. On a
// CPU device a launch of a small kernel costs about as much as the normalization of a 2K-value plane.
__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void channel_norm(__global float* restrict x, const int x_off, const int HW, const float eps,
                  __global const float* restrict gamma, __global const float* restrict beta, const int act,
                  const float alpha) {
    __local float l_n[LOCAL], l_mean[LOCAL], l_m2[LOCAL];
    const int c = get_group_id(0);
    const int t = get_local_id(0);
    __global float* p = x + x_off + (size_t)c * HW;
    const float shift = p[0];
    work_group_channel_stats(p, HW, shift, t, l_n, l_mean, l_m2);
    // Each work-item rewrites only its own range, which it alone read, but every one read p[0] (the shift): the
    // reduction's barriers fence local memory only, so a global fence orders those reads before the writes
    // (without it oclgrind reports the race on p[0]).
    barrier(CLK_GLOBAL_MEM_FENCE);
    const float m = l_mean[0], s = rstd_of(l_n[0], l_m2[0], eps) * gamma[c], b = beta[c];
#if CHUNKED
    const int per = (HW + LOCAL - 1) / LOCAL;
    const int begin = min(t * per, HW), end = min(begin + per, HW), step = 1;
#else
    const int begin = t, end = HW, step = LOCAL;
#endif
    for (int i = begin; i < end; i += step) p[i] = normalize_one(p[i], shift, m, s, b, act, alpha);
}

// channel_norm_serial: the same for planes of a few values (the U-Net's inner levels at N = 64: 32 values or
// fewer), one work-item per channel: its two passes and the normalization run over the whole plane alone, with no
// work-group, local memory or barrier per channel (a work-group of LOCAL items for 32 values leaves most of them
// idle and costs a scheduled group per channel). The statistics are the chunked reduction's for a single range.
__kernel void channel_norm_serial(__global float* restrict x, const int x_off, const int C, const int HW,
                                  const float eps, __global const float* restrict gamma,
                                  __global const float* restrict beta, const int act, const float alpha) {
    const int c = get_global_id(0);
    if (c >= C) return;
    __global float* p = x + x_off + (size_t)c * HW;
    const float shift = p[0];
    float8 acc = (float8)(0.0f);
    int i = 0;
    for (; i + 8 <= HW; i += 8) acc += vload8(0, p + i) - shift;
    float sum = ((acc.s0 + acc.s1) + (acc.s2 + acc.s3)) + ((acc.s4 + acc.s5) + (acc.s6 + acc.s7));
    for (; i < HW; ++i) sum += p[i] - shift;
    const float n = (float)HW, mean = sum / n;
    float8 acc2 = (float8)(0.0f);
    i = 0;
    for (; i + 8 <= HW; i += 8) {
        const float8 d = (vload8(0, p + i) - shift) - mean;
        acc2 = fma(d, d, acc2);
    }
    float m2 = ((acc2.s0 + acc2.s1) + (acc2.s2 + acc2.s3)) + ((acc2.s4 + acc2.s5) + (acc2.s6 + acc2.s7));
    for (; i < HW; ++i) {
        const float d = (p[i] - shift) - mean;
        m2 += d * d;
    }
    const float s = rstd_of(n, m2, eps) * gamma[c], b = beta[c];
    for (i = 0; i < HW; ++i) p[i] = normalize_one(p[i], shift, mean, s, b, act, alpha);
}

__kernel void channel_affine_act(__global float* restrict x, const int x_off, const int C, const int HW,
                                 __global const float* restrict stats, const int stats_off, __global const float* restrict gamma,
                                 __global const float* restrict beta, const int act, const float alpha) {
    const int i = get_global_id(0);
    const int c = get_global_id(1);
    if (i >= HW || c >= C) return;
    const float s = stats[stats_off + 3 * c + 2] * gamma[c];
    __global float* p = x + x_off + (size_t)c * HW + i;
    *p = normalize_one(*p, stats[stats_off + 3 * c], stats[stats_off + 3 * c + 1], s, beta[c], act, alpha);
}

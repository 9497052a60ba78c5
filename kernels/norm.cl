// Per-image batch normalization (pix2pix's default test mode: BatchNorm in training mode, batch 1).
//
// channel_stats: one work-group per channel. Each work-item runs Welford's algorithm over a strided subset of
// the H*W values, then the work-group merges the (count, mean, M2) triples pairwise with Chan et al.'s formula
// in a tree. Single pass, no catastrophic cancellation (E[x^2] - E[x]^2 is never formed), exact zero variance
// for constant channels. The data are shifted by K = the channel's first value before accumulating, so a large
// mean with a small spread (HDR lighting, depth in metres) keeps its precision: mean = K + m, where m is small
// and exactly representable to fp32 precision, while K + m itself would round to the ulp of K.
// Writes stats[c] = {K, m, 1/sqrt(var + eps)} with the biased variance, like PyTorch's forward.
//
// channel_affine_act: y = act(((x - K) - m) * (rstd * gamma) + beta), in place.
//
// LOCAL is a build option (-DLOCAL=64): the work-group size, a power of two.

#ifndef LOCAL
#define LOCAL 64
#endif

__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void channel_stats(__global const float* restrict x, const int x_off, const int HW, const float eps,
                   __global float* restrict stats, const int stats_off /* [C][3]: K, m, rstd */) {
    __local float l_n[LOCAL], l_mean[LOCAL], l_m2[LOCAL];
    const int c = get_group_id(0);
    const int t = get_local_id(0);
    __global const float* p = x + x_off + (size_t)c * HW;
    const float shift = p[0];
    float n = 0.0f, mean = 0.0f, m2 = 0.0f;
    for (int i = t; i < HW; i += LOCAL) {
        const float v = p[i] - shift;
        n += 1.0f;
        const float d = v - mean;
        mean += d / n;
        m2 += d * (v - mean);
    }
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
    if (t == 0) {
        const float var = fmax(l_m2[0] / fmax(l_n[0], 1.0f), 0.0f);
        stats[stats_off + 3 * c] = shift;
        stats[stats_off + 3 * c + 1] = l_mean[0];
        stats[stats_off + 3 * c + 2] = rsqrt(var + eps);
    }
}

__kernel void channel_affine_act(__global float* restrict x, const int x_off, const int C, const int HW,
                                 __global const float* restrict stats, const int stats_off, __global const float* restrict gamma,
                                 __global const float* restrict beta, const int act, const float alpha) {
    const int i = get_global_id(0);
    const int c = get_global_id(1);
    if (i >= HW || c >= C) return;
    // (x - mean) * s + beta, not x * s + (beta - mean * s): the latter rounds mean * s, which is huge when the
    // channel has a large mean and a tiny variance (s = gamma / sqrt(var + eps) ~ 300 for a constant channel).
    const float s = stats[stats_off + 3 * c + 2] * gamma[c];
    __global float* p = x + x_off + (size_t)c * HW + i;
    *p = ngi_activate(fma((*p - stats[stats_off + 3 * c]) - stats[stats_off + 3 * c + 1], s, beta[c]), act, alpha);
}

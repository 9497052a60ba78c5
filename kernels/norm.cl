// Per-image batch normalization (pix2pix's default test mode: BatchNorm in training mode, batch 1).
//
// channel_stats: one work-group per channel. Each work-item runs Welford's algorithm over a strided subset of
// the H*W values, then the work-group merges the (count, mean, M2) triples pairwise with Chan et al.'s formula
// in a tree. Single pass, no catastrophic cancellation (E[x^2] - E[x]^2 is never formed), exact zero variance
// for constant channels. Writes mean and 1/sqrt(var + eps) with the biased variance, like PyTorch's forward.
//
// channel_affine_act: y = act((x - mean) * rstd * gamma + beta), in place.
//
// LOCAL is a build option (-DLOCAL=64): the work-group size, a power of two.

#ifndef LOCAL
#define LOCAL 64
#endif

__kernel __attribute__((reqd_work_group_size(LOCAL, 1, 1)))
void channel_stats(__global const float* restrict x, const int x_off, const int HW, const float eps,
                   __global float* restrict stats, const int stats_off /* [C][2]: mean, rstd */) {
    __local float l_n[LOCAL], l_mean[LOCAL], l_m2[LOCAL];
    const int c = get_group_id(0);
    const int t = get_local_id(0);
    __global const float* p = x + x_off + (size_t)c * HW;
    float n = 0.0f, mean = 0.0f, m2 = 0.0f;
    for (int i = t; i < HW; i += LOCAL) {
        const float v = p[i];
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
        stats[stats_off + 2 * c] = l_mean[0];
        stats[stats_off + 2 * c + 1] = rsqrt(var + eps);
    }
}

__kernel void channel_affine_act(__global float* restrict x, const int x_off, const int C, const int HW,
                                 __global const float* restrict stats, const int stats_off, __global const float* restrict gamma,
                                 __global const float* restrict beta, const int act, const float alpha) {
    const int i = get_global_id(0);
    const int c = get_global_id(1);
    if (i >= HW || c >= C) return;
    const float s = stats[stats_off + 2 * c + 1] * gamma[c];
    const float t = beta[c] - stats[stats_off + 2 * c] * s;
    __global float* p = x + x_off + (size_t)c * HW + i;
    *p = ngi_activate(fma(*p, s, t), act, alpha);
}

// Image metrics: squared-error partial sums (MSE, PSNR) and SSIM (Wang et al. 2004) exactly as scikit-image's
// structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False) computes it.
//
// Both kernels write one partial sum per work-group; the host adds the partials in double, so no float
// accumulator ever sums more than a few hundred terms.
//
// squared_error_partials: grid-stride loop with a Kahan-compensated sum per work-item, then a tree in local memory.
//
// ssim_tiles: one TILE x TILE work-group per tile of one channel's SSIM map. scikit-image filters the whole image
// (scipy.ndimage, mode 'reflect') and then crops R = 5 pixels off every border before averaging: the windows of
// the pixels it keeps lie entirely inside the image, so the padding never reaches the mean. The kernel therefore
// computes only those pixels (map pixel (R + x, R + y) for tile-relative x, y) and reads no padding at all.
// The tile's (TILE + 2R)^2 input span is staged in local memory, the 11-tap Gaussian runs separably (rows, then
// columns) over x, y, x^2, y^2 and x*y, and the tile's SSIM values are summed in a tree.
//
// Numerical care: the variances are E[x^2] - E[x]^2, which cancels catastrophically in float when the local mean
// is large against the local deviation (HDR images compared with a small data range). Variance and covariance do
// not change when x and y are shifted by constants, so each tile first subtracts its own mean of x and of y and
// adds them back to the two local means only.
//
// Build options, the host's (metrics_defines(), host/src/pipeline/metrics.cpp): SSIM_R, the window radius (5: 11
// taps), and the fixed work-group sizes SE_LOCAL x 1 and TILE x TILE.
#if !defined(SSIM_R) || !defined(TILE) || !defined(SE_LOCAL)
#error "metrics.cl needs SSIM_R, TILE and SE_LOCAL: build it with metrics_defines() (host/src/pipeline/metrics.cpp)"
#endif
#define SSIM_TAPS (2 * SSIM_R + 1)
#define TILE_ITEMS (TILE * TILE)
#define SPAN (TILE + 2 * SSIM_R)

__kernel __attribute__((reqd_work_group_size(SE_LOCAL, 1, 1)))
void squared_error_partials(__global const float* restrict a, __global const float* restrict b, const int n,
                            __global float* restrict partial) {
    __local float l[SE_LOCAL];
    const int lid = get_local_id(0);
    float sum = 0.0f, comp = 0.0f;
    for (size_t i = get_global_id(0); i < (size_t)n; i += get_global_size(0)) {
        const float d = a[i] - b[i];
        const float y = d * d - comp;
        const float t = sum + y;
        comp = (t - sum) - y;
        sum = t;
    }
    l[lid] = sum;
    for (int s = SE_LOCAL / 2; s > 0; s >>= 1) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (lid < s) l[lid] += l[lid + s];
    }
    if (lid == 0) partial[get_group_id(0)] = l[0];
}

// a, b: [C][H][W]; w: the SSIM_TAPS normalized Gaussian weights; partial: [C][groups_y][groups_x] sums of SSIM
// over the tile's map pixels that lie inside the cropped region [R, W - R) x [R, H - R).
__kernel __attribute__((reqd_work_group_size(TILE, TILE, 1)))
void ssim_tiles(__global const float* restrict a, __global const float* restrict b, const int W, const int H,
                __constant float* restrict w, const float c1, const float c2, __global float* restrict partial) {
    __local float la[SPAN * SPAN], lb[SPAN * SPAN];
    __local float rows[5][SPAN * TILE];  // row-filtered x, y, x^2, y^2, xy
    __local float ra[TILE_ITEMS], rb[TILE_ITEMS];
    const int lx = get_local_id(0), ly = get_local_id(1), lid = ly * TILE + lx;
    const int x0 = get_group_id(0) * TILE, y0 = get_group_id(1) * TILE;  // span origin = map origin - R
    const size_t plane = (size_t)W * H;
    __global const float* pa = a + get_group_id(2) * plane;
    __global const float* pb = b + get_group_id(2) * plane;

    // Stage the span. Past the image's right/bottom edge (only feeding map pixels masked out below) reads are
    // clamped to the last row/column, which keeps them in bounds.
    float sa = 0.0f, sb = 0.0f;
    for (int i = lid; i < SPAN * SPAN; i += TILE_ITEMS) {
        const int y = min(y0 + i / SPAN, H - 1), x = min(x0 + i % SPAN, W - 1);
        const float va = pa[(size_t)y * W + x], vb = pb[(size_t)y * W + x];
        la[i] = va;
        lb[i] = vb;
        sa += va;
        sb += vb;
    }
    ra[lid] = sa;
    rb[lid] = sb;
    for (int s = TILE_ITEMS / 2; s > 0; s >>= 1) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (lid < s) { ra[lid] += ra[lid + s]; rb[lid] += rb[lid + s]; }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    const float shift_a = ra[0] / (SPAN * SPAN), shift_b = rb[0] / (SPAN * SPAN);
    for (int i = lid; i < SPAN * SPAN; i += TILE_ITEMS) {
        la[i] -= shift_a;
        lb[i] -= shift_b;
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    for (int i = lid; i < SPAN * TILE; i += TILE_ITEMS) {
        const int r = i / TILE, col = i % TILE;
        float sx = 0.0f, sy = 0.0f, sxx = 0.0f, syy = 0.0f, sxy = 0.0f;
        for (int k = 0; k < SSIM_TAPS; ++k) {
            const float wk = w[k], x = la[r * SPAN + col + k], y = lb[r * SPAN + col + k];
            sx += wk * x;
            sy += wk * y;
            sxx += wk * x * x;
            syy += wk * y * y;
            sxy += wk * x * y;
        }
        rows[0][i] = sx; rows[1][i] = sy; rows[2][i] = sxx; rows[3][i] = syy; rows[4][i] = sxy;
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    float mx = 0.0f, my = 0.0f, mxx = 0.0f, myy = 0.0f, mxy = 0.0f;
    for (int k = 0; k < SSIM_TAPS; ++k) {
        const int i = (ly + k) * TILE + lx;
        const float wk = w[k];
        mx += wk * rows[0][i];
        my += wk * rows[1][i];
        mxx += wk * rows[2][i];
        myy += wk * rows[3][i];
        mxy += wk * rows[4][i];
    }
    const float vx = mxx - mx * mx, vy = myy - my * my, vxy = mxy - mx * my;  // population (co)variances
    const float ux = mx + shift_a, uy = my + shift_b;
    // The luminance and contrast-structure ratios are divided separately: each is O(1), while the product of
    // their denominators, mean^2 * variance, overflows float for HDR values beyond ~1e9 (inf / inf = NaN).
    const float ssim = ((2.0f * ux * uy + c1) / (ux * ux + uy * uy + c1)) * ((2.0f * vxy + c2) / (vx + vy + c2));
    const bool inside = x0 + SSIM_R + lx < W - SSIM_R && y0 + SSIM_R + ly < H - SSIM_R;
    ra[lid] = inside ? ssim : 0.0f;  // ra[0] was last read before two barriers: safe to reuse
    for (int s = TILE_ITEMS / 2; s > 0; s >>= 1) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (lid < s) ra[lid] += ra[lid + s];
    }
    if (lid == 0) partial[(get_group_id(2) * get_num_groups(1) + get_group_id(1)) * get_num_groups(0) + get_group_id(0)] = ra[0];
}

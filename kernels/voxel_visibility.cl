// Voxel-pair visibility of seed 004's voxel field (Renderer::voxel_visibility, host/src/render/voxel_field.cpp;
// docs/VOXEL_FIELD.md): a 3D DDA over the block grid alone (no mesh, no lighting), so the program
// "voxel_visibility" is geometry.cl and this file. No build options.

// True when the segment a -> b crosses no solid block other than the blocks with linear ids ia and ib (3D DDA,
// as scene.cl's trace_grid; the parts outside the grid are air).
static inline int vf_segment_clear(__global const uchar* grid, int3 dims, float3 a, float3 b, int ia, int ib) {
    float3 d = b - a;
    const float len = length(d);
    if (!(len > 0.0f)) return 1;
    d /= len;
    const float3 inv = (float3)(safe_inv(d.x), safe_inv(d.y), safe_inv(d.z));
    const float3 ta = -a * inv, tb = (convert_float3(dims) - a) * inv;
    const float3 lo = fmin(ta, tb), hi = fmax(ta, tb);
    const float t_end = fmin(fmin(fmin(hi.x, hi.y), hi.z), len);
    const float t = fmax(fmax(fmax(lo.x, lo.y), lo.z), 0.0f);
    if (t > t_end) return 1;  // the segment misses the grid
    int3 c = clamp(convert_int3(floor(a + d * t)), (int3)(0), dims - 1);
    const int3 step = (int3)(d.x >= 0.0f ? 1 : -1, d.y >= 0.0f ? 1 : -1, d.z >= 0.0f ? 1 : -1);
    const float3 delta = fabs(inv);
    // Scalar compares (1 for true): see trace_grid (scene.cl) on oclgrind and vector selects.
    float3 next = (convert_float3(c + (int3)(step.x > 0, step.y > 0, step.z > 0)) - a) * inv;
    const int sx = dims.x, sxy = dims.x * dims.y;
    int idx = c.x + sx * c.y + sxy * c.z;
    const int max_steps = dims.x + dims.y + dims.z + 3;
    for (int i = 0; i < max_steps; ++i) {
        if (grid[idx] != 0 && idx != ia && idx != ib) return 0;
        float tn;
        if (next.x < next.y && next.x < next.z) {
            tn = next.x; c.x += step.x; idx += step.x; next.x += delta.x;
            if ((uint)c.x >= (uint)dims.x) return 1;
        } else if (next.y < next.z) {
            tn = next.y; c.y += step.y; idx += step.y * sx; next.y += delta.y;
            if ((uint)c.y >= (uint)dims.y) return 1;
        } else {
            tn = next.z; c.z += step.z; idx += step.z * sxy; next.z += delta.z;
            if ((uint)c.z >= (uint)dims.z) return 1;
        }
        if (tn >= t_end) return 1;
    }
    return 1;
}

// Visibility mask: bit b of word w of row i (mask[i * words + w]) = the segment between the probe points of voxels
// i and j = 32 w + b is clear (vf_segment_clear, always traced from the lower index to the higher, so the mask is
// symmetric bit for bit); the diagonal and bits past the last voxel are 0. Bits [bit_first, bit_last) of each word
// per launch (llvmpipe's loop limit), OR-ed into the word. global size (V, words): work-item (i, w).
__kernel void vf_visibility(__global const uchar* grid, int sx, int sy, int sz, __global const float* probe,
                            __global const int4* cells, int nvox, int words, int bit_first, int bit_last,
                            __global uint* mask) {
    const int i = get_global_id(0), w = get_global_id(1);
    if (i >= nvox || w >= words) return;
    const int3 dims = (int3)(sx, sy, sz);
    __global uint* q = mask + (size_t)i * words + w;
    uint bits = bit_first > 0 ? *q : 0u;
    const float3 p_i = vload3(i, probe);
    const int id = block_id(cells[i], sx, sy);
    for (int b = bit_first; b < bit_last; ++b) {
        const int j = 32 * w + b;
        if (j >= nvox) break;
        if (j == i) continue;
        const float3 pj = vload3(j, probe);
        const int jd = block_id(cells[j], sx, sy);
        const int clear = i < j ? vf_segment_clear(grid, dims, p_i, pj, id, jd)
                                : vf_segment_clear(grid, dims, pj, p_i, jd, id);
        if (clear) bits |= 1u << b;
    }
    *q = bits;
}

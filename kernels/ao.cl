// Seed 001's ambient-occlusion network around the per-pixel MLP (host/src/pipeline/ao.cpp, ngi/ao.hpp).
// Normals: [3][h][w] object-space; a zero vector = no surface (background). docs/CONVENTIONS.md section 15.

static inline int is_surface(float x, float y, float z) { return x != 0.0f || y != 0.0f || z != 0.0f; }

// The MLP's input: out[3 k + c][pix] = component c of the normal at ring point k (offsets[2 k] rows,
// offsets[2 k + 1] columns from the pixel); a point outside the image or on the background takes the pixel's own
// normal. Global size h * w.
__kernel void ao_ring_gather(__global const float* restrict normal, const int h, const int w,
                             __constant int* restrict offsets, const int points, __global float* restrict out) {
    const int pix = get_global_id(0);
    const int hw = h * w;
    if (pix >= hw) return;
    const int row = pix / w, col = pix - row * w;
    const float cx = normal[pix], cy = normal[hw + pix], cz = normal[2 * hw + pix];
    for (int k = 0; k < points; ++k) {
        const int r = row + offsets[2 * k], c = col + offsets[2 * k + 1];
        float x = cx, y = cy, z = cz;
        if (r >= 0 && r < h && c >= 0 && c < w) {
            const int q = r * w + c;
            const float nx = normal[q], ny = normal[hw + q], nz = normal[2 * hw + q];
            if (is_surface(nx, ny, nz)) {
                x = nx; y = ny; z = nz;
            }
        }
        out[(size_t)(3 * k) * hw + pix] = x;
        out[(size_t)(3 * k + 1) * hw + pix] = y;
        out[(size_t)(3 * k + 2) * hw + pix] = z;
    }
}

// Accessibility from the network's raw output: clamped to [0, 1] (NaN -> 0), 1 on the background.
__kernel void ao_finish(__global const float* restrict normal, __global const float* restrict raw, const int hw,
                        __global float* restrict ao) {
    const int pix = get_global_id(0);
    if (pix >= hw) return;
    const float v = raw[pix];
    ao[pix] = is_surface(normal[pix], normal[hw + pix], normal[2 * hw + pix]) ? (isnan(v) ? 0.0f : clamp(v, 0.0f, 1.0f))
                                                                               : 1.0f;
}

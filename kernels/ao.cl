// Seed 001's ambient-occlusion network around the per-pixel MLP (host/src/pipeline/ao.cpp, ngi/ao.hpp).
// Normals: [3][h][w] object-space; a zero vector = no surface (background). docs/CONVENTIONS.md section 15.

static inline int is_surface(float x, float y, float z) { return x != 0.0f || y != 0.0f || z != 0.0f; }

// The MLP's input: out[3 k + c][pix] = component c of the normal at ring point k (offsets[2 k] rows,
// offsets[2 k + 1] columns from the pixel); a point outside the image or on the background takes the pixel's own
// normal. Global size rows * w.
// One band of rows [row0, row0 + rows) of the h x w image: `out` is the band's [3 * points][rows][w] (a large image
// runs in bands, so the 48 gathered channels never need 48 floats for every pixel at once).
__kernel void ao_ring_gather(__global const float* restrict normal, const int h, const int w, const int row0,
                             const int rows, __constant int* restrict offsets, const int points,
                             __global float* restrict out) {
    const int i = get_global_id(0);
    const int band = rows * w;
    if (i >= band) return;
    const int hw = h * w;
    const int row = row0 + i / w, col = i - (i / w) * w;
    const int pix = row * w + col;
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
        out[(size_t)(3 * k) * band + i] = x;
        out[(size_t)(3 * k + 1) * band + i] = y;
        out[(size_t)(3 * k + 2) * band + i] = z;
    }
}

// Accessibility from the network's raw output for the band of n pixels starting at pixel pix0: clamped to [0, 1]
// (NaN -> 0), 1 on the background.
__kernel void ao_finish(__global const float* restrict normal, __global const float* restrict raw, const int hw,
                        const int pix0, const int n, __global float* restrict ao) {
    const int i = get_global_id(0);
    if (i >= n) return;
    const int pix = pix0 + i;
    const float v = raw[i];
    ao[pix] = is_surface(normal[pix], normal[hw + pix], normal[2 * hw + pix]) ? (isnan(v) ? 0.0f : clamp(v, 0.0f, 1.0f))
                                                                               : 1.0f;
}

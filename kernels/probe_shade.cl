// Shades the visible surfaces of one camera face from a per-voxel lighting field (seed 004's probe grid: the SH-27
// irradiance of each occupied voxel, or any per-voxel lighting such as the LTF's). Host side:
// host/src/ops/probe_shade.cpp; conventions and why: docs/VOXEL_LTF.md ("Probe shading").
//
// Units: lighting = irradiance / pi. Camera: docs/CONVENTIONS.md sections 1-3 (pixel (col, row) looks along
// normalize(look + u right + v up), as scene.cl's pixel_ray). Grid: block (x, y, z) covers [x, x+1) x [y, y+1)
// x [z, z+1) metres, linear id x + X (y + Y z) (docs/RENDERER.md). The SH basis is sh_basis.cl's, listed before
// this file.

// Build options, the host's (probe_shade_defines(), host/src/ops/probe_shade.hpp):
//   PROBE_MAX_DEPTH       the farthest planar depth that is a surface (kMaxSurfaceDepth; the tracer writes 1e4
//                         where there is none)
//   PROBE_NEIGHBOUR_STEP  offset of the fallback lookups (metres): a hit point on a block edge or corner can round
//                         to the empty side
//   PROBE_NEIGHBOURS      the 27 lookup offsets (x, y, z in {-1, 0, 1}), in the order they are tried: the cell
//                         behind the surface first, then its 26 neighbours, nearest first, so the first voxel found
//                         is the likeliest one
//   FIELD_SH, FIELD_PER_VOXEL   the field layouts (ngi::detail::ProbeField): [V][3][9] SH coefficients of incident
//                         radiance (docs/CONVENTIONS.md section 14), or [V] float4 lighting (w unused)
//   COUNT_NO_VOXEL, COUNT_NON_FINITE   the slots of the miss counters (ProbeShade::counts)
#if !defined(PROBE_MAX_DEPTH) || !defined(PROBE_NEIGHBOUR_STEP) || !defined(PROBE_NEIGHBOURS) || \
    !defined(FIELD_SH) || !defined(FIELD_PER_VOXEL) || !defined(COUNT_NO_VOXEL) || !defined(COUNT_NON_FINITE)
#error "probe_shade.cl needs the host's constants: build it with probe_shade_defines() (host/src/ops/probe_shade.hpp)"
#endif

__constant char kNeighbour[27][3] = {PROBE_NEIGHBOURS};

// The voxel index of the cell containing q, or -1 (outside the grid, empty, or an index_of entry outside [0, V)).
static inline int probe_cell(float3 q, int X, int Y, int Z, __global const int* index_of, int V) {
    const float3 c = floor(q);
    // Compared as floats: a far point must not overflow the int conversion.
    if (!(c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f && c.x < (float)X && c.y < (float)Y && c.z < (float)Z))
        return -1;
    const int id = index_of[(int)c.x + X * ((int)c.y + Y * (int)c.z)];
    return id >= 0 && id < V ? id : -1;
}

// One work-item per pixel of the n x n face. depth [n*n], normal [3][n*n], out [3][n*n] (planar), counts [2]
// (COUNT_*), zeroed by the host before the launch. Sky pixels and misses get lighting 0.
__kernel void probe_shade(__global const float* restrict depth, __global const float* restrict normal, const int n,
                          const float cx, const float cy, const float cz, const float lx, const float ly,
                          const float lz, const float rx, const float ry, const float rz, const float ux,
                          const float uy, const float uz, const int X, const int Y, const int Z,
                          __global const int* restrict index_of, const int V, const int mode,
                          __global const float* restrict field, __global float* restrict out,
                          volatile __global uint* counts) {
    // Every argument is read before any branch: Mesa's rusticl warns that kernel-argument loads inside control
    // flow are assumed uniform ("results may be incorrect").
    const int npix = n * n;
    const int pix = get_global_id(0);
    const float3 centre = (float3)(cx, cy, cz), look = (float3)(lx, ly, lz), right = (float3)(rx, ry, rz),
                 up = (float3)(ux, uy, uz);
    const int grid_x = X, grid_y = Y, grid_z = Z, voxels = V, per_voxel = mode == FIELD_PER_VOXEL;
    if (pix >= npix) return;
    const int row = pix / n, col = pix - row * n;
    const float t = depth[pix];
    const float3 nr = (float3)(normal[pix], normal[npix + pix], normal[2 * npix + pix]);
    float3 lighting = (float3)(0.0f);
    if (!isfinite(t) || !isfinite(nr.x) || !isfinite(nr.y) || !isfinite(nr.z)) {
        atomic_inc(&counts[COUNT_NON_FINITE]);  // treated as sky, but counted: the frame is damaged
    } else if (t <= PROBE_MAX_DEPTH) {
        const float u = 2.0f * ((float)col + 0.5f) / (float)n - 1.0f;
        const float v = 1.0f - 2.0f * ((float)row + 0.5f) / (float)n;
        const float3 dir = normalize(look + u * right + v * up);
        const float along = dot(dir, look);
        const float len = length(nr);
        int id = -1;
        // A surface pixel needs its normal (which block is behind the face; the SH lobe's axis); a camera whose
        // ray does not advance along look cannot place a planar depth.
        if (len > 0.0f && along > 0.0f) {
            const float3 p = centre + dir * (t / along);
            const float3 q = p - 0.5f * nr;  // the middle of the block behind the visible face
            for (int k = 0; k < 27 && id < 0; ++k) {
                const float3 o = (float3)((float)kNeighbour[k][0], (float)kNeighbour[k][1], (float)kNeighbour[k][2]);
                id = probe_cell(q + PROBE_NEIGHBOUR_STEP * o, grid_x, grid_y, grid_z, index_of, voxels);
            }
        }
        if (id < 0) {
            atomic_inc(&counts[COUNT_NO_VOXEL]);
        } else if (per_voxel) {
            lighting = vload3(0, field + 4 * (size_t)id);
        } else {
            const float3 m = nr / len;
            float Y9[9];
            sh9(m.x, m.y, m.z, Y9);
            __global const float* c = field + 27 * (size_t)id;
            float e[3];
            for (int ch = 0; ch < 3; ++ch) {
                float s = 0.0f;
                for (int k = 0; k < 9; ++k) s = mad(kLobe[k] * c[9 * ch + k], Y9[k], s);
                e[ch] = fmax(s, 0.0f) * 0.318309886183790672f;  // E / pi: the lighting unit
            }
            lighting = (float3)(e[0], e[1], e[2]);
        }
    }
    out[pix] = lighting.x;
    out[npix + pix] = lighting.y;
    out[2 * npix + pix] = lighting.z;
}

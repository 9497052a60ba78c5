// Surface-voxel compaction (seed 004; definitions in docs/VOXEL_FIELD.md, host in host/src/render/voxel_field.cpp):
// flag every solid block with an exposed face (vc_flag), an exclusive prefix sum of the per-tile counts
// (vc_scan_tiles), then each tile rescans its blocks and scatters its surface voxels, in increasing block id, with
// their attributes, normal and probe point (vc_scatter).
//
// Grid: palette index per block (uchar, 0 = air), id = x + X (y + Y z); outside the grid is air.
// A tile is VC_LOCAL work-items x VC_ITEMS consecutive blocks each, so a work-item's blocks are contiguous and the
// exclusive scan of the per-work-item counts gives every surface voxel its place in id order. Face normals are
// geometry.cl's face_normal (the program "voxel_compact" lists it first): the tracer's face ids.

// Build options, the host's (voxel_field.cpp): VC_LOCAL, the work-group size of every kernel here (kCompactLocal);
// VC_ITEMS, consecutive blocks per work-item (kCompactItems); VC_ATTRIBUTES, floats per voxel: centre xyz, albedo
// rgb, emission rgb, id (ngi::kVoxelAttributes).
#if !defined(VC_LOCAL) || !defined(VC_ITEMS) || !defined(VC_ATTRIBUTES)
#error "voxel_compact.cl needs VC_LOCAL, VC_ITEMS and VC_ATTRIBUTES: build it through surface_voxels() (host/src/render/voxel_field.cpp)"
#endif

static inline int vc_solid(__global const uchar* grid, int sx, int sy, int sz, int x, int y, int z) {
    if (x < 0 || y < 0 || z < 0 || x >= sx || y >= sy || z >= sz) return 0;
    return grid[x + sx * (y + sy * z)] != 0;
}

// Bit f set when face f (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z) of block (x, y, z) borders a non-solid block; 0 for air.
static inline uint vc_exposed(__global const uchar* grid, int sx, int sy, int sz, int x, int y, int z) {
    if (!vc_solid(grid, sx, sy, sz, x, y, z)) return 0u;
    uint m = 0u;
    if (!vc_solid(grid, sx, sy, sz, x + 1, y, z)) m |= 1u;
    if (!vc_solid(grid, sx, sy, sz, x - 1, y, z)) m |= 2u;
    if (!vc_solid(grid, sx, sy, sz, x, y + 1, z)) m |= 4u;
    if (!vc_solid(grid, sx, sy, sz, x, y - 1, z)) m |= 8u;
    if (!vc_solid(grid, sx, sy, sz, x, y, z + 1)) m |= 16u;
    if (!vc_solid(grid, sx, sy, sz, x, y, z - 1)) m |= 32u;
    return m;
}

// Exclusive prefix sum of v over the work-group (Hillis-Steele in local memory); *total = the sum of every v.
// Every work-item of the group must call it (barriers).
static inline int vc_scan(__local int* tmp, int v, int* total) {
    const int lid = get_local_id(0);
    tmp[lid] = v;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int off = 1; off < VC_LOCAL; off <<= 1) {
        const int add = lid >= off ? tmp[lid - off] : 0;
        barrier(CLK_LOCAL_MEM_FENCE);
        tmp[lid] += add;
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    *total = tmp[VC_LOCAL - 1];
    const int inclusive = tmp[lid];
    barrier(CLK_LOCAL_MEM_FENCE);  // tmp is reused by the next call
    return inclusive - v;
}

// Exposed-face mask of every block, mask[id], and the number of surface voxels of each tile, tile_count[tile].
// global size: tiles * VC_LOCAL.
__kernel __attribute__((reqd_work_group_size(VC_LOCAL, 1, 1)))
void vc_flag(__global const uchar* grid, int sx, int sy, int sz, __global uchar* mask, __global int* tile_count) {
    __local int tmp[VC_LOCAL];
    const int blocks = sx * sy * sz, sxy = sx * sy;
    const int base = (int)get_group_id(0) * (VC_LOCAL * VC_ITEMS) + (int)get_local_id(0) * VC_ITEMS;
    int count = 0;
    for (int k = 0; k < VC_ITEMS; ++k) {
        const int i = base + k;
        if (i >= blocks) break;
        const int z = i / sxy, rest = i - z * sxy, y = rest / sx, x = rest - y * sx;
        const uint m = vc_exposed(grid, sx, sy, sz, x, y, z);
        mask[i] = (uchar)m;
        count += m != 0u;
    }
    int total;
    vc_scan(tmp, count, &total);
    if (get_local_id(0) == 0) tile_count[get_group_id(0)] = total;
}

// tile_offset[t] = sum of tile_count[0..t), tile_offset[tiles] = the number of surface voxels. One work-group
// (global size VC_LOCAL) walks the tiles VC_LOCAL at a time, carrying the running total.
__kernel __attribute__((reqd_work_group_size(VC_LOCAL, 1, 1)))
void vc_scan_tiles(__global const int* tile_count, int tiles, __global int* tile_offset) {
    __local int tmp[VC_LOCAL];
    const int lid = get_local_id(0);
    int carry = 0;
    for (int first = 0; first < tiles; first += VC_LOCAL) {
        const int t = first + lid;
        int total;
        const int before = vc_scan(tmp, t < tiles ? tile_count[t] : 0, &total);
        if (t < tiles) tile_offset[t] = carry + before;
        carry += total;
    }
    if (lid == 0) tile_offset[tiles] = carry;
}

// Writes every surface voxel at its compact index k (running count in id order):
//   cell_out[k] = (x, y, z, exposed mask); attr_out[k][VC_ATTRIBUTES]; normal_out[k][3]; probe_out[k][3]
// and index_of[id] = k, or -1 for blocks that are not surface voxels. mats: per material albedo, emission (lamp
// level applied). probe_offset: the tracer's RAY_OFFSET (kRayOffset). global size: tiles * VC_LOCAL.
//
// Normal (Eq. 3): g = (occ(x-1) - occ(x+1), ...) normalized, the stand-in face's normal where g = 0. With
// outside = air, g_a = exposed(+a) - exposed(-a) = the sum of the exposed faces' normals.
// Probe point: centre + 0.5 g + probe_offset * g / |g|: the centre of a face, the middle of an edge or a corner,
// just off the surface. Where g = 0 (a block exposed on opposite sides), or where that point would lie inside
// the solid block diagonally across an edge or corner (a crease, e.g. blocks touching along an edge only), the
// stand-in face's normal replaces g: the centre of that face, always in air. The stand-in face is the first exposed
// face (in the order +x, -x, +y, -y, +z, -z) whose neighbour lies inside the grid, else the first exposed face.
__kernel __attribute__((reqd_work_group_size(VC_LOCAL, 1, 1)))
void vc_scatter(__global const uchar* grid, int sx, int sy, int sz, __global const uchar* mask,
                __global const int* tile_offset, __global const float4* mats, float probe_offset,
                __global int4* cell_out, __global float* attr_out, __global float* normal_out,
                __global float* probe_out, __global int* index_of) {
    __local int tmp[VC_LOCAL];
    const int blocks = sx * sy * sz, sxy = sx * sy;
    const int base = (int)get_group_id(0) * (VC_LOCAL * VC_ITEMS) + (int)get_local_id(0) * VC_ITEMS;
    int count = 0;
    for (int k = 0; k < VC_ITEMS; ++k) {
        const int i = base + k;
        if (i >= blocks) break;
        count += mask[i] != 0;
    }
    int total;
    int k = tile_offset[get_group_id(0)] + vc_scan(tmp, count, &total);
    for (int j = 0; j < VC_ITEMS; ++j) {
        const int i = base + j;
        if (i >= blocks) break;
        const int m = mask[i];
        if (m == 0) {
            index_of[i] = -1;
            continue;
        }
        const int z = i / sxy, rest = i - z * sxy, y = rest / sx, x = rest - y * sx;
        const int gx = (m & 1) - ((m >> 1) & 1), gy = ((m >> 2) & 1) - ((m >> 3) & 1), gz = ((m >> 4) & 1) - ((m >> 5) & 1);
        // The stand-in face: the first exposed face toward the grid's interior, else the first exposed face. A
        // one-block wall on the grid's border (a closed Cornell box filling the grid) is then probed on the side a
        // camera inside the grid sees, not on its outer side.
        const int inward = (x + 1 < sx ? 1 : 0) | (x > 0 ? 2 : 0) | (y + 1 < sy ? 4 : 0) | (y > 0 ? 8 : 0) |
                           (z + 1 < sz ? 16 : 0) | (z > 0 ? 32 : 0);
        const int pref = (m & inward) ? (m & inward) : m;
        const int first = (pref & 1) ? 0 : (pref & 2) ? 1 : (pref & 4) ? 2 : (pref & 8) ? 3 : (pref & 16) ? 4 : 5;
        const int flat = gx == 0 && gy == 0 && gz == 0;
        const float3 nf = face_normal(first);
        const float3 normal = flat ? nf : normalize((float3)((float)gx, (float)gy, (float)gz));
        const int crease = !flat && vc_solid(grid, sx, sy, sz, x + gx, y + gy, z + gz);
        const float3 g = flat || crease ? nf : (float3)((float)gx, (float)gy, (float)gz);
        const float3 centre = (float3)((float)x + 0.5f, (float)y + 0.5f, (float)z + 0.5f);
        const float3 probe = centre + 0.5f * g + probe_offset * normalize(g);
        const int mat = grid[i];
        const float4 albedo = mats[2 * mat], emission = mats[2 * mat + 1];
        __global float* a = attr_out + (size_t)k * VC_ATTRIBUTES;
        a[0] = centre.x; a[1] = centre.y; a[2] = centre.z;
        a[3] = albedo.x; a[4] = albedo.y; a[5] = albedo.z;
        a[6] = emission.x; a[7] = emission.y; a[8] = emission.z;
        a[9] = (float)i;
        normal_out[3 * k] = normal.x; normal_out[3 * k + 1] = normal.y; normal_out[3 * k + 2] = normal.z;
        probe_out[3 * k] = probe.x; probe_out[3 * k + 1] = probe.y; probe_out[3 * k + 2] = probe.z;
        cell_out[k] = (int4)(x, y, z, m);
        index_of[i] = k++;
    }
}

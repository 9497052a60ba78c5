// Seed 004's light-transition function (LTF) over the occupied surface voxels of a scene, matrix-free: one
// work-item per receiver i sums over the senders j, so no V x V matrix is ever stored. The exact maths, the two
// variants and every deviation from the paper: docs/VOXEL_LTF.md. Host side: host/src/ops/voxel_ltf.cpp.
//
// Units: "lighting" = irradiance / pi (a white Lambertian surface reflects albedo x lighting).
// Buffers are float4 per voxel (w unused) unless stated. Build options:
//   LTF_LOCAL     work-group size of every kernel here (the tiles and the energy tree are sized by it)
//   LTF_PHYSICAL  1: radiosity with both cosines and the sender's exposed-face area; 0: the paper's LTF as written
//   LTF_VIS       1: a visibility bitmask gates every pair (row i: `words` uint32, bit j % 32 of word j / 32)
//   LTF_TILED     1: a work-group stages LTF_LOCAL senders at a time in __local memory (the GPU shape)
//   LTF_VEC       receivers per work-item, as the lanes of floatLTF_VEC (1, 2, 4, 8, 16; the CPU shape: PoCL
//                 vectorizes loops inside a work-item, not across the work-items of a loop that holds another
//                 loop); 1 with LTF_TILED
// The O(V) kernels take the variant as an argument and are built once, without the last four (the normalizer,
// O(V^2) once per run, with LTF_VEC only).

// LTF_LOCAL and LTF_R_MIN are the host's (voxel_ltf.cpp kLtfLocal, voxel_ltf.hpp kLtfRMin): always passed, with
// the luminance weights of luminance.cl (listed before this file), which checks its own.
#if !defined(LTF_LOCAL) || !defined(LTF_R_MIN)
#error "voxel_ltf.cl needs LTF_LOCAL and LTF_R_MIN: build it through VoxelLtf (host/src/ops/voxel_ltf.cpp)"
#endif
#ifndef LTF_PHYSICAL
#define LTF_PHYSICAL 1
#endif
#ifndef LTF_VIS
#define LTF_VIS 0
#endif
#ifndef LTF_TILED
#define LTF_TILED 0
#endif
#ifndef LTF_VEC
#define LTF_VEC 1
#endif
#if LTF_TILED && LTF_VEC != 1
#error "LTF_TILED needs LTF_VEC = 1"
#endif
// Receiver lanes: vfloat is float for LTF_VEC = 1, else floatN.
#if LTF_VEC == 1
#define vfloat float
#define vuint uint
#define vint int
#define VLOAD_F(p) (*(p))
#define VLOAD_I(p) (*(p))
#define VLOAD_U(p) (*(p))
#define VSTORE_F(v, p) (*(p) = (v))
#define CONVERT_VFLOAT(x) ((float)(x))
#else
#define vfloat NGI_CAT(float, LTF_VEC)
#define vuint NGI_CAT(uint, LTF_VEC)
#define vint NGI_CAT(int, LTF_VEC)
#define VLOAD_F(p) NGI_CAT(vload, LTF_VEC)(0, (p))
#define VLOAD_I(p) NGI_CAT(vload, LTF_VEC)(0, (p))
#define VLOAD_U(p) NGI_CAT(vload, LTF_VEC)(0, (p))
#define VSTORE_F(v, p) NGI_CAT(vstore, LTF_VEC)((v), 0, (p))
#define CONVERT_VFLOAT(x) NGI_CAT(convert_float, LTF_VEC)(x)
#endif

// Distances are clamped below at LTF_R_MIN in every 1 / r^2: two adjacent voxels (r = 1 m, centre to centre) see
// each other at a point-to-area form factor that is already a poor approximation, and it diverges as r -> 0
// (coincident positions). LTF_R_MIN is kLtfRMin (host/src/ops/voxel_ltf.hpp), a build option.
#define LTF_INV_PI 0.318309886183790672f


// ---- per-run and per-bounce preparation (O(V)) -------------------------------------------------------------

// Sender geometry, once per run: the position, and the exposed faces as two float3 so the projected area is two
// dot products (ltf_pair): mid = (e+ + e-) / 2, half = (e+ - e-) / 2 per axis, e+/e- = 1 when the +/- face of
// that axis is exposed (bits 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z).
__kernel void ltf_pack_geometry(__global const float4* restrict position, __global const uint* restrict exposed,
                                const int V, __global float4* restrict geometry, __global float4* restrict mid,
                                __global float4* restrict half_diff) {
    const int i = get_global_id(0);
    if (i >= V) return;
    const uint e = exposed[i];
    const float3 pos = (float3)((e & 1u) ? 1.0f : 0.0f, (e & 4u) ? 1.0f : 0.0f, (e & 16u) ? 1.0f : 0.0f);
    const float3 neg = (float3)((e & 2u) ? 1.0f : 0.0f, (e & 8u) ? 1.0f : 0.0f, (e & 32u) ? 1.0f : 0.0f);
    geometry[i] = (float4)(position[i].xyz, 0.0f);
    mid[i] = (float4)(0.5f * (pos + neg), 0.0f);
    half_diff[i] = (float4)(0.5f * (pos - neg), 0.0f);
}

// AsWritten's per-sender normalizer Z_j = sum_{k != j} 1 / max(r_kj^2, r_min^2), so the PDF r_ij^-2 / Z_j of
// sender j sums to 1 over its receivers; LTF_VEC senders j per work-item (the gather's lanes). Terms k in [k0, k1)
// of this launch; `first`: start from 0, else continue the running sum kept in z (the host splits k over launches
// under llvmpipe's loop limit; the order of the sum is the same for any split, so the result is bit-identical).
// Coincident voxels (r = 0, k != j) count with the clamped 1 / r_min^2, as in the gather.
__kernel void ltf_normalizer(__global const float4* restrict geometry, const int V, const int k0, const int k1,
                             const int first, __global float* restrict z) {
    const int j0 = get_global_id(0) * LTF_VEC;
    if (j0 >= V) return;
    float t_px[LTF_VEC], t_py[LTF_VEC], t_pz[LTF_VEC], t_acc[LTF_VEC];
    int t_id[LTF_VEC];
    for (int l = 0; l < LTF_VEC; ++l) {
        const int r = min(j0 + l, V - 1);
        const float4 g = geometry[r];
        t_px[l] = g.x; t_py[l] = g.y; t_pz[l] = g.z;
        t_acc[l] = first || j0 + l >= V ? 0.0f : z[r];
        t_id[l] = j0 + l;
    }
    const vfloat px = VLOAD_F(t_px), py = VLOAD_F(t_py), pz = VLOAD_F(t_pz);
    const vint id = VLOAD_I(t_id);
    vfloat acc = VLOAD_F(t_acc);
    for (int k = k0; k < k1; ++k) {
        const float4 q = geometry[k];
        const vfloat dx = q.x - px, dy = q.y - py, dz = q.z - pz;
        const vfloat t = 1.0f / fmax(dx * dx + dy * dy + dz * dz, LTF_R_MIN * LTF_R_MIN);
        acc += select(t, (vfloat)(0.0f), id == k);
    }
    VSTORE_F(acc, t_acc);
    for (int l = 0; l < LTF_VEC; ++l)
        if (j0 + l < V) z[j0 + l] = t_acc[l];
}

// What sender j emits toward the gather, with every per-sender factor folded in once per bounce:
//   physical = 1:  rho_j (.) L_j / pi                        (radiance leaving j; the 1/pi of G_ij)
//   physical = 0:  rho_j (.) E_j / Z_j  (0 when Z_j = 0: a lone voxel sends nothing)
// rho multiplies at the sender: the reflection happens at j (docs/VOXEL_LTF.md).
__kernel void ltf_senders(__global const float4* restrict light, __global const float4* restrict albedo,
                          __global const float* restrict z, const int physical, const int V,
                          __global float4* restrict sender) {
    const int j = get_global_id(0);
    if (j >= V) return;
    float scale = LTF_INV_PI;
    if (!physical) {
        const float zj = z[j];
        scale = zj > 0.0f ? 1.0f / zj : 0.0f;
    }
    sender[j] = (float4)(albedo[j].xyz * light[j].xyz * scale, 0.0f);
}

// AsWritten's running total E^0 + ... + E^t (Eq. 30): total += e.
__kernel void ltf_accumulate(__global float4* restrict total, __global const float4* restrict e, const int V) {
    const int i = get_global_id(0);
    if (i >= V) return;
    total[i] = (float4)(total[i].xyz + e[i].xyz, 0.0f);
}

// Energy diagnostics: partial[offset + group] = sum over this group's voxels of luminance(a - b) (has_b) or
// luminance(a). The host sums the partials in double after one download.
__kernel __attribute__((reqd_work_group_size(LTF_LOCAL, 1, 1)))
void ltf_energy(__global const float4* restrict a, __global const float4* restrict b, const int has_b, const int V,
                __global float* restrict partial, const int offset) {
    __local float part[LTF_LOCAL];
    const int i = get_global_id(0), lid = get_local_id(0);
    float e = 0.0f;
    if (i < V) {
        float4 x = a[i];
        if (has_b) x -= b[i];
        e = ngi_luminance(x.xyz);
    }
    part[lid] = e;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int w = LTF_LOCAL / 2; w > 0; w /= 2) {
        if (lid < w) part[lid] += part[lid + w];
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0) partial[offset + get_group_id(0)] = part[0];
}

// ---- the gather: one bounce, O(V^2) ---------------------------------------------------------------------------

// One sender j (position q, exposed faces as mid/half, light s) added to LTF_VEC receivers (positions p*, normals
// n*), each pair gated by vis (0 or 1):  acc += vis T_ij s_j with the transfer coefficient, w = (p_j - p_i) / r,
//   physical:   T_ij = max(0, n_i . w) A_j(-w) / max(r^2, r_min^2)
//   as written: T_ij = |n_i . w| / max(r^2, r_min^2)
// A_j(-w) = sum over j's exposed faces f of max(0, -n_f . w): along each axis only the face toward the receiver
// counts, the + face when w_a < 0 and the - face when w_a > 0, which is |w_a| mid_a - w_a half_a.
// r = 0 (the receiver itself, or a coincident voxel) gives w = 0 and so exactly 0 for a finite sender light: no
// branch on j == i. 1 / max(r^2, r_min^2) comes from the same rsqrt as w (no division). No branch at all: the
// compiler vectorizes it.
static inline void ltf_pair(vfloat px, vfloat py, vfloat pz, vfloat nx, vfloat ny, vfloat nz, float4 q, float4 mid,
                            float4 half_diff, float4 s, vfloat vis, vfloat* ar, vfloat* ag, vfloat* ab) {
    const vfloat dx = q.x - px, dy = q.y - py, dz = q.z - pz;
    const vfloat r2 = dx * dx + dy * dy + dz * dz;
    const vfloat inv_r = select((vfloat)(0.0f), rsqrt(r2), r2 > 0.0f);
    const vfloat wx = dx * inv_r, wy = dy * inv_r, wz = dz * inv_r;
    const vfloat c = nx * wx + ny * wy + nz * wz;
    const vfloat inv_r2 = select((vfloat)(1.0f / (LTF_R_MIN * LTF_R_MIN)), inv_r * inv_r, r2 > LTF_R_MIN * LTF_R_MIN);
#if LTF_PHYSICAL
    const vfloat area = fabs(wx) * mid.x + fabs(wy) * mid.y + fabs(wz) * mid.z -
                        (wx * half_diff.x + wy * half_diff.y + wz * half_diff.z);
    const vfloat t = fmax(c, 0.0f) * area * inv_r2 * vis;
#else
    const vfloat t = fabs(c) * inv_r2 * vis;
#endif
    *ar += t * s.x;
    *ag += t * s.y;
    *ab += t * s.z;
}

// out_i = [first ? base_i (physical: the direct light d_i) or 0 : out_i] + sum_{j in [j0, j1), j != i} [V_ij]
//         T_ij sender_j, for the senders [j0, j1) of this launch; LTF_VEC receivers i per work-item. The host
// splits [0, V) over launches so that no work-item loops more than the driver allows (llvmpipe); the running sum
// is carried in out in the same order for any split, so the result is bit-identical. Global size: ceil(V /
// LTF_VEC) rounded up to LTF_LOCAL. mid, half_diff: ltf_pack_geometry's exposed faces (physical only).
#if LTF_TILED
__kernel __attribute__((reqd_work_group_size(LTF_LOCAL, 1, 1)))
#else
__kernel
#endif
void ltf_gather(__global const float4* restrict geometry, __global const float4* restrict mid,
                __global const float4* restrict half_diff, __global const float4* restrict sender,
                __global const float4* restrict normal, __global const float4* restrict base,
                __global const uint* restrict vis, const int V, const int words, const int j0, const int j1,
                const int first, __global float4* restrict out) {
    const int i0 = get_global_id(0) * LTF_VEC;
#if !LTF_TILED
    if (i0 >= V) return;
#endif
    // The receivers' lanes. Lanes past V (and, tiled, whole work-items past V, which must still reach the
    // barriers) work on voxel V - 1 and store nothing; they never read out[V - 1], which its owner writes.
    float t_px[LTF_VEC], t_py[LTF_VEC], t_pz[LTF_VEC], t_nx[LTF_VEC], t_ny[LTF_VEC], t_nz[LTF_VEC];
    float t_ar[LTF_VEC], t_ag[LTF_VEC], t_ab[LTF_VEC];
    for (int k = 0; k < LTF_VEC; ++k) {
        const int r = min(i0 + k, V - 1);
        const float4 g = geometry[r], nn = normal[r];
        t_px[k] = g.x; t_py[k] = g.y; t_pz[k] = g.z;
        t_nx[k] = nn.x; t_ny[k] = nn.y; t_nz[k] = nn.z;
        float4 a = (float4)(0.0f);
        if (i0 + k < V) {
#if LTF_PHYSICAL
            a = first ? base[r] : out[r];
#else
            if (!first) a = out[r];
#endif
        }
        t_ar[k] = a.x; t_ag[k] = a.y; t_ab[k] = a.z;
    }
    const vfloat px = VLOAD_F(t_px), py = VLOAD_F(t_py), pz = VLOAD_F(t_pz);
    const vfloat nx = VLOAD_F(t_nx), ny = VLOAD_F(t_ny), nz = VLOAD_F(t_nz);
    vfloat ar = VLOAD_F(t_ar), ag = VLOAD_F(t_ag), ab = VLOAD_F(t_ab);
#if LTF_TILED
    __local float4 tile_geometry[LTF_LOCAL], tile_sender[LTF_LOCAL];
#if LTF_PHYSICAL
    __local float4 tile_mid[LTF_LOCAL], tile_half[LTF_LOCAL];
#endif
#if LTF_VIS
    __global const uint* row = vis + (size_t)min(i0, V - 1) * (size_t)words;
#endif
    const int lid = get_local_id(0);
    for (int jt = j0; jt < j1; jt += LTF_LOCAL) {
        const int js = min(jt + lid, j1 - 1);  // a partial last tile repeats a sender it never reads
        barrier(CLK_LOCAL_MEM_FENCE);          // the previous tile is no longer read
        tile_geometry[lid] = geometry[js];
        tile_sender[lid] = sender[js];
#if LTF_PHYSICAL
        tile_mid[lid] = mid[js];
        tile_half[lid] = half_diff[js];
#endif
        barrier(CLK_LOCAL_MEM_FENCE);
        const int m = min(LTF_LOCAL, j1 - jt);
        for (int k = 0; k < m; ++k) {
            const int j = jt + k;
#if LTF_VIS
            const float v = (float)((row[j >> 5] >> (j & 31)) & 1u);
#else
            const float v = 1.0f;
#endif
#if LTF_PHYSICAL
            ltf_pair(px, py, pz, nx, ny, nz, tile_geometry[k], tile_mid[k], tile_half[k], tile_sender[k], v, &ar, &ag, &ab);
#else
            ltf_pair(px, py, pz, nx, ny, nz, tile_geometry[k], (float4)(0.0f), (float4)(0.0f), tile_sender[k], v, &ar,
                     &ag, &ab);
#endif
        }
    }
#elif LTF_VIS
    // Blocks of the senders that share one word of every lane's visibility row.
    for (int jb = j0; jb < j1;) {
        const int je = min(j1, (jb & ~31) + 32);
        uint t_w[LTF_VEC];
        for (int k = 0; k < LTF_VEC; ++k) t_w[k] = vis[(size_t)min(i0 + k, V - 1) * (size_t)words + (jb >> 5)];
        const vuint word = VLOAD_U(t_w);
        for (int j = jb; j < je; ++j) {
            const vfloat v = CONVERT_VFLOAT((word >> (uint)(j & 31)) & 1u);
#if LTF_PHYSICAL
            ltf_pair(px, py, pz, nx, ny, nz, geometry[j], mid[j], half_diff[j], sender[j], v, &ar, &ag, &ab);
#else
            ltf_pair(px, py, pz, nx, ny, nz, geometry[j], (float4)(0.0f), (float4)(0.0f), sender[j], v, &ar, &ag, &ab);
#endif
        }
        jb = je;
    }
#else
    for (int j = j0; j < j1; ++j) {
#if LTF_PHYSICAL
        ltf_pair(px, py, pz, nx, ny, nz, geometry[j], mid[j], half_diff[j], sender[j], (vfloat)(1.0f), &ar, &ag, &ab);
#else
        ltf_pair(px, py, pz, nx, ny, nz, geometry[j], (float4)(0.0f), (float4)(0.0f), sender[j], (vfloat)(1.0f), &ar,
                 &ag, &ab);
#endif
    }
#endif
    VSTORE_F(ar, t_ar);
    VSTORE_F(ag, t_ag);
    VSTORE_F(ab, t_ab);
    for (int k = 0; k < LTF_VEC; ++k)
        if (i0 + k < V) out[i0 + k] = (float4)(t_ar[k], t_ag[k], t_ab[k], 0.0f);
}

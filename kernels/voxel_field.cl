// Voxel radiance field (seed 004): docs/VOXEL_FIELD.md; host side voxel_field.cpp (render_voxel_field). The program
// "voxel_field" puts the scene (scene.cl), its lighting (lighting.cl, patch_weights.cl) and the SH basis
// (sh_basis.cl) before this file.
// Per surface voxel (kernels/voxel_compact.cl made the list): probe[V][3] the probe point, shade_normal[V][3] the
// unit normal at it (normalize(probe - centre): the voxel's Eq. 3 normal except at creases, docs/VOXEL_FIELD.md),
// cells[V] = (x, y, z, exposed-face mask). One work-item per voxel (per voxel face in vf_face_lighting).
// Random numbers: pcg4d of (block id, sample, seed ^ salt): a voxel's values do not depend on the other voxels, the
// work-group size or the split of its samples over launches. Every kernel takes samples [first, last) of its count
// and keeps running sums in its output between launches (llvmpipe's loop limit), finishing in the last launch.

#define VF_SALT_SH 0x3c6ef372u
#define VF_SALT_SUN 0xa54ff53au
#define VF_SALT_DIRECT 0x510e527fu
#define VF_SALT_LIGHTING 0x9b05688cu
#define VF_SALT_FACE 0x1f83d9abu
#define VF_SH 27  // coefficients per voxel: [channel][9] (docs/CONVENTIONS.md section 14)

// Sun visibility: vis[i] = the fraction of `count` rays from the probe point toward uniform points of the sun's
// cone that meet no block (the voxel itself included). The host skips it when the sun is off.
__kernel void vf_sun_visibility(SCENE_ARGS, __global const float* probe, __global const int4* cells, int nvox,
                                int count, int first, int last, uint seed, __global float* vis,
                                __global uint* rays_out) {
    const int i = get_global_id(0);
    if (i >= nvox) return;
    MAKE_SCENE(s);
    const float3 p = vload3(i, probe);
    uint rays = first > 0 ? rays_out[i] : 0u;
    float open = first > 0 ? vis[i] : 0.0f;
    const float3 sd = lv(light, L_SUN_DIR);
    const float cmax = light[L_SUN_COS];
    float3 t, b;
    onb(sd, &t, &b);
    Rng r;
    r.a = (uint)block_id(cells[i], sx, sy); r.c = seed ^ VF_SALT_SUN;
    for (int k = first; k < last; ++k) {
        r.b = (uint)k; r.n = 0;
        const float2 u = rng2(&r);
        const float z = 1.0f - u.x * (1.0f - cmax), sr = sqrt(fmax(0.0f, 1.0f - z * z)), phi = 2.0f * M_PI_F * u.y;
        const float3 w = t * (sr * cos(phi)) + b * (sr * sin(phi)) + sd * z;
        if (trace(&s, p, w, T_INF, &rays).mat == 0) open += 1.0f;
    }
    vis[i] = last >= count ? open / (float)count : open;
    rays_out[i] = rays;
}

// SH projection of the radiance arriving at the probe point: directions j = a + m b of M = m^2 strata
// (cell (a, b) of (u, v) jittered; z = 1 - 2u, phi = 2 pi v, pole +z, phi = atan2(y, x)); per direction L(w) = sky
// radiance (sun disc excluded) on a miss, 0 on the voxel itself, emission + albedo * (one lighting_sample with
// max_bounces - 1 further bounces) on another block. sh[i][c][k] accumulates L_c(w_j) Y_k(w_j); the last launch
// scales by 4 pi / M and adds the sun as a delta, E_sun * vis[i] * Y_k(sun direction).
// indirect_only = 1 keeps only light that has bounced at least once (what a probe bake adds to an engine's own
// direct light): a miss (sky), a block's emission and the sun give 0, a block gives albedo * (lighting_sample),
// drawn from the same random numbers as in the full projection, so full(B) - full(0) = indirect(B) up to rounding.
__kernel void vf_sh(SCENE_ARGS, __global const float* probe, __global const int4* cells, int nvox, int m,
                    int first, int last, int max_bounces, int rr_start, int indirect_only, uint seed,
                    __global const float* sun_vis, __global float* sh, __global uint* rays_out) {
    const int i = get_global_id(0);
    if (i >= nvox) return;
    MAKE_SCENE(s);
    const int id = block_id(cells[i], sx, sy);
    const float3 p = vload3(i, probe);
    __global float* out = sh + (size_t)i * VF_SH;
    uint rays = first > 0 ? rays_out[i] : 0u;
    float acc[VF_SH];
    for (int k = 0; k < VF_SH; ++k) acc[k] = first > 0 ? out[k] : 0.0f;
    const int total = m * m;
    const float inv_m = 1.0f / (float)m;
    // The first hit is path vertex 1 of the reference's estimator: its Russian roulette starts one bounce earlier.
    const int inner_rr = max(rr_start - 1, 0);
    Rng r;
    r.a = (uint)id; r.c = seed ^ VF_SALT_SH;
    float Y[9];
    for (int j = first; j < last; ++j) {
        r.b = (uint)j; r.n = 0;
        const float2 u = rng2(&r);
        const int b = j / m, a = j - b * m;
        const float z = 1.0f - 2.0f * (((float)a + u.x) * inv_m);
        const float phi = 2.0f * M_PI_F * (((float)b + u.y) * inv_m);
        const float sr = sqrt(fmax(0.0f, 1.0f - z * z));
        const float3 w = (float3)(sr * cos(phi), sr * sin(phi), z);
        const Hit h = trace(&s, p, w, T_INF, &rays);
        float3 L = (float3)(0.0f);
        if (h.mat == 0) {
            if (!indirect_only) L = sky_radiance(light, w);
        } else if (block_id((int4)(h.cell, 0), sx, sy) != id) {
            if (!indirect_only) L = mats[2 * h.mat + 1].xyz;
            if (max_bounces > 0)
                L += mats[2 * h.mat].xyz * lighting_sample(&s, hit_origin(&s, p, w, &h), hit_normal(&s, w, &h),
                                                           max_bounces - 1, inner_rr, &r, &rays);
        }
        sh9(w.x, w.y, w.z, Y);
        for (int k = 0; k < 9; ++k) {
            acc[k] += L.x * Y[k];
            acc[9 + k] += L.y * Y[k];
            acc[18 + k] += L.z * Y[k];
        }
    }
    if (last >= total) {
        const float3 sd = lv(light, L_SUN_DIR), E = indirect_only ? (float3)(0.0f) : lv(light, L_SUN_E) * sun_vis[i];
        const float scale = 4.0f * M_PI_F / (float)total;
        sh9(sd.x, sd.y, sd.z, Y);
        for (int k = 0; k < 9; ++k) {
            acc[k] = acc[k] * scale + E.x * Y[k];
            acc[9 + k] = acc[9 + k] * scale + E.y * Y[k];
            acc[18 + k] = acc[18 + k] * scale + E.z * Y[k];
        }
    }
    for (int k = 0; k < VF_SH; ++k) out[k] = acc[k];
    rays_out[i] = rays;
}

// Lighting at the probe point with the shading normal: the mean of spp lighting_samples with max_bounces bounces
// (0: the "direct" output). out[i][3].
__kernel void vf_probe_lighting(SCENE_ARGS, __global const float* probe, __global const float* shade_normal,
                                __global const int4* cells, int nvox, int spp, int first, int last, int max_bounces,
                                int rr_start, uint seed, __global float* out, __global uint* rays_out) {
    const int i = get_global_id(0);
    if (i >= nvox) return;
    MAKE_SCENE(s);
    const float3 p = vload3(i, probe), n = vload3(i, shade_normal);
    uint rays = first > 0 ? rays_out[i] : 0u;
    float3 sum = first > 0 ? vload3(i, out) : (float3)(0.0f);
    Rng r;
    r.a = (uint)block_id(cells[i], sx, sy); r.c = seed ^ (max_bounces == 0 ? VF_SALT_DIRECT : VF_SALT_LIGHTING);
    for (int k = first; k < last; ++k) {
        r.b = (uint)k; r.n = 0;
        sum += lighting_sample(&s, p, n, max_bounces, rr_start, &r, &rays);
    }
    vstore3(last >= spp ? sum / (float)spp : sum, i, out);
    rays_out[i] = rays;
}

// Lighting of each exposed face: the mean of spp lighting_samples at uniform random points of the face (lifted
// RAY_OFFSET off it) with its normal; 0 for faces that are not exposed. out[i][face][3]; global size 6 V.
__kernel void vf_face_lighting(SCENE_ARGS, __global const int4* cells, int nvox, int spp, int first, int last,
                               int max_bounces, int rr_start, uint seed, __global float* out, __global uint* rays_out) {
    const int g = get_global_id(0);
    if (g >= 6 * nvox) return;
    MAKE_SCENE(s);
    const int i = g / 6, f = g - 6 * i;
    const int4 c = cells[i];
    if (((c.w >> f) & 1) == 0) {
        vstore3((float3)(0.0f), g, out);
        rays_out[g] = 0u;
        return;
    }
    const float3 n = face_normal(f);
    uint rays = first > 0 ? rays_out[g] : 0u;
    float3 sum = first > 0 ? vload3(g, out) : (float3)(0.0f);
    Rng r;
    r.a = (uint)(6 * block_id(c, sx, sy) + f); r.c = seed ^ VF_SALT_FACE;
    for (int k = first; k < last; ++k) {
        r.b = (uint)k; r.n = 0;
        const float3 q = face_point(c.xyz, f, rng2(&r)) + n * RAY_OFFSET;
        sum += lighting_sample(&s, q, n, max_bounces, rr_start, &r, &rays);
    }
    vstore3(last >= spp ? sum / (float)spp : sum, g, out);
    rays_out[g] = rays;
}

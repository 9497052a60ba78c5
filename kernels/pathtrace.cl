// Voxel path tracer: feature buffers of the six faces of the camera cluster and the path-traced reference
// lighting of one face. Host side: host/src/render/renderer.cpp; definitions: docs/RENDERER.md. The program
// "pathtrace" (host/src/runtime/programs.cpp) puts the scene (scene.cl) and its lighting (lighting.cl,
// patch_weights.cl) before this file. One work-item per pixel; every random number comes from a counter-based hash (rng.cl) of (pixel,
// sample, seed, counter), so the result does not depend on scheduling, work-group size or device.
//
// Build options, the host's: SKY_DEPTH (depth reported where the primary ray escapes, finite on purpose), from
// render/tracer_constants.hpp; the feature planes per face F_ALBEDO ... F_ENV, F_CHANNELS (the frame planes of
// ngi/pipeline.hpp, pipeline/frame_planes.hpp).
#if !defined(SKY_DEPTH) || !defined(F_ALBEDO) || !defined(F_NORMAL) || !defined(F_DEPTH) || !defined(F_DIRECT) || \
    !defined(F_EMISSION) || !defined(F_ENV) || !defined(F_CHANNELS)
#error "pathtrace.cl is built by renderer.cpp, which defines SKY_DEPTH and the feature planes (F_*) as build options"
#endif

// Feature buffers of all six faces: out[(face * F_CHANNELS + channel) * n * n + row * n + col].
// global size: 6 n^2 (one work-item per pixel).
// Samples [first, last) of spp: the host splits spp into chunks on drivers that end loops after a fixed number of
// iterations (llvmpipe: 65,535 per work-item, docs/RELIABILITY.md). The running sum of direct light is kept in
// `out` between chunks and divided by spp in the last one; since the sum continues in the same order, any split
// gives bit-identical results. Rays of the primary hit are counted in the first chunk only.
__kernel void pt_features(SCENE_ARGS, __global const float* cam, int n, int spp, int first, int last, uint seed,
                          __global float* out, __global uint* rays_out) {
    const int gid = get_global_id(0);
    const int npix = n * n;
    if (gid >= 6 * npix) return;
    MAKE_SCENE(s);
    const int f = gid / npix, pix = gid - f * npix, row = pix / n, col = pix - row * n;
    float3 look;
    const float3 o = (float3)(cam[0], cam[1], cam[2]);
    const float3 d = pixel_ray(cam, f, col, row, n, &look);
    uint rays = 0;
    const Hit h = trace(&s, o, d, T_INF, &rays);
    if (first > 0) rays = rays_out[gid];
    float3 albedo = (float3)(0.0f), normal = (float3)(0.0f), direct = (float3)(0.0f), emission = (float3)(0.0f),
           env = (float3)(0.0f);
    float depth = SKY_DEPTH;
    __global float* q = out + (size_t)f * F_CHANNELS * npix + pix;
    if (h.mat == 0) {
        env = sky_radiance(light, d);
    } else {
        albedo = mats[2 * h.mat].xyz;
        emission = mats[2 * h.mat + 1].xyz;
        const float3 ng = hit_normal(&s, d, &h);
        normal = hit_shading_normal(&s, ng, &h);
        depth = h.t * dot(d, look);  // planar depth along the face's look axis
        const float3 p = hit_origin(&s, o, d, &h);
        if (first > 0)
            direct = (float3)(q[(size_t)F_DIRECT * npix], q[(size_t)(F_DIRECT + 1) * npix],
                              q[(size_t)(F_DIRECT + 2) * npix]);
        Rng r;
        r.a = (uint)gid; r.c = seed ^ 0x68e31da4u;
        for (int i = first; i < last; ++i) {
            r.b = (uint)i; r.n = 0;
            direct += lighting_sample(&s, p, ng, 0, 0, &r, &rays);
        }
        if (last >= spp) direct /= (float)max(spp, 1);
    }
    store3(q, F_ALBEDO, npix, albedo);
    store3(q, F_NORMAL, npix, normal);
    q[(size_t)F_DEPTH * npix] = depth;
    store3(q, F_DIRECT, npix, direct);
    store3(q, F_EMISSION, npix, emission);
    store3(q, F_ENV, npix, env);
    rays_out[gid] = rays;
}

// Reference lighting of face `face`: mean[c * n^2 + pix] and the variance of that mean (sample variance / spp).
// Zero where the primary ray escapes (sky has no surface to light). global size: n^2.
// Samples [first, last) of spp, as pt_features: between chunks mean_out holds the running mean and var_out the
// running sum of squared deviations (Welford's M2), so any split continues the same recurrence bit for bit; the
// last chunk turns M2 into the variance of the mean.
__kernel void pt_reference(SCENE_ARGS, __global const float* cam, int face, int n, int spp, int first, int last,
                           int max_bounces, int rr_start, uint seed, __global float* mean_out,
                           __global float* var_out, __global uint* rays_out) {
    const int pix = get_global_id(0);
    const int npix = n * n;
    if (pix >= npix) return;
    MAKE_SCENE(s);
    float3 o, d, look;
    uint rays = 0;
    const Hit h = primary_hit(&s, cam, face, pix, n, &o, &d, &look, &rays);
    if (first > 0) rays = rays_out[pix];
    float3 mean = (float3)(0.0f), m2 = (float3)(0.0f);
    if (first > 0) {
        mean = (float3)(mean_out[pix], mean_out[npix + pix], mean_out[2 * npix + pix]);
        m2 = (float3)(var_out[pix], var_out[npix + pix], var_out[2 * npix + pix]);
    }
    if (h.mat != 0) {
        const float3 p = hit_origin(&s, o, d, &h), nrm = hit_normal(&s, d, &h);
        Rng r;
        r.a = (uint)(face * npix + pix); r.c = seed ^ 0x2545f491u;
        for (int i = first; i < last; ++i) {  // Welford: stable mean and variance in float
            r.b = (uint)i; r.n = 0;
            const float3 x = lighting_sample(&s, p, nrm, max_bounces, rr_start, &r, &rays);
            const float3 dx = x - mean;
            mean += dx / (float)(i + 1);
            m2 += dx * (x - mean);
        }
    }
    const float3 out2 = last < spp ? m2 : spp > 1 ? m2 / ((float)(spp - 1) * (float)spp) : (float3)(0.0f);
    mean_out[pix] = mean.x; mean_out[npix + pix] = mean.y; mean_out[2 * npix + pix] = mean.z;
    var_out[pix] = out2.x; var_out[npix + pix] = out2.y; var_out[2 * npix + pix] = out2.z;
    rays_out[pix] = rays;
}

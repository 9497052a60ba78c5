// Ray-traced ambient occlusion of one camera face (Renderer::render_ao, host/src/render/ao_geometry.cpp). The program
// "ao_geometry" is the scene (scene.cl, with rng.cl and geometry.cl for the cosine-sampled rays), this file and
// render_geometry.cl, without the path tracer's lighting: seed 001's data (ngi ao-data) renders both per view, and
// one program compiles faster than two on PoCL (each program pays a fixed cost).

// Ambient occlusion (seed 001): the accessibility of the surface seen through pixel (col, row) of face `face` =
// the fraction of cosine-weighted hemisphere rays from the hit point that travel max_dist without meeting a solid
// block (1 = unoccluded, 0 = enclosed); for a cosine-weighted estimator that is (1/pi) * integral of V cos over the
// hemisphere. 1 where the primary ray escapes (no surface: evaluations mask it). out[pix]; global size n^2.
// Rays [first, last) of spp, as pt_features: the running count of unoccluded rays is kept in `out` between chunks
// and divided by spp in the last one, so any split gives the same bits.
__kernel void pt_ao(SCENE_ARGS, __global const float* cam, int face, int n, int spp, int first, int last,
                    float max_dist, uint seed, __global float* out) {
    const int pix = get_global_id(0);
    const int npix = n * n;
    if (pix >= npix) return;
    MAKE_SCENE(s);
    float3 o, d, look;
    uint rays = 0;
    const Hit h = primary_hit(&s, cam, face, pix, n, &o, &d, &look, &rays);
    if (h.mat == 0) {
        out[pix] = 1.0f;
        return;
    }
    const float3 p = hit_origin(&s, o, d, &h), nrm = hit_normal(&s, d, &h);
    float open = first > 0 ? out[pix] : 0.0f;
    Rng r;
    r.a = (uint)(face * npix + pix); r.c = seed ^ 0x5bd1e995u;
    for (int i = first; i < last; ++i) {
        r.b = (uint)i; r.n = 0;
        const float3 w = cosine_sample(nrm, rng2(&r));
        if (!occluded(&s, p + RAY_OFFSET * nrm, w, max_dist, &rays)) open += 1.0f;
    }
    out[pix] = last >= spp ? open / (float)max(spp, 1) : open;
}

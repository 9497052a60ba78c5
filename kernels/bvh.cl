// Triangle BVH traversal: closest-hit and any-hit queries over the flattened tree of render/bvh.cpp, with
// watertight ray/triangle intersection (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2013:
// a ray through a shared edge or vertex hits at least one of the triangles that share it, so closed meshes do not
// leak light). Listed before scene.cl in the path tracer's programs, and the program "bvh" of its own, for
// bvh_trace_rays (the BVH tests and perf/bench_bvh); geometry.cl comes first in both (safe_inv).
//
// Layout (render/bvh.hpp, struct Bvh): node i = nodes[2i] (lo.xyz, a) and nodes[2i+1] (hi.xyz, b), a and b being
// int bit patterns; leaf (b >= 1): triangles a .. a+b-1; interior (b <= 0): left child i+1, right child a.
// Triangles: tv[3k .. 3k+2] = vertices (xyz); info[k] = (vertex indices, palette index).
#ifndef BVH_STACK
#error "bvh.cl is built with the BVH constants as -D options (render/bvh.cpp: bvh_defines)"
#endif

// Watertightness needs the edge functions of a shared edge to be exact negatives in the two triangles that share
// it: a*b - c*d must not become fma(a, b, -c*d) (OpenCL C contracts by default, and the contracted form is not
// antisymmetric; the paper falls back to double instead, which OpenCL 1.2 devices need not have). Contraction is
// switched back on at the end of this file for the code that follows it in the program.
#pragma OPENCL FP_CONTRACT OFF

typedef struct {
    float3 o, d, inv;  // origin, direction, 1 / direction (huge but finite where a component is 0)
    int kx, ky, kz;    // axis permutation: kz = the largest |d| component
    float sx, sy, sz;  // shear constants
} BvhRay;

static inline float bvh_comp(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

static inline BvhRay bvh_ray(float3 o, float3 d) {
    BvhRay r;
    r.o = o; r.d = d;
    r.inv = (float3)(safe_inv(d.x), safe_inv(d.y), safe_inv(d.z));
    const float3 ad = fabs(d);
    r.kz = ad.x >= ad.y && ad.x >= ad.z ? 0 : (ad.y >= ad.z ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    const float dz = bvh_comp(d, r.kz);
    if (dz < 0.0f) { const int k = r.kx; r.kx = r.ky; r.ky = k; }  // keep the winding
    r.sx = bvh_comp(d, r.kx) / dz;
    r.sy = bvh_comp(d, r.ky) / dz;
    r.sz = 1.0f / dz;
    return r;
}

// Hit with 0 < t <= tmax: writes t and the barycentric weights (u, v) of vertices b and c. Same arithmetic as
// render/bvh.cpp's intersect_triangle (the tests' brute-force reference).
static inline int bvh_triangle(const BvhRay* r, float3 a, float3 b, float3 c, float tmax, float* t, float2* uv) {
    const float3 A = a - r->o, B = b - r->o, C = c - r->o;
    const float az = bvh_comp(A, r->kz), bz = bvh_comp(B, r->kz), cz = bvh_comp(C, r->kz);
    const float ax = bvh_comp(A, r->kx) - r->sx * az, ay = bvh_comp(A, r->ky) - r->sy * az;
    const float bx = bvh_comp(B, r->kx) - r->sx * bz, by = bvh_comp(B, r->ky) - r->sy * bz;
    const float cx = bvh_comp(C, r->kx) - r->sx * cz, cy = bvh_comp(C, r->ky) - r->sy * cz;
    const float U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return 0;
    const float det = U + V + W;
    if (det == 0.0f) return 0;
    const float T = U * (r->sz * az) + V * (r->sz * bz) + W * (r->sz * cz);
    if (det > 0.0f ? (T <= 0.0f || T > tmax * det) : (T >= 0.0f || T < tmax * det)) return 0;
    const float inv = 1.0f / det;
    *t = T * inv;
    *uv = (float2)(V * inv, W * inv);
    return 1;
}

// Entry distance of the ray into the box within [0, tmax], or INFINITY when it misses. Conservative: the exit
// distance is scaled by 1 + 2 gamma(3) (Ize, "Robust BVH Ray Traversal", JCGT 2013), so that the rounding of the
// slab distances never loses a box whose face or corner a triangle's vertex lies on (a ray through that vertex
// would otherwise leak through a closed mesh).
static inline float bvh_box(const BvhRay* r, float4 lo, float4 hi, float tmax) {
    const float3 t0 = (lo.xyz - r->o) * r->inv, t1 = (hi.xyz - r->o) * r->inv;
    const float3 tn = fmin(t0, t1), tf = fmax(t0, t1);
    const float enter = fmax(fmax(tn.x, tn.y), fmax(tn.z, 0.0f));
    const float exit = fmin(fmin(tf.x, tf.y) * 1.0000004f, fmin(tf.z * 1.0000004f, tmax));
    return enter <= exit ? enter : INFINITY;
}

// Closest triangle along the ray within (0, tmax]: its BVH slot (-1 if none), *t and *uv. With `any` set, returns
// the first hit found instead (shadow rays), *t and *uv then belong to that hit. *steps counts node visits and
// triangle tests (the loop iterations a driver with a per-work-item loop budget sees).
static inline int bvh_intersect(__global const float4* nodes, __global const float4* tv, const BvhRay* r,
                                float tmax, int any, float* t, float2* uv, uint* steps) {
    int stack[BVH_STACK];
    float stack_t[BVH_STACK];
    int sp = 0, hit = -1, node = 0;
    if (bvh_box(r, nodes[0], nodes[1], tmax) == INFINITY) return -1;
    for (;;) {
        ++*steps;
        const float4 lo = nodes[2 * node], hi = nodes[2 * node + 1];
        const int a = as_int(lo.w), b = as_int(hi.w);
        if (b > 0) {
            for (int k = a; k < a + b; ++k) {
                ++*steps;
                float tk;
                float2 uvk;
                if (bvh_triangle(r, tv[3 * k].xyz, tv[3 * k + 1].xyz, tv[3 * k + 2].xyz, tmax, &tk, &uvk)) {
                    tmax = tk; *t = tk; *uv = uvk; hit = k;
                    if (any) return hit;
                }
            }
        } else {
            const int l = node + 1, rr = a;
            const float tl = bvh_box(r, nodes[2 * l], nodes[2 * l + 1], tmax);
            const float tr = bvh_box(r, nodes[2 * rr], nodes[2 * rr + 1], tmax);
            if (tl != INFINITY && tr != INFINITY) {
                const int near = tl <= tr ? l : rr;
                stack[sp] = tl <= tr ? rr : l;
                stack_t[sp] = fmax(tl, tr);
                sp = min(sp + 1, BVH_STACK - 1);  // the builder keeps the depth below BVH_STACK
                node = near;
                continue;
            }
            if (tl != INFINITY) { node = l; continue; }
            if (tr != INFINITY) { node = rr; continue; }
        }
        // Next pending subtree that can still hold a closer hit.
        node = -1;
        while (sp > 0) {
            --sp;
            if (stack_t[sp] <= tmax) { node = stack[sp]; break; }
        }
        if (node < 0) break;
    }
    return hit;
}

// Closest hits of a batch of rays (tests and benchmarks): ray i = origin rays[2i].xyz, direction rays[2i+1].xyz,
// tmax rays[2i].w. hits[i] = (t, bits(BVH slot or -1), u, v); steps[i] = node visits + triangle tests.
// global size: count. A mesh with no triangles (ntri == 0) misses every ray.
__kernel void bvh_trace_rays(__global const float4* nodes, __global const float4* tv, int ntri,
                             __global const float4* rays, int count, int any, __global float4* hits,
                             __global uint* steps) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const float4 ro = rays[2 * i], rd = rays[2 * i + 1];
    const BvhRay r = bvh_ray(ro.xyz, rd.xyz);
    float t = 0.0f;
    float2 uv = (float2)(0.0f);
    uint n = 0;
    const int k = ntri > 0 ? bvh_intersect(nodes, tv, &r, ro.w, any, &t, &uv, &n) : -1;
    hits[i] = (float4)(k >= 0 ? t : 0.0f, as_float(k), uv.x, uv.y);
    steps[i] = n;
}

#pragma OPENCL FP_CONTRACT ON

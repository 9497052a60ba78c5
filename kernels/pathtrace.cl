// Voxel path tracer: feature buffers of the six faces of the camera cluster and the path-traced reference
// lighting of one face. Host side: host/src/render/renderer.cpp; definitions: docs/RENDERER.md.
//
// Scene: a grid of palette indices (uchar, 0 = air), x + sx * (y + sy * z); block (x, y, z) covers the unit cube
// at that corner; rays are traversed with Amanatides & Woo's 3D DDA. Beside it an optional triangle mesh behind a
// BVH (kernels/bvh.cl, built before this file as the program "bvh+pathtrace"); a ray's hit is the closer of the two.
// Triangles are two-sided; light transport uses their geometric normal (facing the incoming ray), the features
// and the AO network's geometry the interpolated vertex normal.
// Lighting buffers hold irradiance / pi ("lighting without albedo"); emission and sky values are radiance.
// One work-item per pixel; every random number comes from a counter-based hash of (pixel, sample, seed, counter),
// so the result does not depend on scheduling, work-group size or device.

// Layout of the `light` parameter array: L_SUN_DIR (3, unit vector toward the sun), L_SUN_E (3, sun irradiance
// facing the sun), L_SUN_COS (1, cosine of the sun's angular radius), L_ZENITH, L_HORIZON, L_GROUND (3 each, sky
// radiance up, at the horizon, from below it), L_GLOW (3, the sun-centred glow), then the rectangular area light:
// L_AREA_CENTRE, L_AREA_U, L_AREA_V (3 each: centre and half-edge vectors), L_AREA_RADIANCE (3; 0 = off),
// L_AREA_NORMAL (3, unit, the emitting side) and L_AREA_AREA (1, m^2). The offsets are defined once, in
// renderer.cpp (kLightLayout), and arrive here as -D build options.
// Also build options, the host's: SKY_DEPTH (depth reported where the primary ray escapes, finite on purpose) and
// RAY_OFFSET (secondary rays start this far off the surface, along the normal), from render/tracer_constants.hpp;
// the feature planes per face F_ALBEDO ... F_ENV, F_CHANNELS (the frame planes of ngi/pipeline.hpp,
// pipeline/frame_planes.hpp); the luminance weights LUMA_R, LUMA_G, LUMA_B of common.cl's ngi_luminance().
#if !defined(L_SUN_DIR) || !defined(L_AREA_AREA) || !defined(SKY_DEPTH) || !defined(RAY_OFFSET) || \
    !defined(F_CHANNELS) || !defined(F_ENV) || !defined(LUMA_R)
#error "pathtrace.cl is built by renderer.cpp, which defines the light layout (L_*), SKY_DEPTH, RAY_OFFSET, the feature planes (F_*) and the luminance weights (LUMA_*) as build options"
#endif

#define T_INF 1.0e30f

typedef struct {
    __global const uchar* grid;
    int3 dims;
    __global const float4* mats;   // per material: albedo, emission (lamp level applied)
    __global const int4* lights;   // emissive faces that border air: cell xyz, face id
    __global const float* cdf;     // cumulative selection probability of lights (proportional to luminance)
    int nlights;
    float inv_total;               // 1 / sum of the luminance of all emissive faces
    __global const float* light;   // L_* parameters
    // Sky portals (renderer.cpp): region id per block (>= 0: covered air, i.e. a block somewhere above it), and
    // per region the range of its portal faces in `portals` (covered cell xyz, face id). 0 portals: no portal
    // sampling anywhere.
    __global const int* region;
    __global const int4* portals;
    __global const int2* portal_range;  // per region: first index, count
    int use_regions, use_portals;
    // Sunlit patches (renderer.cpp): block faces bordering covered air, grouped by region; per frame the
    // probability of picking each within its region (proportional to the sunlight it reflects) and the running
    // sum. Lookup of a face's index: face_slot[block] >= 0 -> face_index[6 * slot + face].
    __global const int4* patches;       // cell xyz, face id
    __global const float* patch_prob;
    __global const float* patch_cdf;
    __global const int2* patch_range;   // per region: first index, count (count 0: nothing sunlit)
    __global const int* face_slot;
    __global const int* face_index;
    int use_patches;
    // Triangles (kernels/bvh.cl layout); has_mesh 0: none (the buffers are placeholders). has_blocks 0: the grid
    // holds no block, so rays skip the DDA walk (a mesh-only scene's grid is all air).
    __global const float4* bvh_nodes;
    __global const float4* tri_v;
    __global const int4* tri_info;
    __global const float4* vnormals;
    int has_mesh, has_blocks;
} Scene;

// Where a ray first leaves covered air into open air (or out of the grid): the covered cell and its face.
typedef struct {
    int found;
    int cell;     // linear block index of the covered cell
    int face;
    float t;      // distance along the ray to the portal face
} Crossing;

typedef struct {
    float t;      // distance along the (unit) ray
    int3 cell;    // block hit; (-1, -1, -1) for a triangle
    int face;     // outward normal of the face hit: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z; -1 for a triangle
    int mat;      // palette index; 0 = the ray left the grid
    int prim;     // BVH slot of the triangle hit, -1 for a block (or no hit)
    float2 uv;    // barycentric weights of the triangle's vertices 1 and 2
} Hit;

// ---- random numbers: PCG4D (Jarzynski & Olano 2020), a counter-based hash ----------------------------------

typedef struct {
    uint a, b, c, n;
} Rng;

static inline uint4 pcg4d(uint4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

static inline float2 rng2(Rng* r) {
    uint4 v = pcg4d((uint4)(r->a, r->b, r->c, r->n++));
    return convert_float2(v.xy >> 8) * (1.0f / 16777216.0f);  // 24 bits: uniform in [0, 1)
}

// ---- geometry --------------------------------------------------------------------------------------------------

static inline float3 face_normal(int f) {
    const float s = (f & 1) ? -1.0f : 1.0f;
    const int a = f >> 1;
    return (float3)(a == 0 ? s : 0.0f, a == 1 ? s : 0.0f, a == 2 ? s : 0.0f);
}

// The point (v.x, v.y) in [0, 1]^2 of face f of block `cell` (faces are unit squares).
static inline float3 face_point(int3 cell, int f, float2 v) {
    const int a = f >> 1;
    const float plane = (f & 1) ? 0.0f : 1.0f;
    const float3 c = convert_float3(cell);
    return c + (a == 0 ? (float3)(plane, v.x, v.y) : (a == 1 ? (float3)(v.x, plane, v.y) : (float3)(v.x, v.y, plane)));
}

// Orthonormal basis around a unit vector (Duff et al. 2017, branchless).
static inline void onb(float3 n, float3* t, float3* b) {
    const float s = n.z >= 0.0f ? 1.0f : -1.0f;
    const float a = -1.0f / (s + n.z);
    const float c = n.x * n.y * a;
    *t = (float3)(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = (float3)(c, s + n.y * n.y * a, -n.y);
}

static inline float3 cosine_sample(float3 n, float2 u) {
    float3 t, b;
    onb(n, &t, &b);
    const float r = sqrt(u.x), phi = 2.0f * M_PI_F * u.y;
    return t * (r * native_cos(phi)) + b * (r * native_sin(phi)) + n * sqrt(fmax(0.0f, 1.0f - u.x));
}

static inline float safe_inv(float x) { return x != 0.0f ? 1.0f / x : 1.0e30f; }

// First solid block along o + t d (d unit), t in [0, tmax]. Counts one ray.
// With `track` set, also reports in *x the first crossing from covered air into open air (Crossing); the ray must
// start inside the grid. x->found is always written.
//
// x must never be a null pointer, even with track == 0 (use trace()): Mesa 22.3's rusticl on llvmpipe (LLVM 15)
// crashed with SIGSEGV in gallivm's NIR-to-LLVM translation (in LLVMBuildBitCast) at the first launch of
// pt_patch_weights when this took an optional `Crossing* x` and callers passed 0: after inlining, the loads and
// stores through the null private pointer stayed in code the compiler could not prove dead (guarded by the
// loop-carried `covered`), and gallivm crashed translating them. PoCL and oclgrind were fine.
static inline Hit trace_grid(const Scene* s, float3 o, float3 d, float tmax, uint* rays, int track, Crossing* x) {
    Hit h;
    h.t = tmax; h.cell = (int3)(0); h.face = 0; h.mat = 0; h.prim = -1; h.uv = (float2)(0.0f);
    x->found = 0;
    ++*rays;
    if (!s->has_blocks) return h;
    const float3 inv = (float3)(safe_inv(d.x), safe_inv(d.y), safe_inv(d.z));
    const float3 ta = -o * inv, tb = (convert_float3(s->dims) - o) * inv;
    const float3 lo = fmin(ta, tb), hi = fmax(ta, tb);
    const float t_enter = fmax(fmax(lo.x, lo.y), lo.z), t_exit = fmin(fmin(hi.x, hi.y), hi.z);
    float t = fmax(t_enter, 0.0f);
    if (t_exit < t || t > tmax) return h;
    // Axis of the last plane crossed (the face a hit block is entered through); -1 while still in the start cell
    // of a ray that begins inside the grid.
    int axis = t_enter > 0.0f ? (lo.x >= lo.y && lo.x >= lo.z ? 0 : (lo.y >= lo.z ? 1 : 2)) : -1;
    const float3 p = o + d * t;
    int3 c = clamp(convert_int3(floor(p)), (int3)(0), s->dims - 1);
    const int3 step = (int3)(d.x >= 0.0f ? 1 : -1, d.y >= 0.0f ? 1 : -1, d.z >= 0.0f ? 1 : -1);
    const float3 delta = fabs(inv);
    // The first plane crossed on each axis: the cell's far side (c + 1) where the ray moves +axis. Spelled with
    // per-component scalar compares (1 for true): oclgrind 21.10 evaluates `step > 0 ? (int3)(1) : (int3)(0)`
    // (compiled to a zext of <3 x i1>) as 255 instead of 1 in the true lanes, which broke every ray under it.
    float3 next = (convert_float3(c + (int3)(step.x > 0, step.y > 0, step.z > 0)) - o) * inv;
    // Walk the linear block index along with the cell: one add per step instead of a 3D index.
    const int sx = s->dims.x, sxy = s->dims.x * s->dims.y;
    const int3 dstep = (int3)(step.x, step.y * sx, step.z * sxy);
    int idx = c.x + sx * c.y + sxy * c.z;
    int covered = track && s->region[idx] >= 0;
    const int max_steps = s->dims.x + s->dims.y + s->dims.z + 3;
    for (int i = 0; i < max_steps; ++i) {
        const int m = s->grid[idx];
        if (m != 0) {
            if (axis < 0) {  // the ray starts inside a block: report the face it would leave backwards through
                const float3 ad = fabs(d);
                axis = ad.x >= ad.y && ad.x >= ad.z ? 0 : (ad.y >= ad.z ? 1 : 2);
            }
            const int st = axis == 0 ? step.x : (axis == 1 ? step.y : step.z);
            h.t = t; h.cell = c; h.mat = m;
            h.face = 2 * axis + (st > 0 ? 1 : 0);  // entered moving +axis: the face's normal points -axis
            return h;
        }
        const int from = idx;
        int out = 0, st;
        if (next.x < next.y && next.x < next.z) {
            axis = 0; st = step.x; t = next.x; c.x += step.x; idx += dstep.x; next.x += delta.x;
            out = (uint)c.x >= (uint)s->dims.x;
        } else if (next.y < next.z) {
            axis = 1; st = step.y; t = next.y; c.y += step.y; idx += dstep.y; next.y += delta.y;
            out = (uint)c.y >= (uint)s->dims.y;
        } else {
            axis = 2; st = step.z; t = next.z; c.z += step.z; idx += dstep.z; next.z += delta.z;
            out = (uint)c.z >= (uint)s->dims.z;
        }
        if (covered && !x->found && (out || (s->grid[idx] == 0 && s->region[idx] < 0))) {
            x->found = 1; x->cell = from; x->face = 2 * axis + (st > 0 ? 0 : 1); x->t = t;  // leaves through +axis
        }
        if (out) break;
        if (covered && !x->found) covered = s->region[idx] >= 0;
        if (t > tmax) break;
    }
    return h;
}

// The closest triangle in front of a grid hit (or within tmax when the ray leaves the grid) replaces it.
static inline void trace_mesh(const Scene* s, float3 o, float3 d, Hit* h) {
    const BvhRay r = bvh_ray(o, d);
    float t;
    float2 uv;
    uint steps = 0;
    const int k = bvh_intersect(s->bvh_nodes, s->tri_v, &r, h->t, 0, &t, &uv, &steps);
    if (k < 0) return;
    h->t = t; h->prim = k; h->uv = uv; h->mat = s->tri_info[k].w; h->cell = (int3)(-1); h->face = -1;
}

// First surface (block or triangle) along o + t d (d unit), t in [0, tmax]. Counts one ray. Crossing tracking as
// trace_grid (the crossing is of blocks only; it is used only when the ray escapes).
static inline Hit trace_crossing(const Scene* s, float3 o, float3 d, float tmax, uint* rays, int track, Crossing* x) {
    Hit h = trace_grid(s, o, d, tmax, rays, track, x);
    if (s->has_mesh) trace_mesh(s, o, d, &h);
    return h;
}

// First surface along o + t d (d unit), t in [0, tmax], no crossing tracking. Counts one ray.
static inline Hit trace(const Scene* s, float3 o, float3 d, float tmax, uint* rays) {
    Crossing unused;
    return trace_crossing(s, o, d, tmax, rays, 0, &unused);
}

// Whether any surface lies along o + t d, t in [0, tmax] (shadow rays: the BVH stops at the first triangle it
// finds). Counts one ray. Same answer as trace(...).mat != 0.
static inline int occluded(const Scene* s, float3 o, float3 d, float tmax, uint* rays) {
    Crossing unused;
    const Hit h = trace_grid(s, o, d, tmax, rays, 0, &unused);
    if (h.mat != 0) return 1;
    if (!s->has_mesh) return 0;
    const BvhRay r = bvh_ray(o, d);
    float t;
    float2 uv;
    uint steps = 0;
    return bvh_intersect(s->bvh_nodes, s->tri_v, &r, tmax, 1, &t, &uv, &steps) >= 0;
}

// Geometric normal of a triangle (BVH slot k), unit, not oriented.
static inline float3 triangle_normal(const Scene* s, int k) {
    const float3 a = s->tri_v[3 * k].xyz;
    return normalize(cross(s->tri_v[3 * k + 1].xyz - a, s->tri_v[3 * k + 2].xyz - a));
}

// The normal light transport uses at a hit: the block face's, or the triangle's geometric normal turned toward the
// side the ray came from (surfaces are two-sided).
static inline float3 hit_normal(const Scene* s, float3 d, const Hit* h) {
    if (h->prim < 0) return face_normal(h->face);
    const float3 n = triangle_normal(s, h->prim);
    return dot(n, d) > 0.0f ? -n : n;
}

// The shading normal at a hit: the block face's, or the triangle's vertex normals interpolated at the hit and
// turned to the side of the geometric normal `ng` (hit_normal).
static inline float3 hit_shading_normal(const Scene* s, float3 ng, const Hit* h) {
    if (h->prim < 0) return ng;
    const int4 v = s->tri_info[h->prim];
    const float3 n = (1.0f - h->uv.x - h->uv.y) * s->vnormals[v.x].xyz + h->uv.x * s->vnormals[v.y].xyz +
                     h->uv.y * s->vnormals[v.z].xyz;
    const float len = length(n);
    if (!(len > 1.0e-12f)) return ng;
    return dot(n, ng) < 0.0f ? -n / len : n / len;
}

// The hit point, snapped onto the face's plane (removes the DDA's rounding along the normal), then lifted off
// the surface so that a ray leaving it starts in the air cell in front of the face. On a triangle: lifted along
// hit_normal.
static inline float3 hit_origin(const Scene* s, float3 o, float3 d, const Hit* h) {
    float3 p = o + d * h->t;
    if (h->prim >= 0) return p + hit_normal(s, d, h) * RAY_OFFSET;
    const int a = h->face >> 1;
    const float plane = (a == 0 ? (float)h->cell.x : (a == 1 ? (float)h->cell.y : (float)h->cell.z)) +
                        ((h->face & 1) ? 0.0f : 1.0f);
    if (a == 0) p.x = plane; else if (a == 1) p.y = plane; else p.z = plane;
    return p + face_normal(h->face) * RAY_OFFSET;
}

// ---- lights -------------------------------------------------------------------------------------------------

static inline float3 lv(__global const float* L, int i) { return (float3)(L[i], L[i + 1], L[i + 2]); }

// Sky radiance toward unit direction d (the sun disc excluded: the sun is sampled as a light).
static inline float3 sky_radiance(__global const float* L, float3 d) {
    if (d.y < 0.0f) return lv(L, L_GROUND);
    float g = 0.5f * (1.0f + dot(d, lv(L, L_SUN_DIR)));
    g *= g; g *= g; g *= g;  // ^8: a broad glow around the sun
    return lv(L, L_HORIZON) + (lv(L, L_ZENITH) - lv(L, L_HORIZON)) * sqrt(d.y) + lv(L, L_GLOW) * g;
}

// Sun: one shadow ray toward a uniform point of the sun's cone. Irradiance E of a disc of small solid angle gives
// lighting E cos / pi.
static inline float3 sun_light(const Scene* s, float3 p, float3 n, Rng* r, uint* rays) {
    const float3 E = lv(s->light, L_SUN_E);
    const float2 u = rng2(r);
    if (E.x + E.y + E.z <= 0.0f) return (float3)(0.0f);
    const float3 sd = lv(s->light, L_SUN_DIR);
    const float cmax = s->light[L_SUN_COS];
    const float z = 1.0f - u.x * (1.0f - cmax), sr = sqrt(fmax(0.0f, 1.0f - z * z)), phi = 2.0f * M_PI_F * u.y;
    float3 t, b;
    onb(sd, &t, &b);
    const float3 w = t * (sr * native_cos(phi)) + b * (sr * native_sin(phi)) + sd * z;
    const float c = dot(n, w);
    if (c <= 0.0f) return (float3)(0.0f);
    return occluded(s, p, w, T_INF, rays) ? (float3)(0.0f) : E * (c * M_1_PI_F);
}

// Rectangular area light (not geometry: no ray ever hits it, the camera does not see it), lit by next-event
// estimation alone: a uniform point y on the rectangle (density 1 / A in area), one shadow ray x -> y. Lighting
// = (1 / pi) * integral over A of L cos_x cos_y / d^2 dA, estimated as A L cos_x cos_y / (pi d^2); one-sided
// (cos_y = 0 behind the emitting side). The shadow ray stops RAY_OFFSET short of y so that a panel flush with
// the face of a block (a ceiling light) is not hidden by that block. Called only when the light is on, so the
// random stream of every other strategy is the same as without an area light.
static inline float3 area_light(const Scene* s, float3 p, float3 n, Rng* r, uint* rays) {
    const float2 u = rng2(r);
    const float3 y = lv(s->light, L_AREA_CENTRE) + lv(s->light, L_AREA_U) * (2.0f * u.x - 1.0f) +
                     lv(s->light, L_AREA_V) * (2.0f * u.y - 1.0f);
    float3 w = y - p;
    const float d2 = dot(w, w), dist = sqrt(d2);
    if (!(dist > RAY_OFFSET)) return (float3)(0.0f);
    w /= dist;
    const float cos_x = dot(n, w), cos_y = -dot(lv(s->light, L_AREA_NORMAL), w);
    if (cos_x <= 0.0f || cos_y <= 0.0f) return (float3)(0.0f);
    if (occluded(s, p, w, dist - RAY_OFFSET, rays)) return (float3)(0.0f);  // a surface between x and y
    return lv(s->light, L_AREA_RADIANCE) * (s->light[L_AREA_AREA] * cos_x * cos_y * M_1_PI_F / d2);
}

// Solid-angle density with which emitter sampling picks the direction toward a point on an emissive face at
// distance `dist` whose normal makes cosine `cos_l` with the direction back to the shading point.
static inline float emitter_pdf(const Scene* s, float3 Le, float dist, float cos_l) {
    return ngi_luminance(Le) * s->inv_total * dist * dist / cos_l;
}

// Power heuristic (beta = 2) weight of a sample drawn with density pa, the other strategy having density pb.
static inline float power_heuristic(float pa, float pb) {
    const float a2 = pa * pa;
    return a2 / (a2 + pb * pb);
}

// Emissive blocks: pick a face in proportion to its luminance (every face has area 1 m^2), a uniform point on
// it, one shadow ray; MIS-weighted against the cosine-sampled bounce ray that can hit the same face.
static inline float3 emitter_light(const Scene* s, float3 p, float3 n, Rng* r, uint* rays) {
    const float2 u = rng2(r), v = rng2(r);
    if (s->nlights == 0) return (float3)(0.0f);
    int lo = 0, hi = s->nlights - 1;
    while (lo < hi) {  // first face whose cumulative probability exceeds u.x
        const int mid = (lo + hi) >> 1;
        if (s->cdf[mid] > u.x) hi = mid; else lo = mid + 1;
    }
    const int4 e = s->lights[lo];
    const float3 q = face_point(e.xyz, e.w, v);
    float3 w = q - p;
    const float dist = length(w);
    w /= dist;
    const float cos_x = dot(n, w), cos_l = -dot(face_normal(e.w), w);
    if (cos_x <= 0.0f || cos_l <= 1.0e-6f) return (float3)(0.0f);
    const Hit h = trace(s, p, w, dist + 1.0f, rays);
    if (h.mat == 0 || h.face != e.w || any(h.cell != e.xyz)) return (float3)(0.0f);  // occluded
    const float3 Le = s->mats[2 * h.mat + 1].xyz;
    const float pl = emitter_pdf(s, Le, dist, cos_l), pb = cos_x * M_1_PI_F;
    return Le * (power_heuristic(pl, pb) * cos_x * M_1_PI_F / pl);
}

// Region of the air block a shading point lies in (-1: open air, outside the grid, or portals disabled).
static inline int region_at(const Scene* s, float3 p) {
    const int3 c = convert_int3(floor(p));
    if (!s->use_regions || any(c < 0) || any(c >= s->dims)) return -1;
    return s->region[c.x + s->dims.x * (c.y + s->dims.y * c.z)];
}

// Solid-angle density with which portal sampling (uniform over the region's `count` unit faces, uniform point)
// produces a direction crossing the portal plane at distance `dist` with cosine `cos_p`.
static inline float portal_pdf(int count, float dist, float cos_p) { return dist * dist / (cos_p * (float)count); }

// Sky light through the openings of the covered region the point is in (rooms, tunnels): pick one of the region's
// portal faces, a uniform point on it, and trace toward it. The sample counts only if the ray escapes and that
// face is the first portal it crosses, so the direction density is portal_pdf of the first crossing - the same
// density the cosine-sampled continuation ray computes for its MIS weight.
static inline float3 portal_light(const Scene* s, float3 p, float3 n, int2 range, Rng* r, uint* rays) {
    const float2 u = rng2(r), v = rng2(r);
    const int4 e = s->portals[range.x + min((int)(u.x * (float)range.y), range.y - 1)];
    const float3 q = face_point(e.xyz, e.w, v);
    float3 w = q - p;
    const float dist = length(w);
    w /= dist;
    const float cos_x = dot(n, w), cos_p = fabs(dot(face_normal(e.w), w));
    if (cos_x <= 0.0f || cos_p <= 1.0e-6f) return (float3)(0.0f);
    Crossing x;
    const Hit h = trace_crossing(s, p, w, T_INF, rays, 1, &x);
    if (h.mat != 0 || !x.found || x.face != e.w || x.cell != e.x + s->dims.x * (e.y + s->dims.y * e.z))
        return (float3)(0.0f);
    const float pp = portal_pdf(range.y, dist, cos_p), pb = cos_x * M_1_PI_F;
    return sky_radiance(s->light, w) * (power_heuristic(pp, pb) * cos_x * M_1_PI_F / pp);
}

// Probability with which sunlit-patch sampling from a point in `reg` picks the face `f` of block `cell` (0 if the
// face is not one of the region's patches or reflects no sunlight).
static inline float patch_probability(const Scene* s, int reg, int3 cell, int f) {
    const int slot = s->face_slot[cell.x + s->dims.x * (cell.y + s->dims.y * cell.z)];
    if (slot < 0) return 0.0f;
    const int i = s->face_index[6 * slot + f];
    const int2 range = s->patch_range[reg];
    return i >= range.x && i < range.x + range.y ? s->patch_prob[i] : 0.0f;
}

// Sunlight reflected once off the sunlit patches of the covered region the point is in (the sun patch on a room's
// floor lights the room): pick a patch face in proportion to the sunlight it reflects, a uniform point y on it,
// check y is visible, then sun next-event estimation at y. This samples the same paths x -> y -> sun as the
// cosine-sampled continuation followed by sun NEE at y; both are MIS-weighted (power heuristic) with the densities
// of the direction x -> y.
static inline float3 patch_light(const Scene* s, float3 p, float3 n, int2 range, Rng* r, uint* rays) {
    const float2 u = rng2(r), v = rng2(r);
    int lo = range.x, hi = range.x + range.y - 1;
    while (lo < hi) {
        const int mid = (lo + hi) >> 1;
        if (s->patch_cdf[mid] > u.x) hi = mid; else lo = mid + 1;
    }
    const int4 e = s->patches[lo];
    const float3 q = face_point(e.xyz, e.w, v);
    float3 w = q - p;
    const float dist = length(w);
    w /= dist;
    const float3 ny = face_normal(e.w);
    const float cos_x = dot(n, w), cos_y = -dot(ny, w);
    const float prob = s->patch_prob[lo];
    if (cos_x <= 0.0f || cos_y <= 1.0e-6f || prob <= 0.0f) {
        rng2(r);  // keep the stream position independent of the branch
        return (float3)(0.0f);
    }
    const Hit h = trace(s, p, w, dist + 1.0f, rays);
    if (h.mat == 0 || h.face != e.w || any(h.cell != e.xyz)) {
        rng2(r);
        return (float3)(0.0f);
    }
    const float3 y = q + ny * RAY_OFFSET;
    const float3 sun = sun_light(s, y, ny, r, rays);  // E cos / pi at y, or 0 in shadow
    const float pp = prob * dist * dist / cos_y, pb = cos_x * M_1_PI_F;
    return s->mats[2 * h.mat].xyz * sun * (power_heuristic(pp, pb) * cos_x * M_1_PI_F / pp);
}

// One sample of the lighting (irradiance / pi) arriving at surface point p with normal n: direct light from the
// sun, emissive blocks, the area light and the sky (depth 0), plus up to max_bounces indirect bounces. Sun,
// emitters and the area light use next-event estimation (the area light nothing else: rays never hit it); the sky and emitters are also hit by the cosine-sampled continuation ray, MIS-weighted
// against emitter sampling and (inside covered regions) sky-portal sampling. Russian roulette after rr_start
// bounces keeps long paths unbiased.
static inline float3 lighting_sample(const Scene* s, float3 p, float3 n, int max_bounces, int rr_start, Rng* r,
                              uint* rays) {
    float3 sum = (float3)(0.0f), beta = (float3)(1.0f);
    float sun_mis = 1.0f;  // MIS weight of sun NEE here against patch sampling at the previous vertex
    const float3 area_le = lv(s->light, L_AREA_RADIANCE);
    const int area_on = area_le.x + area_le.y + area_le.z > 0.0f;
    for (int depth = 0;; ++depth) {
        const int reg = region_at(s, p);
        const int2 range = reg >= 0 && s->use_portals ? s->portal_range[reg] : (int2)(0, 0);
        // Patch sampling covers x -> y -> sun, so only where the continuation would still do sun NEE at y.
        const int2 prange = reg >= 0 && s->use_patches && depth < max_bounces ? s->patch_range[reg] : (int2)(0, 0);
        sum += beta * (sun_mis * sun_light(s, p, n, r, rays) + emitter_light(s, p, n, r, rays));
        if (area_on) sum += beta * area_light(s, p, n, r, rays);
        if (range.y > 0) sum += beta * portal_light(s, p, n, range, r, rays);
        if (prange.y > 0) sum += beta * patch_light(s, p, n, prange, r, rays);
        const float3 w = cosine_sample(n, rng2(r));
        Crossing x;
        const Hit h = trace_crossing(s, p, w, T_INF, rays, range.y > 0, &x);
        if (h.mat == 0) {
            float mis = 1.0f;
            if (range.y > 0 && x.found) {
                const float cos_p = fabs(dot(face_normal(x.face), w));
                mis = power_heuristic(dot(n, w) * M_1_PI_F, portal_pdf(range.y, x.t, cos_p));
            }
            sum += beta * sky_radiance(s->light, w) * mis;
            break;
        }
        const float3 Le = s->mats[2 * h.mat + 1].xyz;
        if (Le.x + Le.y + Le.z > 0.0f) {
            if (h.prim >= 0) {  // emissive triangles are not in the emitter list: only this strategy finds them
                sum += beta * Le;
            } else {
                const float cos_l = fabs(dot(face_normal(h.face), w));
                const float pl = emitter_pdf(s, Le, h.t, cos_l), pb = dot(n, w) * M_1_PI_F;
                sum += beta * Le * power_heuristic(pb, pl);
            }
        }
        if (depth >= max_bounces) break;
        sun_mis = 1.0f;
        if (prange.y > 0 && h.prim < 0) {
            const float prob = patch_probability(s, reg, h.cell, h.face);
            if (prob > 0.0f) {
                const float cos_y = fabs(dot(face_normal(h.face), w));
                sun_mis = power_heuristic(dot(n, w) * M_1_PI_F, prob * h.t * h.t / cos_y);
            }
        }
        beta *= s->mats[2 * h.mat].xyz;
        if (depth + 1 >= rr_start) {
            const float q = fmin(0.95f, fmax(beta.x, fmax(beta.y, beta.z)));
            if (rng2(r).x >= q) break;
            beta /= q;
        }
        n = hit_normal(s, w, &h);
        p = hit_origin(s, p, w, &h);
    }
    return sum;
}

// ---- kernels ------------------------------------------------------------------------------------------------

#define SCENE_ARGS                                                                                           \
    __global const uchar *grid, int sx, int sy, int sz, __global const float4 *mats, __global const int4 *lights, \
        __global const float *cdf, int nlights, float inv_total, __global const float *light,                    \
        __global const int *region, __global const int4 *portals, __global const int2 *portal_range,            \
        int use_regions, int use_portals, __global const int4 *patches, __global const float *patch_prob,         \
        __global const float *patch_cdf, __global const int2 *patch_range, __global const int *face_slot,        \
        __global const int *face_index, int use_patches, __global const float4 *bvh_nodes,                     \
        __global const float4 *tri_v, __global const int4 *tri_info, __global const float4 *vnormals, int has_mesh, \
        int has_blocks

#define MAKE_SCENE(s)                                                                                       \
    Scene s;                                                                                                \
    s.grid = grid; s.dims = (int3)(sx, sy, sz); s.mats = mats; s.lights = lights; s.cdf = cdf;             \
    s.nlights = nlights; s.inv_total = inv_total; s.light = light; s.region = region; s.portals = portals; \
    s.portal_range = portal_range; s.use_regions = use_regions; s.use_portals = use_portals;                   \
    s.patches = patches; s.patch_prob = patch_prob; s.patch_cdf = patch_cdf; s.patch_range = patch_range;     \
    s.face_slot = face_slot; s.face_index = face_index; s.use_patches = use_patches; s.bvh_nodes = bvh_nodes;   \
    s.tri_v = tri_v; s.tri_info = tri_info; s.vnormals = vnormals; s.has_mesh = has_mesh; s.has_blocks = has_blocks

// cam: centre (3), then per face look, right, up (9 each) in camera.hpp's face order.
// Unit direction through the centre of pixel (col, row) of face f (camera.hpp: face_pixel_direction).
static inline float3 pixel_ray(__global const float* cam, int f, int col, int row, int n, float3* look) {
    __global const float* b = cam + 3 + 9 * f;
    *look = (float3)(b[0], b[1], b[2]);
    const float u = 2.0f * ((float)col + 0.5f) / (float)n - 1.0f;
    const float v = 1.0f - 2.0f * ((float)row + 0.5f) / (float)n;
    return normalize(*look + u * (float3)(b[3], b[4], b[5]) + v * (float3)(b[6], b[7], b[8]));
}

// The primary ray through pixel `pix` (row-major, n x n) of face `face` from the cluster centre, and its first hit
// (counted in *rays). *o, *d, *look: the ray's origin, unit direction and the face's look axis.
static inline Hit primary_hit(const Scene* s, __global const float* cam, int face, int pix, int n, float3* o,
                              float3* d, float3* look, uint* rays) {
    const int row = pix / n, col = pix - row * n;
    *o = (float3)(cam[0], cam[1], cam[2]);
    *d = pixel_ray(cam, face, col, row, n, look);
    return trace(s, *o, *d, T_INF, rays);
}

static inline void store3(__global float* q, int plane, int npix, float3 v) {
    q[(size_t)plane * npix] = v.x;
    q[(size_t)(plane + 1) * npix] = v.y;
    q[(size_t)(plane + 2) * npix] = v.z;
}

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

// Sunlight reflected by each patch face (albedo luminance x sun irradiance luminance x cosine x the visible
// fraction of 4 points on the face), for the per-frame patch CDF. global size: number of patches.
__kernel void pt_patch_weights(SCENE_ARGS, int count, __global float* weight_out) {
    const int i = get_global_id(0);
    if (i >= count) return;
    MAKE_SCENE(s);
    const int4 e = patches[i];
    const float3 ny = face_normal(e.w), sd = lv(light, L_SUN_DIR), E = lv(light, L_SUN_E);
    const float c = dot(ny, sd);
    float w = 0.0f;
    if (c > 0.0f && ngi_luminance(E) > 0.0f) {
        uint rays = 0;
        int visible = 0;
        for (int k = 0; k < 4; ++k) {
            const float3 q = face_point(e.xyz, e.w, (float2)((k & 1) ? 0.75f : 0.25f, (k & 2) ? 0.75f : 0.25f));
            visible += trace(&s, q + ny * RAY_OFFSET, sd, T_INF, &rays).mat == 0;
        }
        w = ngi_luminance(mats[2 * s.grid[e.x + sx * (e.y + sy * e.z)]].xyz) * ngi_luminance(E) * c * (float)visible * 0.25f;
    }
    weight_out[i] = w;
}

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

// Object-space geometry of one face for the AO network (seed 001): per pixel the smooth normal (3 planes), the
// voxel face normal (3) and the planar depth (1) of the visible surface, out[plane][pix]; zero normals and
// SKY_DEPTH where the primary ray escapes. Scenes are not transformed, so object space = world space.
// Smooth normal: minus the gradient of the block occupancy blurred with a Gaussian of `sigma` blocks, at the hit
// point: sum over solid blocks c within 2 sigma + 1 of the point of w(c) * (p - centre(c)), w = exp(-d^2 / 2 sigma^2),
// normalized. Blocks outside the grid are air. Falls back to the face normal where that sum vanishes or points
// into the face (thin features) and for sigma <= 0. Cost: (4 sigma + 3)^3 grid reads per pixel.
__kernel void pt_geometry(SCENE_ARGS, __global const float* cam, int face, int n, float sigma,
                          __global float* out) {
    const int pix = get_global_id(0);
    const int npix = n * n;
    if (pix >= npix) return;
    MAKE_SCENE(s);
    __global float* q = out + pix;
    float3 o, d, look;
    uint rays = 0;
    const Hit h = primary_hit(&s, cam, face, pix, n, &o, &d, &look, &rays);
    if (h.mat == 0) {
        store3(q, 0, npix, (float3)(0.0f));
        store3(q, 3, npix, (float3)(0.0f));
        q[(size_t)6 * npix] = SKY_DEPTH;
        return;
    }
    const float3 nf = hit_normal(&s, d, &h);
    const float3 p = hit_origin(&s, o, d, &h) - nf * RAY_OFFSET;  // on the face
    float3 ns = hit_shading_normal(&s, nf, &h);  // triangles: the interpolated vertex normal
    if (sigma > 0.0f && h.prim < 0) {
        const int r = (int)ceil(2.0f * sigma) + 1;
        const int3 c0 = convert_int3(floor(p));
        const float k = -0.5f / (sigma * sigma), reach2 = (float)(r * r);
        float3 g = (float3)(0.0f);
        for (int z = c0.z - r; z <= c0.z + r; ++z) {
            if (z < 0 || z >= s.dims.z) continue;
            for (int y = c0.y - r; y <= c0.y + r; ++y) {
                if (y < 0 || y >= s.dims.y) continue;
                for (int x = c0.x - r; x <= c0.x + r; ++x) {
                    if (x < 0 || x >= s.dims.x) continue;
                    if (s.grid[x + s.dims.x * (y + s.dims.y * z)] == 0) continue;
                    const float3 v = p - ((float3)((float)x, (float)y, (float)z) + 0.5f);
                    const float d2 = dot(v, v);
                    if (d2 > reach2) continue;
                    g += v * exp(k * d2);
                }
            }
        }
        const float len = length(g);
        if (len > 1e-12f && dot(g, nf) > 0.0f) ns = g / len;
    }
    store3(q, 0, npix, ns);
    store3(q, 3, npix, nf);
    q[(size_t)6 * npix] = h.t * dot(d, look);
}

// What pixel (col, row) of face `face` sees of the mesh, for per-vertex baking (seed 001's baseline): out[plane][pix]
// = the three vertex indices of the triangle hit (exact in float up to kMaxMeshVertices = 2^24) and its barycentric
// weights; indices -1 and weights 0 where the pixel sees a block or nothing. global size n^2.
__kernel void pt_surface(SCENE_ARGS, __global const float* cam, int face, int n, __global float* out) {
    const int pix = get_global_id(0);
    const int npix = n * n;
    if (pix >= npix) return;
    MAKE_SCENE(s);
    float3 o, d, look;
    uint rays = 0;
    const Hit h = primary_hit(&s, cam, face, pix, n, &o, &d, &look, &rays);
    float3 index = (float3)(-1.0f), weight = (float3)(0.0f);
    if (h.mat != 0 && h.prim >= 0) {
        index = convert_float3(s.tri_info[h.prim].xyz);
        weight = (float3)(1.0f - h.uv.x - h.uv.y, h.uv.x, h.uv.y);
    }
    store3(out + pix, 0, npix, index);
    store3(out + pix, 3, npix, weight);
}

// ---- voxel radiance field (seed 004): docs/VOXEL_FIELD.md; host side renderer.cpp (render_voxel_field) --------
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

static inline int vf_block_id(int4 c, int sx, int sy) { return c.x + sx * (c.y + sy * c.z); }

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
    r.a = (uint)vf_block_id(cells[i], sx, sy); r.c = seed ^ VF_SALT_SUN;
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
__kernel void vf_sh(SCENE_ARGS, __global const float* probe, __global const int4* cells, int nvox, int m,
                    int first, int last, int max_bounces, int rr_start, uint seed, __global const float* sun_vis,
                    __global float* sh, __global uint* rays_out) {
    const int i = get_global_id(0);
    if (i >= nvox) return;
    MAKE_SCENE(s);
    const int id = vf_block_id(cells[i], sx, sy);
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
            L = sky_radiance(light, w);
        } else if (vf_block_id((int4)(h.cell, 0), sx, sy) != id) {
            L = mats[2 * h.mat + 1].xyz;
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
        const float3 sd = lv(light, L_SUN_DIR), E = lv(light, L_SUN_E) * sun_vis[i];
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
    r.a = (uint)vf_block_id(cells[i], sx, sy); r.c = seed ^ (max_bounces == 0 ? VF_SALT_DIRECT : VF_SALT_LIGHTING);
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
    r.a = (uint)(6 * vf_block_id(c, sx, sy) + f); r.c = seed ^ VF_SALT_FACE;
    for (int k = first; k < last; ++k) {
        r.b = (uint)k; r.n = 0;
        const float3 q = face_point(c.xyz, f, rng2(&r)) + n * RAY_OFFSET;
        sum += lighting_sample(&s, q, n, max_bounces, rr_start, &r, &rays);
    }
    vstore3(last >= spp ? sum / (float)spp : sum, g, out);
    rays_out[g] = rays;
}

// True when the segment a -> b crosses no solid block other than the blocks with linear ids ia and ib (3D DDA,
// as trace(); the parts outside the grid are air).
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
    // Scalar compares (1 for true): see trace_crossing on oclgrind and vector selects.
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
    const int id = vf_block_id(cells[i], sx, sy);
    for (int b = bit_first; b < bit_last; ++b) {
        const int j = 32 * w + b;
        if (j >= nvox) break;
        if (j == i) continue;
        const float3 pj = vload3(j, probe);
        const int jd = vf_block_id(cells[j], sx, sy);
        const int clear = i < j ? vf_segment_clear(grid, dims, p_i, pj, id, jd)
                                : vf_segment_clear(grid, dims, pj, p_i, jd, id);
        if (clear) bits |= 1u << b;
    }
    *q = bits;
}

// The scene the path tracer's kernels trace (pathtrace, ao_geometry and voxel_field in runtime/programs.cpp):
// the block grid walked with Amanatides & Woo's 3D DDA and an optional triangle mesh behind a BVH (kernels/bvh.cl,
// listed before this file in each of those programs); a ray's hit is the closer of the two. Triangles are
// two-sided; light transport uses their geometric normal (facing the incoming ray), the features and the AO
// network's geometry the interpolated vertex normal. Host side: host/src/render/renderer.cpp; docs/RENDERER.md.
//
// Grid: palette indices (uchar, 0 = air), x + sx * (y + sy * z); block (x, y, z) covers the unit cube at that
// corner. Build option, the host's: RAY_OFFSET (secondary rays start this far off the surface, along the normal),
// from render/tracer_constants.hpp.
#ifndef RAY_OFFSET
#error "scene.cl needs RAY_OFFSET: build the tracer's programs with renderer.cpp's pathtrace_defines()"
#endif

#define T_INF 1.0e30f

// Three floats of the light parameter array (Scene.light; its layout: lighting.cl) from slot i.
static inline float3 lv(__global const float* L, int i) { return (float3)(L[i], L[i + 1], L[i + 2]); }

typedef struct {
    __global const uchar* grid;
    int3 dims;
    __global const float4* mats;   // per material: albedo, emission (lamp level applied)
    __global const int4* lights;   // emissive faces that border air: cell xyz, face id
    __global const float* cdf;     // cumulative selection probability of lights (proportional to luminance)
    int nlights;
    float inv_total;               // 1 / sum of the luminance of all emissive faces
    __global const float* light;   // L_* parameters
    // Sky portals (found in light_regions.cpp): region id per block (>= 0: covered air, i.e. a block somewhere above
    // it), and per region the range of its portal faces in `portals` (covered cell xyz, face id). 0 portals: no
    // portal sampling anywhere.
    __global const int* region;
    __global const int4* portals;
    __global const int2* portal_range;  // per region: first index, count
    int use_regions, use_portals;
    // Sunlit patches (found in light_regions.cpp, weighted per frame in renderer.cpp): block faces bordering covered
    // air, grouped by region; per frame the probability of picking each within its region (proportional to the
    // sunlight it reflects) and the running sum. Lookup of a face's index: face_slot[block] >= 0 ->
    // face_index[6 * slot + face].
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

// Surround screen-space global illumination (SSGI): one bounce of the light that the cluster's faces see, gathered
// at the front face's texels as a point-to-patch form-factor sum (docs/CONVENTIONS.md section 19; host:
// host/src/pipeline/ssgi.cpp; naive reference: tests/reference_ssgi.hpp). No network: physics the generators must
// beat, and the estimate they correct.
//
//   E(p) = sum_q L_q cos(theta_p) cos(theta_q) A_q / r^2,   indirect lighting = E(p) / pi   (irradiance / pi)
//
// with L_q = albedo_q * (direct_q [+ the previous bounce's indirect_q]) + emission_q the radiance a Lambertian
// texel q sends, A_q its surface area (solid angle * |q|^2 / cos between its normal and the camera ray) and
// positions from planar depth along each face's look axis. Far senders are clustered: a record stands for a block
// of texels (its area, area-weighted normal sum, area-weighted mean radiance and position, and the positions'
// variance), so one term stands for the block; a receiver near a block (closer than near_factor standard deviations
// of its positions) gathers its four quarter blocks instead, and those near it their texels one by one (a two-step
// hierarchy: a near block rarely needs all of its texels). Pairs closer than min_distance are skipped.
// Visibility (optional, vis_steps > 0): the segment from the receiver toward each sender's mean position is marched
// through the faces' depth buffers (screen-space ray marching over the six faces); the first sample hidden behind
// the surface its face shows there, by more than a depth bias and less than `thickness` times its depth, blocks the
// pair, and the light of that pair is the blocking surface's instead of the sender's (what the receiver sees in
// that direction: the texel's own record), as screen-space ray tracing takes the colour of the surface it hits
// (ssgi_blocker).
//
// Build options, the host's (ssgi_defines(), host/src/pipeline/ssgi.cpp):
//   F_ALBEDO ... F_ENV, F_CHANNELS   the raw frame planes (pipeline/frame_planes.hpp)
//   SSGI_MAX_DEPTH                   metres: a texel farther away (the renderer's sky, 1e4) is no surface
//   SSGI_MIN_COS                     smallest |cos| between a sender's normal and its camera ray in its area
//   SSGI_MAX_RADIANCE                sender radiance is clamped to this (so sums of area x radiance stay finite)
//   SSGI_FACE_BASIS                  the six faces' look, right, up in cluster space (9 values a face, Face order:
//                                    ngi::cluster_face_basis); a pixel's world direction is S^T of its cluster one,
//                                    with the front camera's basis S = [alpha; beta; gamma] passed per frame as
//                                    arguments (so a frame uploads nothing)
//   SSGI_LOCAL                       the work-group size every kernel here is launched with
//   SSGI_VIS_SLOPE                   visibility's depth bias in texels of depth slope: a sample blocks only when
//                                    farther than the face's surface by more than depth * SSGI_VIS_SLOPE * 2 / n
//                                    (a surface's depth changes across its texel by up to that much)
//   SSGI_VEC                         sender records a gathering work-item reads as one vector (4, 8 or 16): the
//                                    far field is summed branch-free in SIMD lanes across senders, which PoCL's
//                                    implicit vectorization across work-items cannot do with the refinement's
//                                    branches (a knob, as CLBlast's; record counts are padded to its multiple)
#if !defined(F_ALBEDO) || !defined(F_NORMAL) || !defined(F_DEPTH) || !defined(F_DIRECT) || !defined(F_EMISSION) || \
    !defined(F_CHANNELS) || !defined(SSGI_MAX_DEPTH) || !defined(SSGI_MIN_COS) || !defined(SSGI_MAX_RADIANCE) || \
    !defined(SSGI_LOCAL) || !defined(SSGI_VIS_SLOPE) || \
    !defined(SSGI_VEC) || !defined(SSGI_FACE_BASIS)
#error "ssgi.cl needs the host's constants: build it with ssgi_defines() (host/src/pipeline/ssgi.cpp)"
#endif

// Record planes (structure of arrays, plane stride = the padded record count). A texel's record is itself (variance 0);
// a cluster's holds its texels' area sum, the sum of A n (whose length against the area says how coherent the
// normals are, and whose dot product with a direction is the block's projected area for a flat block), the
// area-weighted means of radiance and position, and the positions' variance about that mean. Records past the last
// (padding) and texels without a surface are all zero and send nothing.
#define R_AREA 0
#define R_NORMAL 1    // 3 planes: sum of A n
#define R_RADIANCE 4  // 3 planes: mean radiance L
#define R_POSITION 7  // 3 planes: mean position p
#define R_VARIANCE 10 // mean of |p - mean|^2
#define R_PLANES 11

__constant float ssgi_face_basis[54] = {SSGI_FACE_BASIS};

// The front camera's cluster basis (docs/CONVENTIONS.md section 1) as kernel arguments, and as three vectors.
#define SSGI_CLUSTER_ARGS float ax, float ay, float az, float bx, float by, float bz, float gx, float gy, float gz
#define SSGI_CLUSTER_PASS (float3)(ax, ay, az), (float3)(bx, by, bz), (float3)(gx, gy, gz)

#define VTYPE NGI_CAT(float, SSGI_VEC)
#define ITYPE NGI_CAT(int, SSGI_VEC)
#define VLOAD NGI_CAT(vload, SSGI_VEC)
#define VSTORE NGI_CAT(vstore, SSGI_VEC)

// Light terms as compose cleans them: NaN and negative -> 0, +Inf -> FLT_MAX.
static inline float3 ssgi_clean(float3 v) {
    return clamp(select(v, (float3)(0.0f), isnan(v)), (float3)(0.0f), (float3)(FLT_MAX));
}

// A sender's light terms: cleaned, then capped at SSGI_MAX_RADIANCE.
static inline float3 ssgi_light(float3 v) { return fmin(ssgi_clean(v), (float3)(SSGI_MAX_RADIANCE)); }

static inline float3 ssgi_load3(__global const float* q, int plane, int stride) {
    return (float3)(q[(size_t)plane * stride], q[(size_t)(plane + 1) * stride], q[(size_t)(plane + 2) * stride]);
}

static inline void ssgi_store3(__global float* q, int plane, int stride, float3 v) {
    q[(size_t)plane * stride] = v.x;
    q[(size_t)(plane + 1) * stride] = v.y;
    q[(size_t)(plane + 2) * stride] = v.z;
}

// The surface texel `pix` of face `f` shows: its world position relative to the cluster centre and its unit normal,
// and the (unnormalized) camera ray through it. False for no surface: sky (zero normal, depth beyond
// SSGI_MAX_DEPTH), non-finite or non-positive depth or normal. alpha, beta, gamma: the cluster basis (world space).
static inline int ssgi_surface(__global const float* planes, float3 alpha, float3 beta, float3 gamma, int f, int pix,
                               int n, float3* p, float3* nrm, float3* ray) {
    const int npix = n * n;
    __global const float* q = planes + (size_t)f * F_CHANNELS * npix + pix;
    float3 m = ssgi_load3(q, F_NORMAL, npix);
    const float depth = q[(size_t)F_DEPTH * npix];
    if (!(depth > 0.0f && depth <= SSGI_MAX_DEPTH)) return 0;  // also NaN
    if (any(isnan(m)) || any(isinf(m))) return 0;
    const float big = fmax(fabs(m.x), fmax(fabs(m.y), fabs(m.z)));
    if (!(big >= 1e-6f)) return 0;
    m /= big;  // scaled by the largest component first, so huge values cannot overflow
    *nrm = normalize(m);
    const int row = pix / n, col = pix - row * n;
    const float u = 2.0f * ((float)col + 0.5f) / (float)n - 1.0f, v = 1.0f - 2.0f * ((float)row + 0.5f) / (float)n;
    __constant const float* b = ssgi_face_basis + 9 * f;
    const float3 c = (float3)(b[0], b[1], b[2]) + u * (float3)(b[3], b[4], b[5]) + v * (float3)(b[6], b[7], b[8]);
    const float3 d = c.x * alpha + c.y * beta + c.z * gamma;
    *p = depth * d;
    *ray = d;
    return 1;
}

// The record index of texel (col, row) of face f, for clusters of b x b texels refined through their four quarters
// of bm x bm (bm = b / 2; b = 1: row-major): blocks of a face row-major, each block's texels contiguous, and inside
// it each quarter's (row-major quarters, texels row-major in a quarter), so a cluster's quarters and a quarter's
// texels are contiguous runs of records (vector loads).
static inline int ssgi_record_index(int f, int row, int col, int n, int b) {
    const int s = n / b, by = row / b, bx = col / b, ry = row - by * b, rx = col - bx * b;
    const int bm = b > 1 ? b / 2 : 1, qy = ry / bm, qx = rx / bm;
    return f * n * n + (by * s + bx) * b * b + (qy * (b / bm) + qx) * bm * bm + (ry - qy * bm) * bm + (rx - qx * bm);
}

// One record per texel of `faces` faces (at ssgi_record_index), and zero records up to `stride` (global size stride,
// the plane stride of rec, >= faces n^2). bounce: when has_bounce, the previous bounce's indirect lighting per texel,
// [face][3][n][n], added to the direct light before the albedo (a further bounce); else unused.
__kernel void ssgi_senders(__global const float* planes, int faces, int n, int b, SSGI_CLUSTER_ARGS, int has_emission, __global const float* bounce, int has_bounce, int stride,
                           __global float* rec) {
    const int gid = get_global_id(0), npix = n * n;
    if (gid >= stride) return;
    const int f = gid / npix, pix = gid - f * npix;
    float3 p, nrm, ray;
    float area = 0.0f;
    float3 light = (float3)(0.0f);
    if (gid < faces * npix && ssgi_surface(planes, SSGI_CLUSTER_PASS, f, pix, n, &p, &nrm, &ray)) {
        __global const float* q = planes + (size_t)f * F_CHANNELS * npix + pix;
        float3 albedo = ssgi_load3(q, F_ALBEDO, npix);
        albedo = clamp(select(albedo, (float3)(0.0f), isnan(albedo)), (float3)(0.0f), (float3)(1.0f));
        float3 incoming = ssgi_light(ssgi_load3(q, F_DIRECT, npix));
        if (has_bounce)
            incoming = ssgi_light(incoming + ssgi_light(ssgi_load3(bounce + (size_t)f * 3 * npix + pix, 0, npix)));
        light = albedo * incoming;
        if (has_emission) light += ssgi_light(ssgi_load3(q, F_EMISSION, npix));
        light = ssgi_light(light);
        // Solid angle of the texel (2/n)^2 / |d|^3 times |p|^2, over the cosine with the camera ray.
        const float len = length(ray);
        const float c = fmax(fabs(dot(nrm, ray)) / len, SSGI_MIN_COS);
        const float s = 2.0f / (float)n;
        area = s * s * dot(p, p) / (len * len * len) / c;
    }
    if (!(area > 0.0f)) {
        area = 0.0f;
        p = nrm = light = (float3)(0.0f);
    }
    const int row = pix / n;
    __global float* r = rec + (gid < faces * npix ? ssgi_record_index(f, row, pix - row * n, n, b) : gid);
    r[(size_t)R_AREA * stride] = area;
    ssgi_store3(r, R_NORMAL, stride, area * nrm);
    ssgi_store3(r, R_RADIANCE, stride, light);
    ssgi_store3(r, R_POSITION, stride, p);
    r[(size_t)R_VARIANCE * stride] = 0.0f;
}

// Parent records: record i sums the k child records [i k, (i + 1) k) of `child` (plane stride child_stride) for
// i < count, and zero records up to `stride` (global size stride).
__kernel void ssgi_cluster(__global const float* child, int child_stride, int k, int count, int stride,
                           __global float* parent) {
    const int gid = get_global_id(0);
    if (gid >= stride) return;
    float a = 0.0f, spread = 0.0f;
    float3 an = (float3)(0.0f), al = (float3)(0.0f), ap = (float3)(0.0f);
    for (int t = 0; gid < count && t < k; ++t) {
        __global const float* r = child + gid * k + t;
        const float ai = r[(size_t)R_AREA * child_stride];
        const float3 pi = ssgi_load3(r, R_POSITION, child_stride);
        a += ai;
        an += ssgi_load3(r, R_NORMAL, child_stride);
        al += ai * ssgi_load3(r, R_RADIANCE, child_stride);
        ap += ai * pi;
        spread += ai * (r[(size_t)R_VARIANCE * child_stride] + dot(pi, pi));
    }
    __global float* r = parent + gid;
    const float inv = a > 0.0f ? 1.0f / a : 0.0f;
    const float3 mean = ap * inv;
    r[(size_t)R_AREA * stride] = a;
    ssgi_store3(r, R_NORMAL, stride, an);
    ssgi_store3(r, R_RADIANCE, stride, fmin(al * inv, (float3)(SSGI_MAX_RADIANCE)));
    ssgi_store3(r, R_POSITION, stride, mean);
    r[(size_t)R_VARIANCE * stride] = fmax(spread * inv - dot(mean, mean), 0.0f);
}

// What the visibility march needs: the raw frame planes of `faces` sender faces (a sample seen by a face not in
// the frame counts as free), the cluster basis, the samples per pair (0: no test), the assumed thickness of a
// surface as a fraction of its depth (FLT_MAX: everything behind a surface is solid), and the texels' records (plane
// stride fine_stride, at ssgi_record_index with blocks of b) whose radiance a blocking texel sends.
typedef struct {
    __global const float* planes;
    __global const float* fine;
    int n, faces, steps, b, fine_stride;
    float thickness;
    float3 alpha, beta, gamma;
} ssgi_vis_t;

// -1 if the segment from receiver p toward a sender at p + w is free, else the record of the texel whose surface
// blocks it (the first blocking sample's). `variance`: the sender record's
// position variance; a cluster's mean position may lie inside the surfaces it averages, so the march stops sigma
// short of it (at most halfway). Samples at the centres of `steps` equal parts of the marched length; each is seen
// by the face whose look axis is nearest its direction from the cluster centre (ties to the first in Face order)
// and blocks when it lies behind that face's surface by more than the bias and less than the thickness (both in
// proportion to the surface's depth: a scene's scale does not change the test).
static inline int ssgi_blocker(const ssgi_vis_t* vis, float3 p, float3 w, float variance) {
    const float len = length(w);
    if (!(len > 0.0f)) return -1;
    const float reach = 1.0f - fmin(sqrt(fmax(variance, 0.0f)) / len, 0.5f);
    const int n = vis->n, npix = n * n;
    for (int k = 0; k < vis->steps; ++k) {
        const float3 x = p + (reach * ((float)k + 0.5f) / (float)vis->steps) * w;
        const float3 c = (float3)(dot(x, vis->alpha), dot(x, vis->beta), dot(x, vis->gamma));
        int f = 0;
        float t = -FLT_MAX;
        for (int g = 0; g < 6; ++g) {
            __constant const float* b = ssgi_face_basis + 9 * g;
            const float tg = c.x * b[0] + c.y * b[1] + c.z * b[2];
            if (tg > t) {
                t = tg;
                f = g;
            }
        }
        if (f >= vis->faces || !(t > 0.0f)) continue;
        __constant const float* b = ssgi_face_basis + 9 * f;
        const float u = (c.x * b[3] + c.y * b[4] + c.z * b[5]) / t, v = (c.x * b[6] + c.y * b[7] + c.z * b[8]) / t;
        const int col = clamp((int)floor((u + 1.0f) * 0.5f * (float)n), 0, n - 1);
        const int row = clamp((int)floor((1.0f - v) * 0.5f * (float)n), 0, n - 1);
        const float d = vis->planes[((size_t)f * F_CHANNELS + F_DEPTH) * npix + row * n + col];
        if (!(d > 0.0f && d <= SSGI_MAX_DEPTH)) continue;  // sky, no surface, NaN: nothing there to block
        const float behind = t - d;
        if (behind > d * (SSGI_VIS_SLOPE * 2.0f) / (float)n && behind < vis->thickness * d)
            return ssgi_record_index(f, row, col, n, vis->b);
    }
    return -1;
}

// SSGI_VEC records from record c of `rec` (plane stride `stride`) sent to point p with unit normal np, added to
// the lanes of er, eg, eb: each record's mean radiance times the form factor of its projected area,
// max(0, np . w) max(0, -(sum A n) . w) / r^2, w the unit vector to its mean position. Zero for pairs closer than
// sqrt(min_d2) (> 0), for records that must be refined (near2 > 0: mean position within sqrt(near2) standard
// deviations of its positions); with a visibility test a blocked pair's light is its blocker's, added to *e.
// Returns the refine mask.
static inline ITYPE ssgi_terms(__global const float* rec, int stride, int c, float3 p, float3 np, float min_d2,
                               float near2, const ssgi_vis_t* vis, VTYPE* er, VTYPE* eg, VTYPE* eb, float3* e) {
    __global const float* r = rec + c;
    const VTYPE wx = VLOAD(0, r + (size_t)R_POSITION * stride) - p.x;
    const VTYPE wy = VLOAD(0, r + (size_t)(R_POSITION + 1) * stride) - p.y;
    const VTYPE wz = VLOAD(0, r + (size_t)(R_POSITION + 2) * stride) - p.z;
    const VTYPE d2 = wx * wx + wy * wy + wz * wz;
    const VTYPE inv = rsqrt(fmax(d2, min_d2));
    const VTYPE cp = (np.x * wx + np.y * wy + np.z * wz) * inv;
    const VTYPE proj = -(VLOAD(0, r + (size_t)R_NORMAL * stride) * wx + VLOAD(0, r + (size_t)(R_NORMAL + 1) * stride) * wy +
                         VLOAD(0, r + (size_t)(R_NORMAL + 2) * stride) * wz) * inv;
    const ITYPE refine = near2 > 0.0f ? d2 < near2 * VLOAD(0, r + (size_t)R_VARIANCE * stride) : (ITYPE)(0);
    VTYPE g = select(fmax(cp, 0.0f) * fmax(proj, 0.0f) * inv * inv, (VTYPE)(0.0f), (d2 < min_d2) | refine);
    if (vis->steps > 0) {  // the march per lane that sends light: its samples read scattered depths
        float lg[SSGI_VEC], lx[SSGI_VEC], ly[SSGI_VEC], lz[SSGI_VEC], lv[SSGI_VEC];
        VSTORE(g, 0, lg);
        VSTORE(wx, 0, lx);
        VSTORE(wy, 0, ly);
        VSTORE(wz, 0, lz);
        VSTORE(VLOAD(0, r + (size_t)R_VARIANCE * stride), 0, lv);
        for (int k = 0; k < SSGI_VEC; ++k) {
            if (!(lg[k] > 0.0f)) continue;
            const int hit = ssgi_blocker(vis, p, (float3)(lx[k], ly[k], lz[k]), lv[k]);
            if (hit < 0) continue;
            *e += lg[k] * ssgi_load3(vis->fine + hit, R_RADIANCE, vis->fine_stride);
            lg[k] = 0.0f;
        }
        g = VLOAD(0, lg);
    }
    *er += g * VLOAD(0, r + (size_t)R_RADIANCE * stride);
    *eg += g * VLOAD(0, r + (size_t)(R_RADIANCE + 1) * stride);
    *eb += g * VLOAD(0, r + (size_t)(R_RADIANCE + 2) * stride);
    return refine;
}

// One record's term, as ssgi_terms computes each lane, added to *e; or, when near2 > 0 and its mean position is within
// sqrt(near2) standard deviations of its positions, nothing: returns 1 (refine it).
static inline int ssgi_record(__global const float* rec, int stride, int i, float3 p, float3 np, float min_d2,
                              float near2, const ssgi_vis_t* vis, float3* e) {
    const float3 w = ssgi_load3(rec + i, R_POSITION, stride) - p;
    const float d2 = dot(w, w);
    if (near2 > 0.0f && d2 < near2 * rec[(size_t)R_VARIANCE * stride + i]) return 1;
    if (!(d2 >= min_d2)) return 0;
    const float inv = rsqrt(d2);
    const float cp = dot(np, w) * inv, proj = -dot(ssgi_load3(rec + i, R_NORMAL, stride), w) * inv;
    const float g = fmax(cp, 0.0f) * fmax(proj, 0.0f) * inv * inv;
    const int hit = vis->steps > 0 && g > 0.0f ? ssgi_blocker(vis, p, w, rec[(size_t)R_VARIANCE * stride + i]) : -1;
    *e += (hit < 0 ? ssgi_load3(rec + i, R_RADIANCE, stride) : ssgi_load3(vis->fine + hit, R_RADIANCE, vis->fine_stride)) * g;
    return 0;
}

static inline float ssgi_hsum(VTYPE v) {
    float lane[SSGI_VEC];
    VSTORE(v, 0, lane);
    float s = 0.0f;
    for (int k = 0; k < SSGI_VEC; ++k) s += lane[k];
    return s;
}

// Gathers at the texels of faces [first_face, first_face + faces_out) (global size faces_out n^2).
// coarse: the sender clusters, `cstride` records (a multiple of SSGI_VEC, zero past the last); mid: their quarters,
// four per cluster (mid_stride); fine: the texels, `per_mid` per quarter (fine_stride). refine = 0: the coarse
// records are all there is (texels, or clusters gathered whole). near2: a record whose mean position is closer than
// sqrt(near2) standard deviations of its positions is replaced by its children. min_d2 > 0. Output,
// out_lightmap = 0: the indirect lighting E / pi, [face][3][n][n] over the receiving faces; out_lightmap = 1: the
// lightmap clean(direct) + E / pi of the receiving face (faces_out 1), saturating at FLT_MAX. Visibility: vis_steps
// samples per pair (0: none) through the depth of the frame's first vis_faces faces, surfaces vis_thickness x their
// depth thick; vis_block: the cluster side b the fine records are laid out for (ssgi_record_index).
__kernel void ssgi_gather(__global const float* planes, int n, SSGI_CLUSTER_ARGS, __global const float* coarse,
                          int cstride, __global const float* mid, int mid_stride, __global const float* fine,
                          int fine_stride, int per_mid, int refine_on, float near2, float min_d2, int first_face,
                          int faces_out, int out_lightmap, int vis_faces, int vis_steps, float vis_thickness,
                          int vis_block, __global float* out) {
    const int gid = get_global_id(0), npix = n * n;
    if (gid >= faces_out * npix) return;
    const int rf = gid / npix, pix = gid - rf * npix, f = first_face + rf;
    float3 p, np, ray;
    float3 e = (float3)(0.0f);
    ssgi_vis_t vis;
    vis.planes = planes;
    vis.fine = fine;
    vis.fine_stride = fine_stride;
    vis.b = vis_block;
    vis.n = n;
    vis.faces = vis_faces;
    vis.steps = vis_steps;
    vis.thickness = vis_thickness;
    vis.alpha = (float3)(ax, ay, az);
    vis.beta = (float3)(bx, by, bz);
    vis.gamma = (float3)(gx, gy, gz);
    if (ssgi_surface(planes, SSGI_CLUSTER_PASS, f, pix, n, &p, &np, &ray)) {
        const float near_top = refine_on ? near2 : 0.0f;
        VTYPE er = (VTYPE)(0.0f), eg = (VTYPE)(0.0f), eb = (VTYPE)(0.0f);
        for (int c = 0; c < cstride; c += SSGI_VEC) {
            const ITYPE refine = ssgi_terms(coarse, cstride, c, p, np, min_d2, near_top, &vis, &er, &eg, &eb, &e);
            if (!any(refine)) continue;
            int lanes[SSGI_VEC];
            VSTORE(refine, 0, lanes);
            for (int k = 0; k < SSGI_VEC; ++k) {
                if (!lanes[k]) continue;
                for (int m = 4 * (c + k); m < 4 * (c + k) + 4; ++m) {  // the cluster's quarters
                    if (!ssgi_record(mid, mid_stride, m, p, np, min_d2, near2, &vis, &e)) continue;
                    const int first = m * per_mid;  // the quarter's texels (ssgi_record_index)
                    if (per_mid % SSGI_VEC == 0)
                        for (int t = first; t < first + per_mid; t += SSGI_VEC)
                            ssgi_terms(fine, fine_stride, t, p, np, min_d2, 0.0f, &vis, &er, &eg, &eb, &e);
                    else
                        for (int t = first; t < first + per_mid; ++t)
                            ssgi_record(fine, fine_stride, t, p, np, min_d2, 0.0f, &vis, &e);
                }
            }
        }
        e += (float3)(ssgi_hsum(er), ssgi_hsum(eg), ssgi_hsum(eb));
    }
    const float3 indirect = fmin(e * M_1_PI_F, (float3)(FLT_MAX));  // an overflowed sum (+Inf) saturates
    if (!out_lightmap) {
        ssgi_store3(out + (size_t)rf * 3 * npix + pix, 0, npix, indirect);
        return;
    }
    __global const float* q = planes + (size_t)f * F_CHANNELS * npix + pix;
    ssgi_store3(out + pix, 0, npix, fmin(ssgi_clean(ssgi_load3(q, F_DIRECT, npix)) + indirect, (float3)(FLT_MAX)));
}

// Preprocessing of raw G-buffer features (thesis section 4.3.1), per texel, before the merge.
// Value rules and ranges: docs/CONVENTIONS.md ("Preprocessing").

// Build options, the host's (preprocess_defines(), host/src/pipeline/preprocess.cpp):
//   TRANSFER_REINHARD, TRANSFER_CLAMP   ngi::LuminationTransfer
//   F_ALBEDO ... F_ENV, F_CHANNELS      the raw frame planes (ngi/pipeline.hpp kFramePlanes, frame_plane()): per
//                                       face, F_CHANNELS planes of face_texels values (each face's feature images
//                                       land contiguously, so the host uploads them without repacking)
//   COUNT_ALBEDO ... COUNT_ENV          counter slots of the non-finite values per Feature
//   COUNT_SKY, COUNT_FAR, COUNT_SLOTS   then sky normals and far depths; the number of slots
//   PREPROCESS_LOCAL                    the largest work-group size (per-work-item counts are summed in local memory)
//   MAX_DEPTH_M                         depth beyond which a texel is no surface, the depth feature's scale
//                                       (kMaxSurfaceDepth, host/src/base/surface_depth.hpp)
// Output: 10 planes of npix = faces * face_texels values, faces in order inside each plane (the layout the merge
// table indexes): albedo 0-2, normal 3-5, depth 6, lumination 7-9.
#if !defined(TRANSFER_REINHARD) || !defined(TRANSFER_CLAMP) || !defined(F_CHANNELS) || !defined(F_ENV) || \
    !defined(COUNT_ENV) || !defined(COUNT_SLOTS) || !defined(PREPROCESS_LOCAL) || !defined(MAX_DEPTH_M)
#error "gbuffer.cl needs the host's constants: build it with preprocess_defines() (host/src/pipeline/preprocess.cpp)"
#endif

// A normal whose largest component is below this is the zero vector: the renderer's "no surface" (sky).
#define SKY_NORMAL_EPS 1e-6f

// Replaces a non-finite value (NaN -> nan_to, -Inf -> neg_to, +Inf -> pos_to) and counts it.
static inline float clean(float v, float nan_to, float neg_to, float pos_to, int* bad) {
    if (isnan(v)) { ++*bad; return nan_to; }
    if (isinf(v)) { ++*bad; return v > 0.0f ? pos_to : neg_to; }
    return v;
}

// Linear lumination x in [0, FLT_MAX] to [0, 1]. Reinhard x / (1 + x): 1 + FLT_MAX rounds to FLT_MAX, so the
// largest value gives exactly 1 and nothing overflows; the fmin guards a division that is not correctly
// rounded on some devices.
static inline float lum_encode(float x, int transfer) {
    if (transfer == TRANSFER_CLAMP) return fmin(x, 1.0f);
    return fmin(x / (1.0f + x), 1.0f);
}

// S = [alpha; beta; gamma] (cluster basis rows) maps world-space normals into cluster space. lo/hi: the model's
// input range; every feature is first brought to [0, 1], then to lo + v * (hi - lo).
// Launch: 2-D (face_texels, faces), local (PREPROCESS_LOCAL, 1); the counters are summed per work-group in local
// memory, then added once.
__kernel void preprocess_gbuffer(__global const float* restrict raw, __global float* restrict out,
                                 const int face_texels, const int faces, const int has_emission, const int has_env,
                                 const float ax, const float ay, const float az,
                                 const float bx, const float by, const float bz,
                                 const float gx, const float gy, const float gz,
                                 const float lo, const float hi, const int transfer,
                                 __global int* restrict counters) {
    // Each work-item's counts go to local memory once, after its texel; COUNT_SLOTS work-items then sum them and add
    // to the global counters. No atomic inside the per-texel code: PoCL ran the kernel one texel at a time with a
    // local atomic in a branch there (0.84 ms for a 6 x 64 x 64 frame, ~35 ns per texel; docs/PERFORMANCE.md
    // "small shapes").
    __local int group_counts[COUNT_SLOTS][PREPROCESS_LOCAL];
    const int t = get_global_id(0), face = get_global_id(1), lid = get_local_id(0);
    const int npix = face_texels * faces, p = face * face_texels + t;
    int bad_albedo = 0, bad_normal = 0, bad_depth = 0, bad_direct = 0, bad_emission = 0, bad_env = 0, sky = 0, far = 0;

    if (t < face_texels) {
        __global const float* r = raw + face * F_CHANNELS * face_texels + t;
        const float scale = hi - lo;

        // Albedo: reflectance, clamped to [0, 1].
        for (int c = 0; c < 3; ++c) {
            const float a = clamp(clean(r[(F_ALBEDO + c) * face_texels], 0.0f, 0.0f, 1.0f, &bad_albedo), 0.0f, 1.0f);
            out[c * npix + p] = lo + a * scale;
        }

        // Normal: a non-finite component makes the whole normal unknown, i.e. zero (sky). Scaled by its largest
        // component before the length so that huge finite values cannot overflow.
        float nx = clean(r[F_NORMAL * face_texels], 0.0f, 0.0f, 0.0f, &bad_normal);
        float ny = clean(r[(F_NORMAL + 1) * face_texels], 0.0f, 0.0f, 0.0f, &bad_normal);
        float nz = clean(r[(F_NORMAL + 2) * face_texels], 0.0f, 0.0f, 0.0f, &bad_normal);
        const float m = fmax(fabs(nx), fmax(fabs(ny), fabs(nz)));
        float cx = 0.0f, cy = 0.0f, cz = 0.0f;
        if (bad_normal == 0 && m >= SKY_NORMAL_EPS) {
            nx /= m; ny /= m; nz /= m;
            const float inv = 1.0f / sqrt(nx * nx + ny * ny + nz * nz);
            nx *= inv; ny *= inv; nz *= inv;
            cx = ax * nx + ay * ny + az * nz;
            cy = bx * nx + by * ny + bz * nz;
            cz = gx * nx + gy * ny + gz * nz;
        } else {
            sky = 1;
        }
        // [-1, 1] -> [0, 1] (the zero vector of the sky lands on 0.5), clamped against rounding.
        out[3 * npix + p] = lo + clamp(cx * 0.5f + 0.5f, 0.0f, 1.0f) * scale;
        out[4 * npix + p] = lo + clamp(cy * 0.5f + 0.5f, 0.0f, 1.0f) * scale;
        out[5 * npix + p] = lo + clamp(cz * 0.5f + 0.5f, 0.0f, 1.0f) * scale;

        // Depth in metres -> depth / 1000 in [0, 1]; unknown (NaN) and +Inf are as far as it gets.
        const float d = clean(r[F_DEPTH * face_texels], MAX_DEPTH_M, 0.0f, MAX_DEPTH_M, &bad_depth);
        far = d > MAX_DEPTH_M;
        out[6 * npix + p] = lo + clamp(d / MAX_DEPTH_M, 0.0f, 1.0f) * scale;

        // Lumination = direct + emission + env (eq. 4.2): light is >= 0; +Inf is the brightest finite light, and
        // the sum saturates at FLT_MAX instead of overflowing.
        for (int c = 0; c < 3; ++c) {
            float l = fmax(clean(r[(F_DIRECT + c) * face_texels], 0.0f, 0.0f, FLT_MAX, &bad_direct), 0.0f);
            if (has_emission)
                l = fmin(l + fmax(clean(r[(F_EMISSION + c) * face_texels], 0.0f, 0.0f, FLT_MAX, &bad_emission), 0.0f), FLT_MAX);
            if (has_env)
                l = fmin(l + fmax(clean(r[(F_ENV + c) * face_texels], 0.0f, 0.0f, FLT_MAX, &bad_env), 0.0f), FLT_MAX);
            out[(7 + c) * npix + p] = lo + lum_encode(l, transfer) * scale;
        }

    }

    group_counts[COUNT_ALBEDO][lid] = bad_albedo;
    group_counts[COUNT_NORMAL][lid] = bad_normal;
    group_counts[COUNT_DEPTH][lid] = bad_depth;
    group_counts[COUNT_DIRECT][lid] = bad_direct;
    group_counts[COUNT_EMISSION][lid] = bad_emission;
    group_counts[COUNT_ENV][lid] = bad_env;
    group_counts[COUNT_SKY][lid] = sky;
    group_counts[COUNT_FAR][lid] = far;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < COUNT_SLOTS) {
        int sum = 0;
        for (int i = 0; i < (int)get_local_size(0); ++i) sum += group_counts[lid][i];  // the launch may shrink the group
        if (sum) atomic_add(&counters[lid], sum);
    }
}

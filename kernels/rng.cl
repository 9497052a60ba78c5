// Counter-based random numbers: PCG4D (Jarzynski & Olano 2020) hashes (a, b, c, n) to four 32-bit values, so a
// stream is a pure function of its counters (pixel or voxel, sample, seed ^ salt, draw) and results do not depend
// on scheduling, work-group size, launch splits or device. Used by the path tracer's programs (pathtrace,
// ao_geometry, voxel_field in host/src/runtime/programs.cpp).

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

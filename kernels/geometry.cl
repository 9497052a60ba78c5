// Geometry of the block grid shared by the tracer's programs, voxel compaction and the BVH traversal: faces of
// unit blocks, orthonormal frames and cosine sampling around a normal, and a reciprocal that stays finite. No build
// options. Block (x, y, z) covers the unit cube at that corner; face ids are the outward normals
// 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z (docs/RENDERER.md).

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

// Linear id of the block at cell c.xyz of a grid sx blocks wide and sy deep (c.w is ignored: the voxel field's
// cells carry their exposed-face mask there).
static inline int block_id(int4 c, int sx, int sy) { return c.x + sx * (c.y + sy * c.z); }

// Geometry of one camera face from its primary rays (Renderer::render_geometry and render_surface,
// host/src/render/ao_geometry.cpp), in the program "ao_geometry" after render_ao.cl: no lighting, no random numbers.
// Build option, the host's: SKY_DEPTH (depth reported where the primary ray escapes), render/tracer_constants.hpp.
#ifndef SKY_DEPTH
#error "render_geometry.cl needs SKY_DEPTH: build it with renderer.cpp's pathtrace_defines()"
#endif

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

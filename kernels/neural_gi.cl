// Seed 002's per-pixel inputs, assembled on the device from a frame's front face (host/src/pipeline/neural_gi.cpp),
// and the final lighting. Channel order, encodings and sanitizing: docs/MODEL_FORMAT.md "neural_gi" and
// ngi.neural_gi.assemble_inputs (the training side), which this kernel must match:
//   0-2 position, the scene box mapped to [-1, 1] and clamped (an axis of zero extent -> 0)
//   3-5 unit normal          6-8 albedo in [0, 1]          9-11 unit view direction (camera -> point)
//   12-14 log(1 + direct)    15-17 unit direction from the point to the area light's centre
// NaN -> 0 everywhere; a vector with infinite components keeps their signs; a zero vector stays zero.

// NGI_RADIANCE_MAX, the bound of the radiances: a build option, the host's kNeuralGiRadianceMax
// (host/src/pipeline/neural_gi_inputs.hpp), which ngi.neural_gi.RADIANCE_MAX reads too.
#ifndef NGI_RADIANCE_MAX
#error "neural_gi.cl needs NGI_RADIANCE_MAX: build it with neural_gi_defines() (host/src/pipeline/neural_gi_inputs.hpp)"
#endif

// ngi.neural_gi._unit: NaN components -> 0; if any component is infinite, the vector of their signs; then
// normalized (divided by its largest |component| first, so the squares cannot overflow); zero stays zero.
static inline float3 ngi_unit(float3 v) {
    v = (float3)(isnan(v.x) ? 0.0f : v.x, isnan(v.y) ? 0.0f : v.y, isnan(v.z) ? 0.0f : v.z);
    if (isinf(v.x) || isinf(v.y) || isinf(v.z))
        v = (float3)(isinf(v.x) ? sign(v.x) : 0.0f, isinf(v.y) ? sign(v.y) : 0.0f, isinf(v.z) ? sign(v.z) : 0.0f);
    const float largest = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
    if (!(largest > 0.0f)) return (float3)(0.0f);
    v /= largest;
    return v / length(v);
}

static inline float ngi_radiance(float v) { return isnan(v) ? 0.0f : clamp(v, 0.0f, NGI_RADIANCE_MAX); }

// One work-item per output pixel (w x w, launch 2-D). The output pixel (x, y) reads the face pixel
// (stride x + stride / 2, stride y + stride / 2) of the n x n face: stride 1 is the face itself, stride K the
// pixel nearest the centre of each K x K block (the low-resolution G-buffer of joint bilateral upsampling).
// Face planes: albedo, normal, direct [3][n*n], depth [n*n] (planar depth along look). out [18][w*w].
// position_out [3][w*w] and normal_out [3][w*w]: the world position and the raw normal of each output pixel (the
// upsampling's low-resolution guides); may alias nothing else.
__kernel void neural_gi_inputs(__global const float* restrict albedo, __global const float* restrict normal,
                               __global const float* restrict depth, __global const float* restrict direct,
                               const int n, const int stride, const int w, const float cx, const float cy,
                               const float cz, const float lx, const float ly, const float lz, const float rx,
                               const float ry, const float rz, const float ux, const float uy, const float uz,
                               const float ex, const float ey, const float ez, const float box_lo_x,
                               const float box_lo_y, const float box_lo_z, const float box_hi_x,
                               const float box_hi_y, const float box_hi_z, __global float* restrict out,
                               __global float* restrict position_out, __global float* restrict normal_out) {
    // Every argument is read before the first branch (Mesa's rusticl warns about argument loads in control flow).
    const int x = get_global_id(0), y = get_global_id(1);
    const int face = n, step = stride, side = w;
    const float3 centre = (float3)(cx, cy, cz), look = (float3)(lx, ly, lz), right = (float3)(rx, ry, rz),
                 up = (float3)(ux, uy, uz), light = (float3)(ex, ey, ez);
    const float3 lo = (float3)(box_lo_x, box_lo_y, box_lo_z), hi = (float3)(box_hi_x, box_hi_y, box_hi_z);
    if (x >= side || y >= side) return;
    const int col = x * step + step / 2, row = y * step + step / 2;
    const int plane = face * face, i = row * face + col;
    const int out_plane = side * side, o = y * side + x;

    const float u = 2.0f * ((float)col + 0.5f) / (float)face - 1.0f;
    const float v = 1.0f - 2.0f * ((float)row + 0.5f) / (float)face;
    const float3 ray = look + u * right + v * up;
    const float t = depth[i];
    const float3 p = centre + (isnan(t) ? 0.0f : t) * ray;

    float3 q = 2.0f * (p - lo) / (hi - lo) - 1.0f;
    q = (float3)(hi.x > lo.x ? q.x : 0.0f, hi.y > lo.y ? q.y : 0.0f, hi.z > lo.z ? q.z : 0.0f);
    q = (float3)(isnan(q.x) ? 0.0f : q.x, isnan(q.y) ? 0.0f : q.y, isnan(q.z) ? 0.0f : q.z);
    q = clamp(q, -1.0f, 1.0f);
    const float3 nrm_raw = (float3)(normal[i], normal[plane + i], normal[2 * plane + i]);
    const float3 nrm = ngi_unit(nrm_raw);
    const float3 view = ngi_unit(p - centre);
    const float3 to_light = ngi_unit(light - p);
    const float channel[18] = {
        q.x, q.y, q.z, nrm.x, nrm.y, nrm.z,
        isnan(albedo[i]) ? 0.0f : clamp(albedo[i], 0.0f, 1.0f),
        isnan(albedo[plane + i]) ? 0.0f : clamp(albedo[plane + i], 0.0f, 1.0f),
        isnan(albedo[2 * plane + i]) ? 0.0f : clamp(albedo[2 * plane + i], 0.0f, 1.0f),
        view.x, view.y, view.z,
        log1p(ngi_radiance(direct[i])), log1p(ngi_radiance(direct[plane + i])),
        log1p(ngi_radiance(direct[2 * plane + i])),
        to_light.x, to_light.y, to_light.z};
    for (int c = 0; c < 18; ++c) out[c * out_plane + o] = channel[c];
    position_out[o] = p.x;
    position_out[out_plane + o] = p.y;
    position_out[2 * out_plane + o] = p.z;
    normal_out[o] = nrm_raw.x;
    normal_out[out_plane + o] = nrm_raw.y;
    normal_out[2 * out_plane + o] = nrm_raw.z;
}

// lighting = direct + indirect where the pixel has a surface (a normal with |n|^2 >= 0.25, as the upsampling's
// rule), direct alone elsewhere (the reference's lighting is 0 where the primary ray escapes, and direct is 0
// there too). Light terms sanitized as compose_final does (NaN and negative -> 0), the sum saturates at FLT_MAX.
// indirect_out receives the masked indirect light. One work-item per pixel of the n x n face (1-D).
__kernel void neural_gi_lighting(__global const float* restrict direct, __global const float* restrict indirect,
                                 __global const float* restrict normal, const int n,
                                 __global float* restrict indirect_out, __global float* restrict lighting) {
    const int i = get_global_id(0);
    const int plane = n * n;
    if (i >= plane) return;
    const float3 nrm = (float3)(normal[i], normal[plane + i], normal[2 * plane + i]);
    const int surface = isfinite(nrm.x) && isfinite(nrm.y) && isfinite(nrm.z) && dot(nrm, nrm) >= 0.25f;
    for (int c = 0; c < 3; ++c) {
        const float d = direct[c * plane + i], l = indirect[c * plane + i];
        const float ind = surface ? (isnan(l) ? 0.0f : clamp(l, 0.0f, FLT_MAX)) : 0.0f;
        indirect_out[c * plane + i] = ind;
        lighting[c * plane + i] = fmin((isnan(d) ? 0.0f : clamp(d, 0.0f, FLT_MAX)) + ind, FLT_MAX);
    }
}

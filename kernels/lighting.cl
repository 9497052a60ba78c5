// Light transport of the path tracer: sun, sky, emissive blocks, the rectangular area light, sky portals and
// sunlit patches by next-event estimation, MIS-weighted against the cosine-sampled continuation
// (lighting_sample). Lighting values are irradiance / pi ("lighting without albedo"); emission and sky values are
// radiance. Used by pathtrace.cl and voxel_field.cl, after rng.cl, luminance.cl, geometry.cl, bvh.cl and scene.cl.
//
// Layout of the `light` parameter array: L_SUN_DIR (3, unit vector toward the sun), L_SUN_E (3, sun irradiance
// facing the sun), L_SUN_COS (1, cosine of the sun's angular radius), L_ZENITH, L_HORIZON, L_GROUND (3 each, sky
// radiance up, at the horizon, from below it), L_GLOW (3, the sun-centred glow), then the rectangular area light:
// L_AREA_CENTRE, L_AREA_U, L_AREA_V (3 each: centre and half-edge vectors), L_AREA_RADIANCE (3; 0 = off),
// L_AREA_NORMAL (3, unit, the emitting side) and L_AREA_AREA (1, m^2). The offsets are defined once, in
// renderer.cpp (kLightLayout), and arrive here as -D build options.
#if !defined(L_SUN_DIR) || !defined(L_SUN_E) || !defined(L_SUN_COS) || !defined(L_ZENITH) || \
    !defined(L_HORIZON) || !defined(L_GROUND) || !defined(L_GLOW) || !defined(L_AREA_CENTRE) || \
    !defined(L_AREA_U) || !defined(L_AREA_V) || !defined(L_AREA_RADIANCE) || !defined(L_AREA_NORMAL) || \
    !defined(L_AREA_AREA)
#error "lighting.cl needs the light layout L_*: build the tracer's programs with renderer.cpp's pathtrace_defines()"
#endif

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

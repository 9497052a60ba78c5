// Per-frame weights of the sunlit patches (renderer.cpp: update_patches), from which the host builds the
// probabilities lighting.cl's patch_light samples with. Listed after lighting.cl by both programs that light the
// scene (pathtrace, voxel_field): a frame runs it from the program it is rendered with, so no third program is
// built for it. Build options, the host's: the sun's slots of the light layout (lighting.cl).
#if !defined(L_SUN_DIR) || !defined(L_SUN_E)
#error "patch_weights.cl needs the light layout L_*: build it with renderer.cpp's pathtrace_defines()"
#endif

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

// The display transform, shared by the compose program (its tonemap kernel) and the display program (display_compose
// writes tone-mapped pixels directly): listed before those files (host/src/runtime/programs.cpp). Build options:
// tonemap_defines() (host/src/pipeline/compose.cpp), which compose_defines() and display_defines() include.
#if !defined(CURVE_ACES) || !defined(CURVE_REINHARD) || !defined(CURVE_CLAMP) || !defined(TONEMAP_VEC)
#error "tonemap.cl needs the tone-curve codes and TONEMAP_VEC: build it with tonemap_defines() (host/src/pipeline/compose.cpp)"
#endif

// Linear -> display [0, 1]: scale (2^exposure), tone curve, optional sRGB OETF. Elementwise over `count`.
// ACES: Narkowicz's fit of the ACES filmic curve, x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14); its input is
// capped at 1e4 (where it is long saturated) so x*x cannot overflow.
// TONEMAP_VEC (8, the host's kTonemapVec) values per work-item in a float8: the same formulas lane for lane, with
// selects for the branches; the last, partial vector goes through the same code on lanes loaded one by one.
#if TONEMAP_VEC != 8
#error "tonemap is written for TONEMAP_VEC 8 (host/src/pipeline/pipeline_impl.hpp kTonemapVec)"
#endif
static inline float8 tonemap8(float8 x, const float scale, const int curve, const int srgb) {
    x = select(fmax(x, (float8)(0.0f)), (float8)(0.0f), isnan(x));
    x = fmin(x * scale, (float8)(FLT_MAX));
    if (curve == CURVE_ACES) {
        x = fmin(x, (float8)(1e4f));
        x = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
    } else if (curve == CURVE_REINHARD) {
        x = x / (1.0f + x);
    }
    x = clamp(x, 0.0f, 1.0f);
    // x^(1/2.4) as exp2(log2(x) / 2.4) where x > 0.0031308 (PoCL's general pow() is ~5x slower); log2 of the
    // lanes below that (0 included) is computed and discarded.
    if (srgb) x = select(1.055f * exp2(log2(x) * (1.0f / 2.4f)) - 0.055f, 12.92f * x, x <= 0.0031308f);
    return clamp(x, 0.0f, 1.0f);
}


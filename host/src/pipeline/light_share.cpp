// outside_light_share: how much of a frame's lumination the front camera cannot see (the per-frame switch
// between a surround-aware and a single-view model; docs/RESULTS.md). indirect_share: how much of the front view's
// final image a lightmap adds beyond direct light (the per-frame guard of `ngi lightmap --guard`).
//
// Both run on the host: each is one scalar per frame over a few N x N planes (0.2 M values at N = 256), far
// cheaper than the network they decide about, and the callers already hold the planes on the host. A kernel would
// add an upload and a reduction for no gain.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <string>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "ops/luminance.hpp"

namespace ngi {

namespace {

// The lumination input's sanitizing of one light term (docs/CONVENTIONS.md section 7): NaN and negative -> 0,
// +Inf -> FLT_MAX.
double clean_light(float v) {
    if (std::isnan(v) || v <= 0.0f) return 0.0;
    return std::isinf(v) ? double(FLT_MAX) : double(v);
}

// Sum over the face's pixels of the Rec. 709 luminance of direct + emission + env (absent terms count 0).
double face_lumination(const Frame& frame, Face face) {
    const double* kLuma = detail::kRec709Luma;
    double sum = 0.0;
    for (Feature f : {Feature::Direct, Feature::Emission, Feature::Env}) {
        const Image& im = frame.get(f, face);
        if (im.data.empty()) continue;
        const std::size_t pixels = std::size_t(im.width) * std::size_t(im.height);
        for (int c = 0; c < 3 && c < im.channels; ++c)
            for (std::size_t i = 0; i < pixels; ++i) sum += kLuma[c] * clean_light(im.data[std::size_t(c) * pixels + i]);
    }
    return sum;
}

// compose.cl's clean_light, in float as the kernel computes it: NaN -> 0, negative -> 0, +Inf -> FLT_MAX.
float clean_light_f(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX); }

// compose_final's albedo: NaN -> 0, clamped to [0, 1].
float clean_albedo(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f); }

std::string shape_text(const Image& im) {
    return std::to_string(im.width) + "x" + std::to_string(im.height) + "x" + std::to_string(im.channels);
}

// A front-face feature indirect_share reads: present (unless optional) and N x N x 3 with its data.
const Image* front_plane(const Frame& frame, Feature f, bool required) {
    const Image& im = frame.get(f, Face::Front);
    const std::size_t n = std::size_t(frame.n > 0 ? frame.n : 0);
    if (im.data.empty()) {
        if (!required) return nullptr;
        throw InputError(std::string("indirect_share: the frame has no front ") + feature_name(f) +
                         " (the share needs the front albedo and direct light)");
    }
    if (im.width != frame.n || im.height != frame.n || im.channels != 3 || im.data.size() != n * n * 3)
        throw InputError(std::string("indirect_share: the frame's front ") + feature_name(f) + " is " +
                         shape_text(im) + ", expected " + std::to_string(frame.n) + "x" + std::to_string(frame.n) +
                         "x3 (the face size)");
    return &im;
}

}  // namespace

double indirect_share(const Frame& frame, const Image& lightmap) {
    if (frame.n < 1) throw InputError("indirect_share: the frame has face size " + std::to_string(frame.n));
    const std::size_t pixels = std::size_t(frame.n) * std::size_t(frame.n);
    if (lightmap.width != frame.n || lightmap.height != frame.n || lightmap.channels != 3 ||
        lightmap.data.size() != pixels * 3)
        throw InputError("indirect_share: the lightmap is " + shape_text(lightmap) + ", expected " +
                         std::to_string(frame.n) + "x" + std::to_string(frame.n) + "x3 (the frame's front view)");
    const Image* albedo = front_plane(frame, Feature::Albedo, true);
    const Image* direct = front_plane(frame, Feature::Direct, true);
    const Image* emission = front_plane(frame, Feature::Emission, false);
    const Image* env = front_plane(frame, Feature::Env, false);

    const double* kLuma = detail::kRec709Luma;
    double added_sum = 0.0, final_sum = 0.0;
    for (int c = 0; c < 3; ++c) {
        double added_c = 0.0, final_c = 0.0;
        for (std::size_t i = std::size_t(c) * pixels, end = i + pixels; i < end; ++i) {
            // Per pixel in float, exactly as compose_final (and decode_indirect's clean(direct)) compute it; only
            // the sums are in double.
            const float a = clean_albedo(albedo->data[i]);
            const float lm = clean_light_f(lightmap.data[i]);
            const float added = std::max(lm - clean_light_f(direct->data[i]), 0.0f);
            float v = lm * a;
            if (emission) v = std::min(v + clean_light_f(emission->data[i]), FLT_MAX);
            if (env) v = std::min(v + clean_light_f(env->data[i]), FLT_MAX);
            added_c += double(added * a);
            final_c += double(v);
        }
        added_sum += kLuma[c] * added_c;
        final_sum += kLuma[c] * final_c;
    }
    // added <= lightmap per value, so the share cannot exceed 1 but for rounding; nothing lit: nothing added.
    return final_sum > 0.0 ? std::clamp(added_sum / final_sum, 0.0, 1.0) : 0.0;
}

double outside_light_share(const Frame& frame) {
    double total = 0.0, outside = 0.0;
    for (int f = 0; f < kFaceCount; ++f) {
        const double l = face_lumination(frame, Face(f));
        total += l;
        if (Face(f) != Face::Front) outside += l;
    }
    return total > 0.0 ? outside / total : 0.0;
}

}  // namespace ngi

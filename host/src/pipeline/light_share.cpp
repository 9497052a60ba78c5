// outside_light_share: how much of a frame's lumination the front camera cannot see (the per-frame switch
// between a surround-aware and a single-view model; docs/RESULTS.md).
#include <cfloat>
#include <cmath>

#include "ngi/pipeline.hpp"

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
    static constexpr double kLuma[3] = {0.2126, 0.7152, 0.0722};
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

}  // namespace

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

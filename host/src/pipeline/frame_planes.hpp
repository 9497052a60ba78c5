// The raw frame planes (ngi/pipeline.hpp kFramePlanes, frame_plane()) as kernel build options: the path tracer
// writes them (kernels/pathtrace.cl), preprocessing reads them (kernels/gbuffer.cl). Header-only, so the renderer
// uses it without linking the pipeline. Library-internal.
#pragma once
#include <string>

#include "base/surface_depth.hpp"
#include "ngi/pipeline.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// F_ALBEDO, F_NORMAL, F_DEPTH, F_DIRECT, F_EMISSION, F_ENV (first plane of each feature), F_CHANNELS (planes per face).
inline std::string frame_plane_defines() {
    return join_defines({define("F_ALBEDO", frame_plane(Feature::Albedo)), define("F_NORMAL", frame_plane(Feature::Normal)),
                         define("F_DEPTH", frame_plane(Feature::Depth)), define("F_DIRECT", frame_plane(Feature::Direct)),
                         define("F_EMISSION", frame_plane(Feature::Emission)), define("F_ENV", frame_plane(Feature::Env)),
                         define("F_CHANNELS", kFramePlanes)});
}

}  // namespace ngi::detail

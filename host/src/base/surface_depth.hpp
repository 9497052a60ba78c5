// The two depths every stage agrees on (docs/CONVENTIONS.md sections 3, 6, 19, 20). Header-only, in base so that the
// ops (image gather, probe shading), the pipeline (preprocessing, SSGI, the display view) and the tracer share them.
#pragma once

namespace ngi::detail {

// Planar depth (metres) a frame holds where there is no surface -- the tracer's escaped rays, a perspective depth
// attachment's cleared pixels: a finite sentinel, not a distance.
constexpr float kNoSurfaceDepth = 1.0e4f;
// The farthest planar depth (metres) that is a surface: beyond it a texel is no surface for every reader -- the
// preprocessing's depth scale, SSGI's and the display view's surface test, probe shading, ngi.temporal (Python:
// ngi._constants.MAX_SURFACE_DEPTH).
constexpr float kMaxSurfaceDepth = 1000.0f;
static_assert(kNoSurfaceDepth > kMaxSurfaceDepth, "the no-surface sentinel must read as no surface");

}  // namespace ngi::detail

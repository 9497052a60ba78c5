// Constants of the path tracer (kernels/scene.cl and the programs built on it) that other render code shares;
// they reach the kernels as build options (renderer.cpp's pathtrace_defines(), voxel_field.cpp's compaction).
// Library-internal.
#pragma once
#include "ops/gather_image.hpp"
#include "ops/probe_shade.hpp"

namespace ngi::detail {

// Secondary rays start this far (metres) off a surface, along its normal; a surface voxel's probe point sits this
// far off its face (kernels/voxel_compact.cl). Build option RAY_OFFSET.
constexpr float kRayOffset = 1.0e-3f;
// Depth (metres) the tracer writes where the primary ray escapes: finite on purpose, the frame's no-surface depth
// that image descriptors' perspective depth also writes (ops/gather_image.hpp). Build option SKY_DEPTH.
constexpr float kSkyDepth = kNoSurfaceDepth;
// Every reader takes depths beyond kMaxSurfaceDepth as no surface: the tracer's sky must be among them.
static_assert(kSkyDepth > kMaxSurfaceDepth, "the tracer's sky would read as a surface");

}  // namespace ngi::detail

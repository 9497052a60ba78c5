// Surround screen-space GI (issue 45): one bounce of the light the cluster's faces see, gathered at the front face
// (kernels/ssgi.cl; definitions in docs/CONVENTIONS.md section 19). The pipeline runs it for a model of family
// "ssgi" (models/ssgi_config.hpp): the rung that needs no network. Library-internal.
#pragma once
#include <string>

#include "ngi/camera.hpp"
#include "ngi/model.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// Build options of kernels/ssgi.cl.
std::string ssgi_defines();
// Smallest |cos| between a sender's normal and its camera ray used in its area: a texel seen within 6 degrees of
// grazing covers a long, thin patch whose planar-depth position is poorly known; its area is capped at 10x.
constexpr float kSsgiMinCos = 0.1f;
// Sender radiance cap: far above any light (the half-float limit is 65504), low enough that sums of area x radiance
// over a cluster stay finite in float.
constexpr float kSsgiMaxRadiance = 1e30f;
// Visibility's depth bias (kernels/ssgi.cl SSGI_VIS_SLOPE): a march sample blocks a pair only when it lies behind
// the face's surface by more than depth * slope * 2 / N, what a surface tilted to 63 degrees from the camera ray
// changes in depth across two texels' width; less and a flat floor would block the light crossing it.
constexpr float kSsgiVisSlope = 2.0f;
// Work-group size of every ssgi kernel (fixed: PoCL compiles one work-group function per size).
constexpr int kSsgiLocal = 64;
// Sender records one gathering work-item reads as a vector (kernels/ssgi.cl SSGI_VEC): 8 fills an AVX2 register and
// half an AVX-512 one; on a GPU a wider load per work-item of records every work-item reads alike.
constexpr int kSsgiVec = 8;

class Ssgi {
public:
    explicit Ssgi(Context& ctx);
    // The front face's lightmap, clean(direct) + indirect ([3][n][n] float32 into `lightmap`), from raw frame planes
    // (ngi/pipeline.hpp layout) holding `faces` faces (6, or 1 for params.view "front"). Enqueued, nothing waited for.
    // Throws InputError for a face size the clustering does not divide, or more sender records than the device's loop
    // limit allows one work-item to visit (Mesa llvmpipe: 65,535).
    void enqueue(Context& ctx, cl_mem planes, int faces, int n, bool has_emission, const CameraCluster& cluster,
                 const ModelConfig::Ssgi& params, cl_mem lightmap);

private:
    Kernel senders_, cluster_, gather_;
    Buffer fine_, mid_, coarse_, bounce_;
};

}  // namespace ngi::detail

// The front view's GI at the application's display resolution, stable from frame to frame (issue 47;
// docs/CONVENTIONS.md section 20).
//
// A SurroundPipeline computes the front view's lightmap at the cluster's face size N (64 for the offered rungs). An
// application displays far more pixels, and it already has their direct light, albedo and geometry in its G-buffer.
// A DisplayView takes that full-resolution front G-buffer beside the pipeline's N x N result and
//   1. splits the N x N lightmap into the frame's direct light and the indirect rest (lightmap - direct),
//   2. upsamples the rest to the display's S x S pixels, joint-bilaterally guided by the display's normals and world
//      positions (kernels/jbu.cl: light does not bleed across depth steps and creases the N x N grid cannot resolve),
//      or bilinearly (DisplayUpsampler::Bilinear, for comparison),
//   3. accumulates it over frames (kernels/display.cl display_temporal): the previous frame's result reprojected with
//      the camera motion and the display's depth, rejected where the point was not visible (disocclusion), clamped
//      to what this frame's light allows (a change of lighting), blended exponentially,
//   4. composes lightmap = direct + indirect and final = albedo x lightmap + emission + env at display resolution,
//      and tone maps.
// A DisplayView is one view's state (the history): one per camera / window, used by one thread at a time; reset()
// after a cut, a teleport or a scene change (anything the reprojection should not bridge).
//
// The display's camera is the cluster's front camera (90 degrees, square): the display G-buffer is S x S, with the
// frame's look and up and the same centre. A non-square window shows a crop of it (the application's concern).
#pragma once
#include <glm/glm.hpp>
#include <memory>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/image.hpp"
#include "ngi/pipeline.hpp"

namespace ngi {

enum class DisplayUpsampler { Jbu, Bilinear };
const char* display_upsampler_name(DisplayUpsampler u);                 // "jbu", "bilinear"
DisplayUpsampler display_upsampler_from_name(const std::string& name);  // throws InputError

struct DisplaySettings {
    DisplayUpsampler upsampler = DisplayUpsampler::Jbu;
    // Joint bilateral weights (ops/jbu.hpp JbuParams; docs/CONVENTIONS.md section 18): spatial sigma in N x N pixels,
    // normal exponent, tangent-plane sigma in metres, window radius 1..3.
    float sigma_spatial = 0.75f, normal_power = 32.0f, sigma_plane = 0.1f;
    int radius = 2;
    // Temporal accumulation; off: every frame stands alone (and no history is kept).
    bool temporal = true;
    // Weight of the current frame, (0, 1]: 0.2 averages ~9 frames of a static view (noise variance x 0.11) and lags a
    // steady change of light by (1 - blend) / blend = 4 frames.
    float blend = 0.2f;
    // A reprojected tap counts when its stored planar depth d agrees with the point's, |d - z| <= depth_rel z + depth_abs
    // (ngi.temporal's occlusion test).
    float depth_rel = 0.02f, depth_abs = 0.05f;
    // History clamp: the range of this frame's N x N indirect light over the 3 x 3 texels around a pixel, widened by
    // clip_margin x its mean level; < 0 turns the clamp off.
    float clip_margin = 0.25f;
};

// What one frame did (downloaded only when asked for).
struct DisplayStats {
    int jbu_fallbacks = 0;   // display pixels the joint bilateral weights left to the bilinear fallback
    int disoccluded = 0;     // surface pixels without a valid history tap (0 when no history was used)
    int clipped = 0;         // pixels whose history the clamp moved
    bool history_used = false;
};

// Wall-clock milliseconds of the display stages, waiting for the device after each (so slightly slower than untimed):
// geometry (guides of both resolutions and the N x N indirect light), upsample, temporal, outputs (compose, tone map).
struct DisplayTimings {
    double geometry_ms = 0, upsample_ms = 0, temporal_ms = 0, outputs_ms = 0;
    double total_ms() const { return geometry_ms + upsample_ms + temporal_ms + outputs_ms; }
};

class DisplayView {
public:
    // size: the display's side S in pixels, 2..16384. Throws InputError for settings out of range.
    DisplayView(const Device& device, int size, const DisplaySettings& settings = {});
    DisplayView(DisplayView&&) noexcept;
    DisplayView& operator=(DisplayView&&) noexcept;
    ~DisplayView();

    int size() const;
    const DisplaySettings& settings() const;
    // Forget the history: the next frame stands alone.
    void reset();

    // Device in, device out, asynchronous (unless stats or timings are asked for). low_planes: the frame planes the
    // pipeline ran (ngi/pipeline.hpp layout; face 0 = front, n x n); low_lightmap: that frame's lightmap
    // (FrameOutputs::lightmap, 3 n^2 floats); display_planes: one face of frame planes at S x S (albedo, normal,
    // depth, direct; emission and env when desc says so); outputs: lightmap, final_image, display, each 3 S^2 floats
    // (empty ones are not produced). `desc`: the display planes' optional features and the camera's look and up
    // (faces is not read); `position`: the camera's centre in world metres (the reprojection needs it).
    // Throws InputError for buffers too small, n < 2 or n > S, or look/up that are not a camera.
    void enqueue(int n, const DeviceBuffer& low_planes, const DeviceBuffer& low_lightmap,
                 const DeviceBuffer& display_planes, const FrameDesc& desc, const glm::vec3& position,
                 const FrameOutputs& outputs, DisplayStats* stats = nullptr, DisplayTimings* timings = nullptr);

    // The same from host memory: `low` the frame the pipeline ran (its front normal, depth and direct light are read),
    // `low_lightmap` the pipeline's lightmap of it (N x N x 3), `display` a frame of size S holding the front face
    // (albedo, normal, depth, direct; emission and env optional). The frames' look and up must agree, and the camera's
    // with them (InputError naming both otherwise). One upload, one download of the outputs asked for.
    FrameImages run(const Frame& low, const Image& low_lightmap, const Frame& display, const glm::vec3& position,
                    bool lightmap, bool final_image, bool display_image, const ToneMapOptions& tonemap = {},
                    DisplayStats* stats = nullptr, DisplayTimings* timings = nullptr);

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi

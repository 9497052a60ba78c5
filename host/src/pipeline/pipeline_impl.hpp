// Library-internal state of SurroundPipeline and the lookup tables behind the merge and the extraction
// (exposed here so tests can check them against naive references).
#pragma once
#include <array>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "ngi/host_memory.hpp"
#include "ngi/pipeline.hpp"
#include "ops/gather_image.hpp"
#include "pipeline/ssgi.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// A gather table: output pixel p = sum_k w[p][k] * source[idx[p][k]] (per channel plane).
struct GatherLut {
    std::vector<std::array<int, 4>> idx;
    std::vector<std::array<float, 4>> w;
};

// Merge table: output = global view (4N x 2N, index y * 4N + x); source = six faces stacked in Face order
// (index face * N * N + row * N + col).
GatherLut build_merge_lut(int n, GlobalViewMode mode);
// Extraction table: output = front face (N x N); source = global view (index y * 4N + x).
GatherLut build_extract_lut(int n, GlobalViewMode mode);

// Checks one face image of a frame: present, square, N x N, with the feature's channel count. `what` names
// the operation for the message.
void check_face_image(const Image& image, Feature feature, Face face, int n, const char* what);
// Whether an optional feature (emission, env) is present: on every listed face, or on none (else InputError).
bool optional_feature_present(const Frame& frame, Feature feature, const Face* faces, int face_count, int n,
                              const char* what);

// Build options of kernels/gbuffer.cl (the lumination transfer codes, the raw frame planes, the counter slots) and of
// kernels/compose.cl (the lumination transfer and tone curve codes): the host's values, defined once.
std::string preprocess_defines();
std::string compose_defines();
// Build options of kernels/tonemap.cl (the tone curve codes, TONEMAP_VEC): part of compose_defines() and of the display
// program's options.
std::string tonemap_defines();
// Values per work-item of compose.cl's tonemap (TONEMAP_VEC, a float8): PoCL evaluates the sRGB curve's scalar exp2
// and log2 one value at a time (~25 ns per value, 0.3 ms of a 64 x 64 frame); in vector lanes they are ~1 ns.
constexpr int kTonemapVec = 8;
// tonemap's global size for `count` values.
inline std::size_t tonemap_items(int count) { return (std::size_t(count) + kTonemapVec - 1) / kTonemapVec; }
// Build options of kernels/metrics.cl: the SSIM window radius and the two fixed work-group sizes (metrics.cpp).
std::string metrics_defines();
// The largest lightmap value the decoding produces: the largest half float, so a lightmap survives a half-float EXR
// (compose.cl LIGHT_MAX; Python's ngi.scoring.LIGHT_MAX).
constexpr float kLightMax = 65504.0f;

// Which input the model wants: true = global view (12 channels), false = front view only (10). Throws InputError
// for a model whose input width, input_layout or input_range the pipeline cannot serve.
bool check_model_input(const ModelConfig& config);
// The faces a model reads from a frame: 6 (a surround-aware network, an ssgi rung of view "surround") or 1 (the
// front face). Throws InputError as check_model_input for a network the pipeline cannot serve.
int frame_faces(const ModelConfig& config);
// Whether the model's output is indirect light only (output_mode "indirect"), which the output side adds to the
// frame's front direct light. Throws InputError naming `what` for an output_mode other than "lightmap" and
// "indirect" (a hand-built ModelConfig: the loader refuses other values).
bool indirect_output(const ModelConfig& config, const char* what);

// Wall-clock stage times into a timings struct (FrameTimings, DisplayTimings), when one is given: each lap waits for
// the device and stores the time since the previous lap into the named field.
template <class Timings>
class StageClock {
public:
    StageClock(Context& ctx, Timings* timings)
        : ctx_(ctx), timings_(timings), t_(std::chrono::steady_clock::now()) {}
    void operator()(double Timings::*field) {
        if (!timings_) return;
        ctx_.finish();
        const auto now = std::chrono::steady_clock::now();
        timings_->*field = std::chrono::duration<double, std::milli>(now - t_).count();
        t_ = now;
    }

private:
    Context& ctx_;
    Timings* timings_;
    std::chrono::steady_clock::time_point t_;
};

// Work-group shapes of the pipeline's element-wise (64) and image (8 x 8) kernels: fixed, as PoCL compiles one
// work-group function per local size.
inline constexpr std::size_t kLocal1[1] = {64};
inline constexpr std::size_t kLocal2[2] = {8, 8};

}  // namespace ngi::detail

namespace ngi {

struct SurroundPipeline::Impl {
    Device device;  // keeps the context alive
    detail::Context& ctx;
    int n;
    GlobalViewMode mode;
    LuminationTransfer transfer;

    detail::Kernel gather, preprocess, decode, decode_indirect, encode, resize, compose, tonemap;
    detail::Kernel encode_ssgi, decode_residual;  // output mode "ssgi_residual"
    detail::Buffer merge_idx, merge_w;      // 8 N^2 entries
    detail::Buffer extract_idx, extract_w;  // N^2 entries
    HostMemoryHold coords_hold;             // coords' bytes in the host-memory ledger (64 N^2: 256 MiB at 2048)
    Image coords;                           // 4N x 2N x 2, phi and theta in [0, 1]

    // Scratch reused between frames, grown on demand.
    detail::Buffer raw, stack, view, counters, light, aux[3], out;
    detail::Buffer frame_out, frame_light, frame_final, frame_result;  // enqueue() / run()
    DeviceBuffer raw_handle, out_handles[3];                           // run(): raw and the outputs as handles
    // The coordinate planes of `view` hold the coordinate map scaled to this input range.
    float coords_lo = 0.0f, coords_hi = 0.0f;

    Impl(const Device& d, int n, GlobalViewMode mode, LuminationTransfer transfer);

    // Launches lut_gather: `channels` planes of src (plane stride src_plane) through the table into dst.
    void gather_planes(cl_mem src, int src_plane, const detail::Buffer& idx, const detail::Buffer& w, int npix,
                       int channels, cl_mem dst, int dst_plane);

    // The network input from raw planes on the device (layout of kFramePlanes): resets the counters, preprocesses
    // `faces` faces into `stack` and, for a surround model, merges them into `view` beside the coordinate planes.
    // Returns the buffer that holds the input ([1, 12, 2N, 4N] in view, or [1, 10, N, N] in stack).
    const detail::Buffer& enqueue_input(cl_mem raw, int faces, bool has_emission, bool has_env, glm::vec3 look,
                                        glm::vec3 up, const ModelConfig& config, bool surround);
    // Output mode "ssgi_residual": the SSGI gather of the raw planes (`faces` faces, config.ssgi) into ssgi_light,
    // then the network input [1, 13, N, N] in `stack`: the front view's preprocessed planes and the SSGI estimate
    // encoded into planes 10-12 (compose.cl encode_ssgi_input).
    const detail::Buffer& enqueue_residual_input(cl_mem raw, int faces, bool has_emission, bool has_env,
                                                 glm::vec3 look, glm::vec3 up, const ModelConfig& config);
    detail::Buffer ssgi_light;
    // Downloads the preprocessing counters of the last enqueue_input into `stats`.
    void read_stats(PreprocessStats& stats);
    // Decode (in place), compose and tone map of enqueue(); the destinations are raw buffers of >= 3 N^2 floats.
    // An indirect-mode model's decoded output is added to the front direct light read from `planes`; an
    // ssgi_residual model's output is first added to the SSGI channels of its input `residual_input`.
    void enqueue_outputs(cl_mem model_out, bool global, const ModelConfig& config, cl_mem planes, bool has_emission,
                         bool has_env, cl_mem light_dst, cl_mem final_dst, cl_mem display_dst,
                         const ToneMapOptions& tonemap, cl_mem residual_input = nullptr);
    // Compose and tone map of a lightmap already in light_dst (>= 3 N^2 floats); nothing when neither is asked for.
    void enqueue_final(cl_mem light_dst, cl_mem planes, bool has_emission, bool has_env, cl_mem final_dst,
                       cl_mem display_dst, const ToneMapOptions& tonemap);
    // enqueue()'s checks of the planes (faces_used faces) and of the outputs asked for.
    void check_frame_buffers(const DeviceBuffer& planes, int faces_used, const FrameOutputs& outputs);
    // enqueue() for a model of family "ssgi" (no network): the gather of pipeline/ssgi.cpp, then compose and tone map.
    void enqueue_ssgi(const ModelConfig& config, const DeviceBuffer& planes, const FrameDesc& desc,
                      const FrameOutputs& outputs, PreprocessStats* stats, FrameTimings* timings);
    std::unique_ptr<detail::Ssgi> ssgi;  // built on first use

    // run(): scratch device outputs for the images asked for, and their one download (timed into outputs_ms).
    FrameOutputs scratch_outputs(bool lightmap, bool final_image, bool display, const ToneMapOptions& tonemap);
    FrameImages download_outputs(const FrameOutputs& outputs, FrameTimings* timings);

    // Image descriptors (frame_inputs.cpp): the gather op, built on first use, and the staging buffer of host images.
    std::unique_ptr<detail::GatherImage> gather_image;
    detail::Buffer staging;
};

}  // namespace ngi

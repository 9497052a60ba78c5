// The surround-aware pipeline around the generator (docs/CONVENTIONS.md has every convention used here):
//
//   Frame (6 faces x features) --network_input--> NCHW tensor [1, 12, 2N, 4N] (or [1, 10, N, N] front only)
//   model output [1, 3, 2N, 4N] --front_lightmap--> N x N linear lightmap --compose--> final --tonemap--> display
//
// A SurroundPipeline is built for one face size N; it builds its lookup tables once and keeps its device
// buffers between frames. It is used by one thread at a time; pipelines of other threads may share its Device.
//
// One frame in one call: enqueue() (device in, device out, asynchronous, no host transfer) or run() (host in, host
// out: one upload of the frame's planes, one download of the outputs asked for). The step-by-step calls below
// (network_input, front_lightmap, compose, tonemap) remain for training, tests and tools.
#pragma once
#include <array>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/image.hpp"
#include "ngi/image_desc.hpp"
#include "ngi/model.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

// How six N x N faces become one 4N x 2N global view.
enum class GlobalViewMode {
    Thesis,       // the thesis's MergeToGlobalView: side faces copied, up/down faces resampled into the bands
    Equirect,     // every pixel resampled at its own (phi, theta): a true equirectangular panorama
};
const char* global_view_mode_name(GlobalViewMode m);                 // "thesis", "equirect"
GlobalViewMode global_view_mode_from_name(const std::string& name);  // throws InputError

// Unit direction, in cluster space, of the centre of global-view pixel (x, y) (row 0 = top) of a 4N x 2N view.
// The single definition behind the merge's lookup table and the coordinate map.
glm::vec3 global_view_direction(int x, int y, int n, GlobalViewMode mode);

// Normalized spherical coordinates of a cluster-space direction d (any length > 0):
// phi = atan2(d.x, -d.z) / (2 pi) + 0.5 in [0, 1] (0.5 = straight ahead, increasing to the right),
// theta = acos(d.y / |d|) / pi in [0, 1] (0 = up). And the inverse (a unit vector).
glm::vec2 direction_to_phi_theta(glm::vec3 d);
glm::vec3 phi_theta_to_direction(float phi, float theta);

// How HDR lumination (linear, >= 0, unbounded) is brought to [0, 1] before the model's input scaling, and
// how the model's output is brought back. Reinhard: y = x / (1 + x), x = y / (1 - y). Clamp: y = min(x, 1)
// (the thesis's 8-bit data sets), x = y.
enum class LuminationTransfer { Reinhard, Clamp };
const char* lumination_transfer_name(LuminationTransfer t);                     // "reinhard", "clamp"
LuminationTransfer lumination_transfer_from_name(const std::string& name);      // throws InputError

// Channel names of the network input, in tensor order: surround (12) or front view only (10). A model's
// ModelConfig::input_layout, when not empty, must equal one of these.
const std::vector<std::string>& surround_input_channels();
const std::vector<std::string>& single_view_input_channels();
// A network that corrects SSGI (output_mode "ssgi_residual"): the front view's 10 channels, then the SSGI rung's
// indirect light encoded like a training target ("ssgi.r", "ssgi.g", "ssgi.b"; docs/CONVENTIONS.md section 8).
const std::vector<std::string>& ssgi_residual_input_channels();

// The share of a frame's lumination (direct + emission + env, each term sanitized as the network input's
// lumination is) that lies outside the front face: sum over the five other faces / sum over all six, each sum
// the Rec. 709 luminance over every pixel of the face, in double. In [0, 1]; 0 for a frame without light. A
// frame whose light is nearly all on screen (a small share) gains little from the surround-aware network: the
// per-frame switch of a plan (docs/RESULTS.md, "Model only what a scene requires") runs a single-view model then.
double outside_light_share(const Frame& frame);

// The share of the front view's final image that a lightmap adds beyond the frame's direct light (the per-frame
// guard of `ngi lightmap --guard`, docs/CONVENTIONS.md section 17):
//   sum Y(albedo x max(clean(lightmap) - clean(direct), 0)) / sum Y(final),
// final = compose_final's albedo x clean(lightmap) + clean(emission) + clean(env) (the terms the frame has), both
// sums over the front face's pixels in double, Y = Rec. 709 luminance (as outside_light_share), albedo NaN -> 0
// and clamped to [0, 1], clean = compose's rule for light terms (NaN, negative -> 0; +Inf -> FLT_MAX). In [0, 1];
// 0 when nothing is lit. Any lightmap: a lightmap-mode network's or an indirect-mode one's (direct + indirect).
// A large share means the frame's look rests mostly on the network's indirect light. Throws InputError when
// `lightmap` is not N x N x 3 or the frame lacks the front albedo or direct light (or one is not N x N x 3).
double indirect_share(const Frame& frame, const Image& lightmap);

// What preprocessing found in a frame's raw buffers (all faces it used).
struct PreprocessStats {
    std::array<int, kFeatureCount> nonfinite{};  // NaN / +-Inf values replaced, per Feature
    int sky_normals = 0;                         // zero-length normals (sky), kept as the zero vector
    int far_depths = 0;                          // depths beyond 1000 m (clamped to 1)
    int total_nonfinite() const;
};

// Display transform for 8-bit output: exposure, tone curve, sRGB OETF; the result lies in [0, 1].
enum class ToneCurve { AcesFitted, Reinhard, Clamp };
struct ToneMapOptions {
    float exposure_ev = 0.0f;           // multiply by 2^exposure_ev first
    ToneCurve curve = ToneCurve::AcesFitted;
    bool srgb = true;                   // apply the sRGB OETF (PNG expects sRGB-encoded values)
};
const char* tone_curve_name(ToneCurve c);                   // "aces", "reinhard", "clamp"
ToneCurve tone_curve_from_name(const std::string& name);    // throws InputError

// A frame's raw planes in one array (device buffer or host memory): float32, [face][plane][row][col], row 0 =
// top, faces in Face order (front, back, left, right, up, down; a frame for a single-view model may hold the
// front face only), kFramePlanes planes per face: albedo RGB 0-2, normal XYZ 3-5 (world space), depth 6 (metres),
// direct RGB 7-9, emission RGB 10-12, env RGB 13-15 (kernels/gbuffer.cl reads the same layout). Planes of an
// absent optional feature (emission, env) are not read. This is the layout the renderer's feature buffers have.
constexpr int kFramePlanes = 16;
// First plane of a feature: 0, 3, 6, 7, 10, 13.
constexpr int frame_plane(Feature feature) {
    constexpr int first[kFeatureCount] = {0, 3, 6, 7, 10, 13};
    return first[int(feature)];
}
std::size_t frame_planes_bytes(int n, int faces);   // faces * 16 * n * n * 4
// Packs a Frame's face images (faces = 6, or 1: the front face) into that layout; absent optional features are 0.
std::vector<float> pack_frame_planes(const Frame& frame, int faces);

// What enqueue() needs to know about the planes: how many faces they hold, which optional features, the camera.
struct FrameDesc {
    int faces = kFaceCount;  // 6, or 1 (front face only: single-view models)
    bool has_emission = false, has_env = false;
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};  // the front camera (world space)
    static FrameDesc of(const Frame& frame, int faces);  // from a Frame: presence of emission/env, look, up
};
// The inverse of pack_frame_planes: a Frame of n x n images from planes in that layout (frame_planes_bytes(n,
// desc.faces) bytes are read), desc.faces of its faces (6, or 1: the front face), the optional features desc says are
// present, desc's look and up. Throws InputError for faces other than 1 or 6, n < 1 or null planes.
Frame unpack_frame_planes(const float* planes, int n, const FrameDesc& desc);

// The outputs of one frame; empty buffers are not produced. Each is N x N x 3 planar float32 (3 N^2 floats):
// lightmap = linear HDR lightmap of the front view (for an output_mode "indirect" model: its decoded indirect light
// + the planes' front direct light, docs/CONVENTIONS.md section 8), final_image = lightmap x albedo + emission + env (linear),
// display = final_image tone-mapped by `tonemap` to [0, 1].
struct FrameOutputs {
    DeviceBuffer lightmap, final_image, display;
    ToneMapOptions tonemap;
};

// Host results of run(); the images not asked for stay empty.
struct FrameImages {
    Image lightmap, final_image, display;
};

// Wall-clock milliseconds of a frame's stages, measured when asked for by waiting for the device after each stage
// (so a timed frame runs slightly slower than an untimed one: one queue drain per stage). gather: host images'
// upload + the descriptors' gather (0 for frame planes); input: preprocessing, merge and coordinate map; network:
// the generator; outputs: front-view extraction, decode, compose and tone map.
struct FrameTimings {
    double gather_ms = 0, input_ms = 0, network_ms = 0, outputs_ms = 0;
    double total_ms() const { return gather_ms + input_ms + network_ms + outputs_ms; }
};

class SurroundPipeline {
public:
    // n: face size, even, 2 <= n <= 2048. Builds the merge and extract lookup tables and the coordinate map.
    SurroundPipeline(const Device& device, int n, GlobalViewMode mode = GlobalViewMode::Thesis,
                     LuminationTransfer transfer = LuminationTransfer::Reinhard);
    SurroundPipeline(SurroundPipeline&&) noexcept;
    SurroundPipeline& operator=(SurroundPipeline&&) noexcept;
    ~SurroundPipeline();

    int n() const;
    GlobalViewMode mode() const;
    LuminationTransfer transfer() const;
    int width() const { return 4 * n(); }   // global view size
    int height() const { return 2 * n(); }

    // One frame, device in and device out: preprocessing, merge, coordinate map, generator, front-view
    // extraction, decode, compose and tone map enqueued on the device's in-order queue. No host transfer and
    // nothing waited for (the first frame of a pipeline also uploads its constant coordinate planes), unless
    // `stats` is given: then it blocks to download the preprocessing counters. `planes` is only read.
    // Throws InputError for buffers too small, read-only outputs, buffers of another device, or a model that does
    // not fit (its input width, input_layout or size).
    // `timings`, when given, receives each stage's wall-clock time (waiting for the device after each stage).
    void enqueue(Model& model, const DeviceBuffer& planes, const FrameDesc& desc, const FrameOutputs& outputs,
                 PreprocessStats* stats = nullptr, FrameTimings* timings = nullptr);

    // The same from host memory: exactly one upload (the frame's planes, packed) and one download (the outputs
    // asked for, side by side), plus the counters' download when `stats` is given.
    FrameImages run(Model& model, const Frame& frame, bool lightmap, bool final_image, bool display,
                    const ToneMapOptions& tonemap = {}, PreprocessStats* stats = nullptr,
                    FrameTimings* timings = nullptr);
    // The same from frame planes already packed in host memory (layout above; planes_bytes >= what desc needs).
    FrameImages run(Model& model, const float* planes, std::size_t planes_bytes, const FrameDesc& desc, bool lightmap,
                    bool final_image, bool display, const ToneMapOptions& tonemap = {},
                    PreprocessStats* stats = nullptr, FrameTimings* timings = nullptr);

    // One frame from image descriptors (ngi/image_desc.hpp: an engine's render targets as they are, host memory or
    // device buffers, any of the formats, strides and row orders it describes). Each image is gathered on the device
    // into the pipeline's frame planes by one kernel; the host images are uploaded first, all in one transfer (device
    // images need none). Then as enqueue() above. Throws InputError naming the face and feature of a descriptor that
    // does not fit (validate_image_desc), before anything is enqueued.
    void enqueue(Model& model, const FrameInputs& inputs, const FrameOutputs& outputs,
                 PreprocessStats* stats = nullptr, FrameTimings* timings = nullptr);
    // The same, blocking, with host outputs (one download of the outputs asked for).
    FrameImages run(Model& model, const FrameInputs& inputs, bool lightmap, bool final_image, bool display,
                    const ToneMapOptions& tonemap = {}, PreprocessStats* stats = nullptr,
                    FrameTimings* timings = nullptr);

    // One raw feature of all six faces merged into a 4N x 2N image (no preprocessing, no sanitizing).
    Image global_view(const Frame& frame, Feature feature);

    // The 2-channel coordinate map (phi, theta in [0, 1]) of the global view, 4N x 2N.
    const Image& coord_map() const;

    // The generator's input for `frame`: config.input_nc = 12 gives the global view [1, 12, 2N, 4N], 10 gives
    // the front face only [1, 10, N, N]; channel order as surround_input_channels(), values in
    // config.input_range. Needs albedo, normal, depth and direct of every face used; emission and env are
    // optional (all six faces or none). Throws InputError for a frame or config that does not fit.
    Tensor network_input(const Frame& frame, const ModelConfig& config, PreprocessStats* stats = nullptr);

    // The front view's linear HDR lightmap (N x N x 3) from the generator's output: [1, 3, 2N, 4N] (front
    // view extracted: an exact crop in Thesis mode) or [1, 3, N, N]; values mapped from config.output_range
    // through the inverse lumination transfer. For config.output_mode "lightmap" only: an "indirect" config
    // throws InputError (its lightmap needs the frame's direct light: use the overload below).
    Image front_lightmap(const Tensor& model_output, const ModelConfig& config);
    // The same for a model of either output mode. "indirect": the decoded output is indirect light, and the
    // lightmap is that + the frame's front direct light (Feature::Direct of Face::Front, N x N x 3; NaN and
    // negative -> 0, +Inf -> FLT_MAX, the sum saturating at FLT_MAX; docs/CONVENTIONS.md section 8); InputError
    // naming the feature and face when the frame lacks it. "lightmap": the frame is not read.
    Image front_lightmap(const Tensor& model_output, const ModelConfig& config, const Frame& frame);

    // The inverse of front_lightmap's decoding, for training targets: a linear lightmap (any size, 3 channels)
    // -> [1, 3, H, W] in config.output_range through this pipeline's lumination transfer. Light is sanitized
    // like the input's lumination and encoded by the same formula (docs/CONVENTIONS.md, section 8).
    Tensor encode_lightmap(const Image& lightmap, const ModelConfig& config);

    // final = lightmap x albedo + emission + env of the front face (the terms the frame has). The lightmap
    // must be N x N x 3; with frame.reference as the lightmap this gives the reference final image.
    Image compose(const Image& lightmap, const Frame& frame);

    // Bilinear resize (pixel centres, edge clamped) of any image to width x height.
    Image upscale(const Image& image, int width, int height);

    // Linear image (any channel count) to display-referred [0, 1] values (see ToneMapOptions).
    Image tonemap(const Image& linear, const ToneMapOptions& options = {});

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi

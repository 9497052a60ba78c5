// Seed 002 on one frame (ngi/neural_gi.hpp): kernels/neural_gi.cl assembles the inputs from the front face, the
// neural_gi model runs as one graph, ops/jbu upsamples its indirect light when it ran at a lower resolution, and
// neural_gi_lighting adds the direct light. Everything stays on the device between the upload of the four face
// planes and the download of the two results.
#include "ngi/neural_gi.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/vec_text.hpp"
#include "models/model_access.hpp"
#include "ops/jbu.hpp"
#include "pipeline/neural_gi_inputs.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/context.hpp"

namespace ngi {

namespace {

constexpr int kInputChannels = 18;  // docs/MODEL_FORMAT.md "neural_gi"

const Image& front(const Frame& frame, Feature f) {
    const Image& im = frame.get(f, Face::Front);
    if (im.width != frame.n || im.height != frame.n || im.channels != feature_channels(f))
        throw InputError(std::string("neural GI: the frame's front ") + feature_name(f) + " is " +
                         std::to_string(im.width) + "x" + std::to_string(im.height) + "x" + std::to_string(im.channels) +
                         ", expected " + std::to_string(frame.n) + "x" + std::to_string(frame.n) + "x" +
                         std::to_string(feature_channels(f)));
    return im;
}

void require_finite(const glm::vec3& v, const char* what) {
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw InputError(std::string("neural GI: the frame's ") + what + " is not finite");
}

// A Neural GI model is trained for one scene: the camera and the light of a frame of that scene lie in its box
// (the grid). A point outside means a frame of another scene (or a light placed where training never put one), whose
// inputs the network would see clamped to the box's faces and answer with confident, wrong light. The margin
// (1e-3 of the box's largest side) only absorbs float rounding of points on a face.
void require_in_box(const glm::vec3& p, const ModelConfig::NeuralGi& cfg, const char* what) {
    float extent = 0.0f;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, cfg.scene_max[k] - cfg.scene_min[k]);
    const float margin = 1.0e-3f * extent;
    for (int k = 0; k < 3; ++k)
        if (!(p[k] >= cfg.scene_min[k] - margin && p[k] <= cfg.scene_max[k] + margin)) {
            const glm::vec3 lo(cfg.scene_min[0], cfg.scene_min[1], cfg.scene_min[2]);
            const glm::vec3 hi(cfg.scene_max[0], cfg.scene_max[1], cfg.scene_max[2]);
            throw InputError(std::string("neural GI: the frame's ") + what + " " + detail::vec_text(p) +
                             " is outside the model's scene box " + detail::vec_text(lo) + ".." + detail::vec_text(hi) +
                             ": a frame of another scene? (a Neural GI model is trained "
                             "for one scene; neural_gi.scene_box in the model file)");
        }
}

}  // namespace

struct NeuralGiRenderer::Impl {
    Device device;
    detail::Context& ctx;
    detail::Kernel inputs, lighting;
    detail::JointBilateralUpsample jbu;
    // Face planes; the network's input, output and low-resolution guides; the full-resolution guides (only when
    // upsampling: inputs at stride 1); the results.
    detail::Buffer albedo, normal, depth, direct, net_in, net_out, low_position, low_normal, hi_inputs, hi_position,
        hi_normal, upsampled, indirect, lit;

    explicit Impl(const Device& d)
        : device(d),
          ctx(detail::context_of(device)),
          inputs(ctx.kernel("neural_gi", "neural_gi_inputs", detail::neural_gi_defines())),
          lighting(ctx.kernel("neural_gi", "neural_gi_lighting", detail::neural_gi_defines())),
          jbu(ctx) {}

    void upload(detail::Buffer& b, const Image& im, const char* what) {
        detail::ensure_buffer(ctx, b, im.data.size() * sizeof(float), what);
        ctx.write(b, 0, im.data.size() * sizeof(float), im.data.data(), what);
    }

    // The inputs of every stride-th pixel (side = n / stride) into `out`, with their positions and raw normals.
    void assemble(const Frame& frame, const ModelConfig::NeuralGi& cfg, int stride, detail::Buffer& out,
                  detail::Buffer& position, detail::Buffer& nrm) {
        const int n = frame.n, side = n / stride;
        const std::size_t plane = std::size_t(side) * side * sizeof(float);
        detail::ensure_buffer(ctx, out, kInputChannels * plane, "neural GI: network input");
        detail::ensure_buffer(ctx, position, 3 * plane, "neural GI: positions");
        detail::ensure_buffer(ctx, nrm, 3 * plane, "neural GI: normals");
        const CameraCluster cluster = CameraCluster::from_look_up(frame.look, frame.up);
        const FaceBasis b = cluster.face(Face::Front);
        const glm::vec3 c = *frame.position, l = frame.area_light->centre;
        inputs.args(albedo, normal, depth, direct, n, stride, side, c.x, c.y, c.z, b.look.x, b.look.y, b.look.z,
                    b.right.x, b.right.y, b.right.z, b.up.x, b.up.y, b.up.z, l.x, l.y, l.z, cfg.scene_min[0],
                    cfg.scene_min[1], cfg.scene_min[2], cfg.scene_max[0], cfg.scene_max[1], cfg.scene_max[2], out,
                    position, nrm);
        const std::size_t g[2] = {std::size_t(side), std::size_t(side)};
        ctx.launch(inputs, 2, g, detail::kLocal2);
    }
};

const std::vector<std::string>& neural_gi_input_channels() {
    static const std::vector<std::string> names = {
        "position.x", "position.y", "position.z", "normal.x", "normal.y", "normal.z",
        "albedo.r", "albedo.g", "albedo.b", "view.x", "view.y", "view.z",
        "log1p_direct.r", "log1p_direct.g", "log1p_direct.b", "light_dir.x", "light_dir.y", "light_dir.z"};
    return names;
}

NeuralGiRenderer::NeuralGiRenderer(const Device& device) : impl_(std::make_unique<Impl>(device)) {}
NeuralGiRenderer::NeuralGiRenderer(NeuralGiRenderer&&) noexcept = default;
NeuralGiRenderer& NeuralGiRenderer::operator=(NeuralGiRenderer&&) noexcept = default;
NeuralGiRenderer::~NeuralGiRenderer() = default;

NeuralGiImages NeuralGiRenderer::run(Model& model, const Frame& frame, const NeuralGiOptions& options) {
    Impl& im = *impl_;
    const ModelConfig& config = model.config();
    // A requirement of the renderer, not a dispatch: it assembles neural_gi's 18 inputs and reads the family's own
    // section (ModelConfig::neural_gi).
    if (config.family != "neural_gi")
        throw InputError("neural GI: the model is a " + config.family + " model; a neural_gi model is needed");
    if (!config.neural_gi.has_scene_box)
        throw InputError("neural GI: the model file has no neural_gi.scene_box (the box its positions were "
                         "normalized with): export it with ngi.neural_gi.export_model(..., scene_box=...)");
    // The model must read what the kernel assembles: 18 channels, and if it names them, these names in this order
    // (a model trained on other inputs ran here before, its output meaningless, without a word).
    const std::vector<std::string>& names = neural_gi_input_channels();
    if (config.input_nc != kInputChannels)
        throw InputError("neural GI: the model takes " + std::to_string(config.input_nc) + " input channels; the " +
                         "frame's assembled inputs are " + std::to_string(kInputChannels));
    if (!config.input_layout.empty() && config.input_layout != names) {
        std::size_t i = 0;
        while (i < names.size() && i < config.input_layout.size() && config.input_layout[i] == names[i]) ++i;
        throw InputError("neural GI: the model's input_layout differs from the assembled inputs at channel " +
                         std::to_string(i) + ": model '" +
                         (i < config.input_layout.size() ? config.input_layout[i] : std::string("(none)")) +
                         "', assembled '" + (i < names.size() ? names[i] : std::string("(none)")) + "'");
    }
    if (detail::shared_context_of(detail::ModelAccess::device(model)) != detail::shared_context_of(im.device))
        throw InputError("neural GI: the model was loaded on another device than the renderer's");
    if (!frame.area_light || !frame.position)
        throw InputError("neural GI: the frame has no area light (camera.json \"area_light\" and \"position\"); "
                         "Neural GI models are trained for a scene lit by one (ngi render --area-light)");
    require_finite(*frame.position, "camera position");
    check_area_light(*frame.area_light, "neural GI");
    require_in_box(*frame.position, config.neural_gi, "camera position");
    require_in_box(frame.area_light->centre, config.neural_gi, "area light centre");
    const int n = frame.n, k = options.upsample;
    if (k < 1 || k > 64 || n < 1 || n % k)
        throw InputError("neural GI: upsample " + std::to_string(k) + " must be in 1..64 and divide the face size " +
                         std::to_string(n));
    const int side = n / k, step = 1 << config.unet.num_downs;
    if (side % step)
        throw InputError("neural GI: the network runs at " + std::to_string(side) + "x" + std::to_string(side) +
                         " (face size " + std::to_string(n) + " / upsample " + std::to_string(k) +
                         "), which must be a multiple of 2^num_downs = " + std::to_string(step));
    const Image& albedo = front(frame, Feature::Albedo);
    const Image& normal = front(frame, Feature::Normal);
    const Image& depth = front(frame, Feature::Depth);
    const Image& direct = front(frame, Feature::Direct);
    detail::JbuParams jbu;
    jbu.sigma_spatial = options.jbu_sigma_spatial;
    jbu.normal_power = options.jbu_normal_power;
    jbu.sigma_plane = options.jbu_sigma_plane;

    detail::Context& ctx = im.ctx;
    im.upload(im.albedo, albedo, "neural GI: albedo");
    im.upload(im.normal, normal, "neural GI: normal");
    im.upload(im.depth, depth, "neural GI: depth");
    im.upload(im.direct, direct, "neural GI: direct light");
    const ModelConfig::NeuralGi& cfg = config.neural_gi;
    im.assemble(frame, cfg, k, im.net_in, im.low_position, im.low_normal);
    const std::size_t low_plane = std::size_t(side) * side, plane = std::size_t(n) * n;
    detail::ensure_buffer(ctx, im.net_out, 3 * low_plane * sizeof(float), "neural GI: network output");
    detail::ModelAccess::enqueue(model, im.net_in.get(), 0, im.net_out.get(), 0, side, side);

    NeuralGiImages out;
    out.network_size = side;
    // The inputs kernel replaces NaN (-> 0) and infinities (clamped, or a unit vector of their signs) without a
    // trace on the device; they are counted here, on the host copy, so that a frame with NaN features is reported
    // (the model's guard sees only the already-sanitized inputs).
    for (const Image* feature : {&albedo, &normal, &depth, &direct})
        for (float v : feature->data) out.nonfinite_features += !std::isfinite(v);
    cl_mem indirect = im.net_out.get();
    if (k > 1) {
        im.assemble(frame, cfg, 1, im.hi_inputs, im.hi_position, im.hi_normal);
        detail::ensure_buffer(ctx, im.upsampled, 3 * plane * sizeof(float), "neural GI: upsampled indirect light");
        detail::JbuInputs in;
        in.low_width = in.low_height = side;
        in.channels = 3;
        in.low = im.net_out.get();
        in.low_normal = im.low_normal.get();
        in.low_position = im.low_position.get();
        in.width = in.height = n;
        in.normal = im.hi_normal.get();
        in.position = im.hi_position.get();
        im.jbu.enqueue(ctx, in, jbu, im.upsampled.get(), false);
        indirect = im.upsampled.get();
    }
    detail::ensure_buffer(ctx, im.indirect, 3 * plane * sizeof(float), "neural GI: indirect light");
    detail::ensure_buffer(ctx, im.lit, 3 * plane * sizeof(float), "neural GI: lighting");
    im.lighting.args(im.direct, indirect, im.normal, n, im.indirect, im.lit);
    const std::size_t g[1] = {plane};
    ctx.launch(im.lighting, 1, g, detail::kLocal1);

    out.indirect = Image(n, n, 3);
    out.lighting = Image(n, n, 3);
    ctx.read(im.indirect, 0, 3 * plane * sizeof(float), out.indirect.data.data(), "neural GI: indirect light");
    ctx.read(im.lit, 0, 3 * plane * sizeof(float), out.lighting.data.data(), "neural GI: lighting");
    if (k > 1) out.jbu_fallbacks = im.jbu.fallback_count(ctx);
    out.sanitized_inputs = model.sanitized_inputs();
    return out;
}

}  // namespace ngi

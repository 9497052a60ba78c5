// The generator's input: raw faces -> preprocess_gbuffer (kernels/gbuffer.cl) -> merge (lut_gather) ->
// NCHW tensor with the coordinate map. Channel order and value rules: docs/CONVENTIONS.md.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "ngi/error.hpp"
#include "models/ssgi_config.hpp"
#include "pipeline/frame_planes.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi {

namespace {

constexpr int kFeaturePlanes = 10; // albedo 3, normal 3, depth 1, lumination 3
// Counter slots of preprocess_gbuffer: the non-finite values per Feature (slot = the Feature's value), then sky
// normals and far depths.
constexpr int kCountSky = kFeatureCount, kCountFar = kFeatureCount + 1, kCounterSlots = kFeatureCount + 2;
// preprocess_gbuffer's work-group size (its PREPROCESS_LOCAL): fixed, as PoCL compiles one work-group function per size.
constexpr int kPreprocessLocal = 64;
const Face kAllFaces[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};

}  // namespace

std::size_t frame_planes_bytes(int n, int faces) {
    return std::size_t(faces) * kFramePlanes * std::size_t(n) * std::size_t(n) * sizeof(float);
}

std::vector<float> pack_frame_planes(const Frame& frame, int faces) {
    if (faces != 1 && faces != kFaceCount)
        throw InputError("pack frame planes: faces must be 1 (front) or 6, got " + std::to_string(faces));
    const int n = frame.n != 0 ? frame.n : frame.get(Feature::Albedo, Face::Front).width;
    for (Feature f : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct})
        for (int i = 0; i < faces; ++i) detail::check_face_image(frame.get(f, kAllFaces[i]), f, kAllFaces[i], n, "pack frame");
    const bool has_emission = detail::optional_feature_present(frame, Feature::Emission, kAllFaces, faces, n, "pack frame");
    const bool has_env = detail::optional_feature_present(frame, Feature::Env, kAllFaces, faces, n, "pack frame");
    const std::size_t face_plane = std::size_t(n) * n;
    std::vector<float> planes(frame_planes_bytes(n, faces) / sizeof(float), 0.0f);
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature f = Feature(fi);
        if ((f == Feature::Emission && !has_emission) || (f == Feature::Env && !has_env)) continue;
        for (int i = 0; i < faces; ++i) {
            const Image& src = frame.get(f, kAllFaces[i]);
            std::copy(src.data.begin(), src.data.end(),
                      planes.begin() + std::ptrdiff_t((i * kFramePlanes + frame_plane(f)) * face_plane));
        }
    }
    return planes;
}

FrameDesc FrameDesc::of(const Frame& frame, int faces) {
    FrameDesc d;
    d.faces = faces;
    const int n = frame.n != 0 ? frame.n : frame.get(Feature::Albedo, Face::Front).width;
    d.has_emission = detail::optional_feature_present(frame, Feature::Emission, kAllFaces, faces, n, "frame");
    d.has_env = detail::optional_feature_present(frame, Feature::Env, kAllFaces, faces, n, "frame");
    d.look = frame.look;
    d.up = frame.up;
    return d;
}

Frame unpack_frame_planes(const float* planes, int n, const FrameDesc& desc) {
    if (desc.faces != 1 && desc.faces != kFaceCount)
        throw InputError("unpack frame planes: faces must be 1 (front) or 6, got " + std::to_string(desc.faces));
    if (n < 1) throw InputError("unpack frame planes: n must be positive, got " + std::to_string(n));
    if (!planes) throw InputError("unpack frame planes: planes is null");
    Frame frame;
    frame.n = n;
    frame.look = desc.look;
    frame.up = desc.up;
    const std::size_t face_plane = std::size_t(n) * std::size_t(n);
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature f = Feature(fi);
        if ((f == Feature::Emission && !desc.has_emission) || (f == Feature::Env && !desc.has_env)) continue;
        for (int i = 0; i < desc.faces; ++i) {
            Image im(n, n, feature_channels(f));
            const float* src = planes + (std::size_t(i) * kFramePlanes + std::size_t(frame_plane(f))) * face_plane;
            std::copy(src, src + im.data.size(), im.data.begin());
            frame.get(f, kAllFaces[i]) = std::move(im);
        }
    }
    return frame;
}

namespace detail {

std::string preprocess_defines() {
    std::string d = join_defines({define("TRANSFER_REINHARD", int(LuminationTransfer::Reinhard)),
                                  define("TRANSFER_CLAMP", int(LuminationTransfer::Clamp)), frame_plane_defines(),
                                  define("COUNT_SKY", kCountSky), define("COUNT_FAR", kCountFar),
                                  define("COUNT_SLOTS", kCounterSlots), define("PREPROCESS_LOCAL", kPreprocessLocal),
                                  define("MAX_DEPTH_M", kMaxSurfaceDepth)});
    for (int f = 0; f < kFeatureCount; ++f) {
        std::string name = "COUNT_";
        for (const char* c = feature_name(Feature(f)); *c; ++c) name += char(std::toupper(static_cast<unsigned char>(*c)));
        d += ' ';
        d += define(name, f);
    }
    return d;
}

int frame_faces(const ModelConfig& config) {
    if (!config.has_network || config.output_mode == "ssgi_residual")  // the SSGI gather's faces
        return config.ssgi.view == "front" ? 1 : kFaceCount;
    return check_model_input(config) ? kFaceCount : 1;
}

bool check_model_input(const ModelConfig& config) {
    if (!config.has_network)
        throw InputError("network input: family " + config.family + " has no network and no network input; run it "
                         "on frames (SurroundPipeline::run or enqueue)");
    const bool residual = config.output_mode == "ssgi_residual";
    const bool surround = !residual && config.input_nc == int(surround_input_channels().size());
    const auto& names = residual   ? ssgi_residual_input_channels()
                        : surround ? surround_input_channels()
                                   : single_view_input_channels();
    if (residual && config.input_nc != int(names.size()))
        throw InputError("network input: the model corrects SSGI and takes " + std::to_string(config.input_nc) +
                         " input channels; the surround pipeline makes " + std::to_string(names.size()) +
                         " for it (the front view and the SSGI estimate)");
    if (!surround && config.input_nc != int(names.size()))
        throw InputError("network input: the model takes " + std::to_string(config.input_nc) +
                         " input channels; the surround pipeline makes 12 (global view) or 10 (front view only)");
    if (!config.input_layout.empty() && config.input_layout != names) {
        std::size_t i = 0;
        while (i < names.size() && i < config.input_layout.size() && config.input_layout[i] == names[i]) ++i;
        throw InputError("network input: the model's input_layout differs from the pipeline's channel order at "
                         "channel " + std::to_string(i) + ": model '" +
                         (i < config.input_layout.size() ? config.input_layout[i] : std::string("(none)")) +
                         "', pipeline '" + (i < names.size() ? names[i] : std::string("(none)")) + "'");
    }
    const float lo = config.input_range[0], hi = config.input_range[1];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
        throw InputError("network input: the model's input_range [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "] is not a finite increasing range");
    // The features are scaled into [lo, hi] (lo + f x (hi - lo)): an unbounded range -- what an imported (graph)
    // model gets when its file names none -- overflows to Inf and every input to NaN (issue 51).
    if (!std::isfinite(hi - lo)) {
        char range[64];
        std::snprintf(range, sizeof range, "[%g, %g]", double(lo), double(hi));
        throw InputError("network input: the model's input_range " + std::string(range) + " is no range the pipeline can scale its features into (they are mapped from [0, 1] to "
                         "[lo, hi]); a model imported from ONNX has none unless given: the range its network was "
                         "trained on, e.g. python3 -m ngi.convert model.onnx out.safetensors --input-range=-1,1");
    }
    return surround;
}

}  // namespace detail

const detail::Buffer& SurroundPipeline::Impl::enqueue_input(cl_mem raw_planes, int faces, bool has_emission,
                                                            bool has_env, glm::vec3 look, glm::vec3 up,
                                                            const ModelConfig& config, bool surround) {
    const CameraCluster cluster = CameraCluster::from_look_up(look, up);
    const std::size_t face_plane = std::size_t(n) * n, npix = face_plane * faces;
    detail::ensure_buffer(ctx, stack, kFeaturePlanes * npix * sizeof(float), "preprocessed features");
    detail::ensure_buffer(ctx, counters, kCounterSlots * sizeof(int), "preprocessing counters");
    ctx.fill_zero(counters, 0, kCounterSlots * sizeof(int), "preprocessing counters");  // a device command

    const glm::vec3 a = cluster.alpha, b = cluster.beta, g = cluster.gamma;
    preprocess.args(raw_planes, stack, int(face_plane), faces, int(has_emission), int(has_env), a.x, a.y, a.z, b.x,
                    b.y, b.z, g.x, g.y, g.z, config.input_range[0], config.input_range[1], int(transfer), counters);
    static const std::size_t local[2] = {kPreprocessLocal, 1};
    const std::size_t global[2] = {face_plane, std::size_t(faces)};
    ctx.launch(preprocess, 2, global, local);
    if (!surround) return stack;

    const std::size_t plane = std::size_t(4 * n) * 2 * n;
    const std::size_t channels = surround_input_channels().size();
    // The coordinate planes (10, 11) are constant: written once per buffer and input range.
    const bool fresh = detail::ensure_buffer(ctx, view, channels * plane * sizeof(float), "network input");
    const float lo = config.input_range[0], hi = config.input_range[1];
    if (fresh || lo != coords_lo || hi != coords_hi) {
        std::vector<float> scaled(coords.data.size());
        for (std::size_t i = 0; i < scaled.size(); ++i) scaled[i] = lo + coords.data[i] * (hi - lo);
        ctx.write(view, kFeaturePlanes * plane * sizeof(float), scaled.size() * sizeof(float), scaled.data(),
                  "coordinate map");
        coords_lo = lo;
        coords_hi = hi;
    }
    gather_planes(stack.get(), int(npix), merge_idx, merge_w, int(plane), kFeaturePlanes, view.get(), int(plane));
    return view;
}

const detail::Buffer& SurroundPipeline::Impl::enqueue_residual_input(cl_mem raw_planes, int faces, bool has_emission,
                                                                     bool has_env, glm::vec3 look, glm::vec3 up,
                                                                     const ModelConfig& config) {
    const std::size_t face_plane = std::size_t(n) * n;
    if (!ssgi) ssgi = std::make_unique<detail::Ssgi>(ctx);
    detail::ensure_buffer(ctx, ssgi_light, 3 * face_plane * sizeof(float), "ssgi estimate");
    ssgi->enqueue(ctx, raw_planes, faces, n, has_emission, CameraCluster::from_look_up(look, up), config.ssgi,
                  ssgi_light.get());
    // The front view's planes first (face 0 of the raw planes), in a stack with room for the three SSGI planes.
    detail::ensure_buffer(ctx, stack, std::size_t(detail::kSsgiResidualInputs) * face_plane * sizeof(float),
                          "network input");
    enqueue_input(raw_planes, 1, has_emission, has_env, look, up, config, false);
    const int count = int(3 * face_plane);
    encode_ssgi.args(ssgi_light, raw_planes, int(std::size_t(frame_plane(Feature::Direct)) * face_plane), stack,
                     int(kFeaturePlanes * face_plane), count, config.input_range[0], config.input_range[1],
                     int(transfer));
    const std::size_t g[1] = {std::size_t(count)};
    ctx.launch(encode_ssgi, 1, g, detail::kLocal1);
    return stack;
}

void SurroundPipeline::Impl::read_stats(PreprocessStats& stats) {
    int counts[kCounterSlots];
    ctx.read(counters, 0, sizeof counts, counts, "preprocessing counters");
    for (int f = 0; f < kFeatureCount; ++f) stats.nonfinite[f] = counts[f];
    stats.sky_normals = counts[kCountSky];
    stats.far_depths = counts[kCountFar];
}

Tensor SurroundPipeline::network_input(const Frame& frame, const ModelConfig& config, PreprocessStats* stats) {
    Impl& im = *impl_;
    const bool surround = detail::check_model_input(config);
    const bool residual = config.output_mode == "ssgi_residual";
    const int n = im.n;
    if (frame.n != 0 && frame.n != n)
        throw InputError("network input: the frame has N = " + std::to_string(frame.n) + ", this pipeline N = " +
                         std::to_string(n));
    // The faces the input needs, in stacking order (= Face order, which the merge table indexes).
    const int faces = residual ? detail::frame_faces(config) : surround ? kFaceCount : 1;  // Face::Front is first
    for (Feature f : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct})
        for (int i = 0; i < faces; ++i)
            detail::check_face_image(frame.get(f, kAllFaces[i]), f, kAllFaces[i], n, "network input");
    const FrameDesc desc = FrameDesc::of(frame, faces);
    const std::vector<float> planes = pack_frame_planes(frame, faces);  // one upload instead of one per image
    // A grown buffer is a new cl_mem: run()'s handle on the old one must go, or run() would enqueue stale planes.
    if (detail::ensure_buffer(im.ctx, im.raw, planes.size() * sizeof(float), "raw features")) im.raw_handle = {};
    im.ctx.write(im.raw, 0, planes.size() * sizeof(float), planes.data(), "raw features");
    const detail::Buffer& input =
        residual ? im.enqueue_residual_input(im.raw.get(), faces, desc.has_emission, desc.has_env, frame.look,
                                             frame.up, config)
                 : im.enqueue_input(im.raw.get(), faces, desc.has_emission, desc.has_env, frame.look, frame.up,
                                    config, surround);
    Tensor out = surround   ? Tensor({1, int(surround_input_channels().size()), 2 * n, 4 * n})
                 : residual ? Tensor({1, detail::kSsgiResidualInputs, n, n})
                            : Tensor({1, kFeaturePlanes, n, n});
    im.ctx.read(input, 0, out.size() * sizeof(float), out.data.data(), "network input");
    if (stats) im.read_stats(*stats);
    return out;
}

}  // namespace ngi

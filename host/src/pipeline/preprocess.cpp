// The generator's input: raw faces -> preprocess_gbuffer (kernels/gbuffer.cl) -> merge (lut_gather) ->
// NCHW tensor with the coordinate map. Channel order and value rules: docs/CONVENTIONS.md.
#include <cmath>

#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace ngi {

namespace {

constexpr int kRawPlanes = 16;     // albedo 3, normal 3, depth 1, direct 3, emission 3, env 3
constexpr int kFeaturePlanes = 10; // albedo 3, normal 3, depth 1, lumination 3
constexpr int kCounterSlots = 8;   // see kernels/gbuffer.cl
const int kRawFirstPlane[kFeatureCount] = {0, 3, 6, 7, 10, 13};  // per Feature

// Which input the model wants: true = global view (12 channels), false = front view only (10).
bool check_model_input(const ModelConfig& config) {
    const bool surround = config.input_nc == int(surround_input_channels().size());
    const auto& names = surround ? surround_input_channels() : single_view_input_channels();
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
    return surround;
}

}  // namespace

Tensor SurroundPipeline::network_input(const Frame& frame, const ModelConfig& config, PreprocessStats* stats) {
    Impl& im = *impl_;
    const bool surround = check_model_input(config);
    const int n = im.n;
    if (frame.n != 0 && frame.n != n)
        throw InputError("network input: the frame has N = " + std::to_string(frame.n) + ", this pipeline N = " +
                         std::to_string(n));
    const CameraCluster cluster = CameraCluster::from_look_up(frame.look, frame.up);

    // The faces the input needs, in stacking order (= Face order, which the merge table indexes).
    static const Face kAll[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};
    const int faces = surround ? kFaceCount : 1;  // Face::Front is first
    for (Feature f : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct})
        for (int i = 0; i < faces; ++i) detail::check_face_image(frame.get(f, kAll[i]), f, kAll[i], n, "network input");
    const bool has_emission = detail::optional_feature_present(frame, Feature::Emission, kAll, faces, n, "network input");
    const bool has_env = detail::optional_feature_present(frame, Feature::Env, kAll, faces, n, "network input");

    // Raw planes [face][16][row][col]: each face image is uploaded as it is, without repacking on the host.
    // Planes of absent optional features stay unwritten (the kernel does not read them).
    const std::size_t face_plane = std::size_t(n) * n, npix = face_plane * faces;
    detail::ensure_buffer(im.ctx, im.raw, kRawPlanes * npix * sizeof(float), "raw features");
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature f = Feature(fi);
        if ((f == Feature::Emission && !has_emission) || (f == Feature::Env && !has_env)) continue;
        for (int i = 0; i < faces; ++i) {
            const Image& src = frame.get(f, kAll[i]);
            im.ctx.write(im.raw, (i * kRawPlanes + kRawFirstPlane[fi]) * face_plane * sizeof(float),
                         src.data.size() * sizeof(float), src.data.data(), "raw features");
        }
    }
    detail::ensure_buffer(im.ctx, im.stack, kFeaturePlanes * npix * sizeof(float), "preprocessed features");
    detail::ensure_buffer(im.ctx, im.counters, kCounterSlots * sizeof(int), "preprocessing counters");
    const int zeros[kCounterSlots] = {};
    im.ctx.write(im.counters, 0, sizeof zeros, zeros, "preprocessing counters");

    const glm::vec3 a = cluster.alpha, b = cluster.beta, g = cluster.gamma;
    im.preprocess.args(im.raw, im.stack, int(face_plane), faces, int(has_emission), int(has_env), a.x, a.y, a.z, b.x,
                       b.y, b.z, g.x, g.y, g.z, config.input_range[0], config.input_range[1], int(im.transfer),
                       im.counters);
    static const std::size_t local[2] = {64, 1};
    const std::size_t global[2] = {face_plane, std::size_t(faces)};
    im.ctx.launch(im.preprocess, 2, global, local);

    Tensor out;
    if (surround) {
        const int w = 4 * n, h = 2 * n;
        const std::size_t plane = std::size_t(w) * h;
        out = Tensor({1, int(surround_input_channels().size()), h, w});
        // The coordinate planes (10, 11) are constant: written once per buffer and input range.
        const bool fresh = detail::ensure_buffer(im.ctx, im.view, out.size() * sizeof(float), "network input");
        const float lo = config.input_range[0], hi = config.input_range[1];
        if (fresh || lo != im.coords_lo || hi != im.coords_hi) {
            std::vector<float> coords(im.coords.data.size());
            for (std::size_t i = 0; i < coords.size(); ++i) coords[i] = lo + im.coords.data[i] * (hi - lo);
            im.ctx.write(im.view, kFeaturePlanes * plane * sizeof(float), coords.size() * sizeof(float), coords.data(),
                         "coordinate map");
            im.coords_lo = lo;
            im.coords_hi = hi;
        }
        im.gather_planes(im.stack, int(npix), im.merge_idx, im.merge_w, int(plane), kFeaturePlanes, im.view,
                         int(plane));
        im.ctx.read(im.view, 0, out.size() * sizeof(float), out.data.data(), "network input");
    } else {
        out = Tensor({1, kFeaturePlanes, n, n});
        im.ctx.read(im.stack, 0, out.size() * sizeof(float), out.data.data(), "network input");
    }

    int counts[kCounterSlots];
    im.ctx.read(im.counters, 0, sizeof counts, counts, "preprocessing counters");
    if (stats) {
        for (int f = 0; f < kFeatureCount; ++f) stats->nonfinite[f] = counts[f];
        stats->sky_normals = counts[6];
        stats->far_depths = counts[7];
    }
    return out;
}

}  // namespace ngi

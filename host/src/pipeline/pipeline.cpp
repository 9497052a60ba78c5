// SurroundPipeline: construction, shared checks and names. The stages live in global_view.cpp (direction
// mapping, lookup tables, merge), preprocess.cpp (network input) and compose.cpp (output side).
#include <cmath>

#include "ngi/error.hpp"
#include "models/ssgi_config.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace ngi {

namespace {

std::string size_string(const Image& im) { return std::to_string(im.width) + "x" + std::to_string(im.height); }

}  // namespace

const char* global_view_mode_name(GlobalViewMode m) { return m == GlobalViewMode::Thesis ? "thesis" : "equirect"; }

GlobalViewMode global_view_mode_from_name(const std::string& name) {
    if (name == "thesis") return GlobalViewMode::Thesis;
    if (name == "equirect") return GlobalViewMode::Equirect;
    throw InputError("unknown global view mode '" + name + "' (thesis, equirect)");
}

const char* lumination_transfer_name(LuminationTransfer t) {
    return t == LuminationTransfer::Reinhard ? "reinhard" : "clamp";
}

LuminationTransfer lumination_transfer_from_name(const std::string& name) {
    if (name == "reinhard") return LuminationTransfer::Reinhard;
    if (name == "clamp") return LuminationTransfer::Clamp;
    throw InputError("unknown lumination transfer '" + name + "' (reinhard, clamp)");
}

const char* tone_curve_name(ToneCurve c) {
    switch (c) {
        case ToneCurve::AcesFitted: return "aces";
        case ToneCurve::Reinhard: return "reinhard";
        case ToneCurve::Clamp: return "clamp";
    }
    throw Error("tone_curve_name: bad curve");
}

ToneCurve tone_curve_from_name(const std::string& name) {
    for (ToneCurve c : {ToneCurve::AcesFitted, ToneCurve::Reinhard, ToneCurve::Clamp})
        if (name == tone_curve_name(c)) return c;
    throw InputError("unknown tone curve '" + name + "' (aces, reinhard, clamp)");
}

const std::vector<std::string>& single_view_input_channels() {
    static const std::vector<std::string> names = {"albedo.r", "albedo.g", "albedo.b", "normal.x",
                                                   "normal.y", "normal.z", "depth", "lumination.r",
                                                   "lumination.g", "lumination.b"};
    return names;
}

const std::vector<std::string>& ssgi_residual_input_channels() {
    static const std::vector<std::string> names = [] {
        auto v = single_view_input_channels();
        for (const char* c : {"ssgi.r", "ssgi.g", "ssgi.b"}) v.push_back(c);
        return v;
    }();
    return names;
}

const std::vector<std::string>& surround_input_channels() {
    static const std::vector<std::string> names = [] {
        auto v = single_view_input_channels();
        v.push_back("coord.phi");
        v.push_back("coord.theta");
        return v;
    }();
    return names;
}

int PreprocessStats::total_nonfinite() const {
    int t = 0;
    for (int c : nonfinite) t += c;
    return t;
}

namespace detail {

void check_face_image(const Image& im, Feature feature, Face face, int n, const char* what) {
    const std::string where = std::string(what) + ": feature '" + feature_name(feature) + "' of face '" +
                              face_name(face) + "'";
    if (im.width == 0 && im.height == 0) throw InputError(where + " is missing");
    if (im.width != im.height) throw InputError(where + " is " + size_string(im) + "; faces must be square");
    if (im.width != n)
        throw InputError(where + " is " + size_string(im) + ", but this pipeline merges " + std::to_string(n) + "x" +
                         std::to_string(n) + " faces (all faces must have the same size)");
    if (im.channels != feature_channels(feature))
        throw InputError(where + " has " + std::to_string(im.channels) + " channels, expected " +
                         std::to_string(feature_channels(feature)));
    if (im.data.size() != im.plane() * std::size_t(im.channels))
        throw InputError(where + " holds " + std::to_string(im.data.size()) + " values, expected " +
                         std::to_string(im.plane() * std::size_t(im.channels)));
}

bool optional_feature_present(const Frame& frame, Feature feature, const Face* faces, int face_count, int n,
                              const char* what) {
    int present = 0;
    for (int i = 0; i < face_count; ++i) {
        const Image& im = frame.get(feature, faces[i]);
        if (im.width != 0 || im.height != 0) ++present;
    }
    if (present == 0) return false;
    for (int i = 0; i < face_count; ++i) {
        const Image& im = frame.get(feature, faces[i]);
        if (im.width == 0 && im.height == 0)
            throw InputError(std::string(what) + ": feature '" + feature_name(feature) + "' is present on some faces "
                             "but missing on face '" + face_name(faces[i]) + "' (give it for all faces or none)");
        check_face_image(im, feature, faces[i], n, what);
    }
    return true;
}

bool indirect_output(const ModelConfig& config, const char* what) {
    if (config.output_mode == "lightmap") return false;
    if (config.output_mode == "indirect" || config.output_mode == "ssgi_residual") return true;
    throw InputError(std::string(what) + ": the model's output_mode is \"" + config.output_mode.substr(0, 80) +
                     "\"; expected \"lightmap\", \"indirect\" or \"ssgi_residual\"");
}

}  // namespace detail

SurroundPipeline::Impl::Impl(const Device& d, int n_, GlobalViewMode mode_, LuminationTransfer transfer_)
    : device(d), ctx(ngi::detail::context_of(d)), n(n_), mode(mode_), transfer(transfer_),
      gather(ctx.kernel("globalview", "lut_gather")),
      preprocess(ctx.kernel("gbuffer", "preprocess_gbuffer", detail::preprocess_defines())),
      decode(ctx.kernel("compose", "decode_lightmap", detail::compose_defines())),
      decode_indirect(ctx.kernel("compose", "decode_indirect", detail::compose_defines())),
      encode(ctx.kernel("compose", "encode_lightmap", detail::compose_defines())),
      resize(ctx.kernel("compose", "resize_bilinear", detail::compose_defines())),
      compose(ctx.kernel("compose", "compose_final", detail::compose_defines())),
      tonemap(ctx.kernel("compose", "tonemap", detail::compose_defines())),
      encode_ssgi(ctx.kernel("compose", "encode_ssgi_input", detail::compose_defines())),
      decode_residual(ctx.kernel("compose", "decode_ssgi_residual", detail::compose_defines())) {
    if (ssgi_residual_input_channels().size() != std::size_t(detail::kSsgiResidualInputs))
        throw Error("surround pipeline: ssgi_residual_input_channels() and kSsgiResidualInputs disagree");
}

void SurroundPipeline::Impl::gather_planes(cl_mem src, int src_plane, const detail::Buffer& idx,
                                           const detail::Buffer& w, int npix, int channels, cl_mem dst,
                                           int dst_plane) {
    static const std::size_t local[1] = {64};
    gather.args(src, src_plane, idx, w, npix, channels, dst, dst_plane);
    const std::size_t global[1] = {std::size_t(npix)};
    ctx.launch(gather, 1, global, local);
}

SurroundPipeline::SurroundPipeline(SurroundPipeline&&) noexcept = default;
SurroundPipeline& SurroundPipeline::operator=(SurroundPipeline&&) noexcept = default;
SurroundPipeline::~SurroundPipeline() = default;

int SurroundPipeline::n() const { return impl_->n; }
GlobalViewMode SurroundPipeline::mode() const { return impl_->mode; }
LuminationTransfer SurroundPipeline::transfer() const { return impl_->transfer; }
const Image& SurroundPipeline::coord_map() const { return impl_->coords; }

}  // namespace ngi

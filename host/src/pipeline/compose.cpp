// Output side: model output -> front lightmap (extract + decode), final composition, resize and tone map
// (kernels/compose.cl). Value rules: docs/CONVENTIONS.md.
#include <climits>
#include <cmath>

#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi {

std::string detail::tonemap_defines() {
    return join_defines({define("CURVE_ACES", int(ToneCurve::AcesFitted)), define("CURVE_REINHARD", int(ToneCurve::Reinhard)),
                         define("CURVE_CLAMP", int(ToneCurve::Clamp)), define("TONEMAP_VEC", kTonemapVec)});
}

std::string detail::compose_defines() {
    return join_defines({define("TRANSFER_REINHARD", int(LuminationTransfer::Reinhard)),
                         define("TRANSFER_CLAMP", int(LuminationTransfer::Clamp)), define("LIGHT_MAX", kLightMax),
                         tonemap_defines()});
}

namespace {


// A usable image: non-empty, values matching its size, small enough for the kernels' int indexing.
void check_image(const Image& im, const char* what) {
    if (im.width <= 0 || im.height <= 0 || im.channels <= 0)
        throw InputError(std::string(what) + ": the image is empty (" + std::to_string(im.width) + "x" +
                         std::to_string(im.height) + "x" + std::to_string(im.channels) + ")");
    if (im.data.size() != im.plane() * std::size_t(im.channels))
        throw InputError(std::string(what) + ": the image holds " + std::to_string(im.data.size()) +
                         " values, expected " + std::to_string(im.plane() * std::size_t(im.channels)));
    if (im.data.size() > std::size_t(INT_MAX))
        throw InputError(std::string(what) + ": the image is too large (" + std::to_string(im.data.size()) + " values)");
}

void upload_image(detail::Context& ctx, detail::Buffer& b, const Image& im, const char* what) {
    detail::ensure_buffer(ctx, b, im.data.size() * sizeof(float), what);
    ctx.write(b, 0, im.data.size() * sizeof(float), im.data.data(), what);
}

// The shared body of both front_lightmap overloads: extraction, then the decode; with `direct` (the front face's
// direct light, N x N x 3, checked) the decoded indirect light is added to it (decode_indirect).
Image decode_front(SurroundPipeline::Impl& im, const Tensor& y, const ModelConfig& config, const Image* direct) {
    const int n = im.n;
    const auto& s = y.shape;
    const bool global = s.size() == 4 && s[2] == 2 * n && s[3] == 4 * n;
    const bool front = s.size() == 4 && s[2] == n && s[3] == n;
    if (s.size() != 4 || s[0] != 1 || s[1] != 3 || !(global || front))
        throw InputError("front lightmap: the model output is " + shape_string(s) + ", expected [1, 3, " +
                         std::to_string(2 * n) + ", " + std::to_string(4 * n) + "] (global view) or [1, 3, " +
                         std::to_string(n) + ", " + std::to_string(n) + "] (front view)");
    if (y.data.size() != Tensor::element_count(s))
        throw InputError("front lightmap: the model output holds " + std::to_string(y.data.size()) +
                         " values for shape " + shape_string(s));
    const float lo = config.output_range[0], hi = config.output_range[1];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
        throw InputError("front lightmap: the model's output_range [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "] is not a finite increasing range");

    Image out(n, n, 3);
    const std::size_t bytes = out.data.size() * sizeof(float);
    detail::ensure_buffer(im.ctx, im.light, bytes, "front lightmap");
    if (global) {
        const std::size_t plane = std::size_t(4 * n) * 2 * n;
        detail::ensure_buffer(im.ctx, im.out, y.data.size() * sizeof(float), "model output");
        im.ctx.write(im.out, 0, y.data.size() * sizeof(float), y.data.data(), "model output");
        im.gather_planes(im.out.get(), int(plane), im.extract_idx, im.extract_w, int(out.plane()), 3, im.light.get(),
                         int(out.plane()));
    } else {
        im.ctx.write(im.light, 0, bytes, y.data.data(), "model output");
    }
    // Decoding after the extraction: in Thesis mode the crop is exact either way; in Equirect mode the
    // resampling then interpolates in the model's (perceptually more even) encoded domain.
    const int count = int(out.data.size());
    const std::size_t g[1] = {std::size_t(count)};
    if (direct) {
        upload_image(im.ctx, im.aux[0], *direct, "front direct light");
        im.decode_indirect.args(im.light, count, lo, hi, int(im.transfer), im.aux[0], 0);
        im.ctx.launch(im.decode_indirect, 1, g, detail::kLocal1);
    } else {
        im.decode.args(im.light, count, lo, hi, int(im.transfer));
        im.ctx.launch(im.decode, 1, g, detail::kLocal1);
    }
    im.ctx.read(im.light, 0, bytes, out.data.data(), "front lightmap");
    return out;
}

}  // namespace

namespace {

// The step-by-step decode has the network's output only; a correction of SSGI also needs the SSGI estimate the
// network saw, which run / enqueue keep on the device.
void refuse_ssgi_residual(const ModelConfig& config) {
    if (config.output_mode == "ssgi_residual")
        throw InputError("front lightmap: the model's output_mode is \"ssgi_residual\" (it corrects the SSGI rung's "
                         "light, which its output alone does not hold); run it on frames (SurroundPipeline::run or "
                         "enqueue)");
}

}  // namespace

Image SurroundPipeline::front_lightmap(const Tensor& y, const ModelConfig& config) {
    refuse_ssgi_residual(config);
    if (detail::indirect_output(config, "front lightmap"))
        throw InputError("front lightmap: the model's output_mode is \"indirect\" (it predicts indirect light "
                         "only): an indirect-mode model needs the frame's front direct light; call "
                         "front_lightmap(output, config, frame)");
    return decode_front(*impl_, y, config, nullptr);
}

Image SurroundPipeline::front_lightmap(const Tensor& y, const ModelConfig& config, const Frame& frame) {
    refuse_ssgi_residual(config);
    if (!detail::indirect_output(config, "front lightmap")) return decode_front(*impl_, y, config, nullptr);
    const Image& direct = frame.get(Feature::Direct, Face::Front);
    detail::check_face_image(direct, Feature::Direct, Face::Front, impl_->n,
                             "front lightmap (an indirect-mode model adds the front direct light)");
    return decode_front(*impl_, y, config, &direct);
}

Tensor SurroundPipeline::encode_lightmap(const Image& lightmap, const ModelConfig& config) {
    Impl& im = *impl_;
    check_image(lightmap, "encode lightmap");
    if (lightmap.channels != 3)
        throw InputError("encode lightmap: the lightmap has " + std::to_string(lightmap.channels) +
                         " channels, expected 3");
    const float lo = config.output_range[0], hi = config.output_range[1];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
        throw InputError("encode lightmap: the model's output_range [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "] is not a finite increasing range");
    upload_image(im.ctx, im.aux[0], lightmap, "encode lightmap");
    Tensor out({1, 3, lightmap.height, lightmap.width});
    const std::size_t bytes = out.data.size() * sizeof(float);
    detail::ensure_buffer(im.ctx, im.out, bytes, "encoded lightmap");
    const int count = int(out.data.size());
    im.encode.args(im.aux[0], im.out, count, lo, hi, int(im.transfer));
    const std::size_t g[1] = {std::size_t(count)};
    im.ctx.launch(im.encode, 1, g, detail::kLocal1);
    im.ctx.read(im.out, 0, bytes, out.data.data(), "encoded lightmap");
    return out;
}

Image SurroundPipeline::compose(const Image& lightmap, const Frame& frame) {
    Impl& im = *impl_;
    const int n = im.n;
    check_image(lightmap, "compose");
    if (lightmap.width != n || lightmap.height != n || lightmap.channels != 3)
        throw InputError("compose: the lightmap is " + std::to_string(lightmap.width) + "x" +
                         std::to_string(lightmap.height) + "x" + std::to_string(lightmap.channels) +
                         ", expected the front view's " + std::to_string(n) + "x" + std::to_string(n) + "x3");
    detail::check_face_image(frame.get(Feature::Albedo, Face::Front), Feature::Albedo, Face::Front, n, "compose");
    const Face front[1] = {Face::Front};
    const bool has_emission = detail::optional_feature_present(frame, Feature::Emission, front, 1, n, "compose");
    const bool has_env = detail::optional_feature_present(frame, Feature::Env, front, 1, n, "compose");

    upload_image(im.ctx, im.light, lightmap, "compose lightmap");
    upload_image(im.ctx, im.aux[0], frame.get(Feature::Albedo, Face::Front), "compose albedo");
    // Absent terms are switched off in the kernel; the albedo buffer stands in for their argument.
    if (has_emission) upload_image(im.ctx, im.aux[1], frame.get(Feature::Emission, Face::Front), "compose emission");
    if (has_env) upload_image(im.ctx, im.aux[2], frame.get(Feature::Env, Face::Front), "compose env");
    Image out(n, n, 3);
    const std::size_t bytes = out.data.size() * sizeof(float);
    detail::ensure_buffer(im.ctx, im.out, bytes, "final image");
    const int count = int(out.data.size());
    im.compose.args(im.light, im.aux[0], has_emission ? im.aux[1] : im.aux[0], has_env ? im.aux[2] : im.aux[0],
                    int(has_emission), int(has_env), im.out, count);
    const std::size_t g[1] = {std::size_t(count)};
    im.ctx.launch(im.compose, 1, g, detail::kLocal1);
    im.ctx.read(im.out, 0, bytes, out.data.data(), "final image");
    return out;
}

Image SurroundPipeline::upscale(const Image& image, int width, int height) {
    Impl& im = *impl_;
    check_image(image, "upscale");
    if (width <= 0 || height <= 0 || double(width) * height * image.channels > double(INT_MAX))
        throw InputError("upscale: target size " + std::to_string(width) + "x" + std::to_string(height) +
                         " is empty or too large");
    // The device buffer first: its size is checked against the device's limit (OutOfMemoryError naming it) before
    // the host allocates the same amount (`lightmap --size 16384x16384` once reached 3.2 GB of host memory first).
    const std::size_t bytes = std::size_t(width) * std::size_t(height) * std::size_t(image.channels) * sizeof(float);
    detail::ensure_buffer(im.ctx, im.out, bytes, "upscale output");
    upload_image(im.ctx, im.aux[0], image, "upscale input");
    Image out(width, height, image.channels);
    im.resize.args(im.aux[0], image.width, image.height, im.out, width, height, image.channels);
    const std::size_t g[2] = {std::size_t(width), std::size_t(height)};
    im.ctx.launch(im.resize, 2, g, detail::kLocal2);
    im.ctx.read(im.out, 0, bytes, out.data.data(), "upscale output");
    return out;
}

Image SurroundPipeline::tonemap(const Image& linear, const ToneMapOptions& options) {
    Impl& im = *impl_;
    check_image(linear, "tone map");
    if (!std::isfinite(options.exposure_ev) || std::abs(options.exposure_ev) > 64.0f)
        throw InputError("tone map: exposure " + std::to_string(options.exposure_ev) + " EV is not in [-64, 64]");
    upload_image(im.ctx, im.aux[0], linear, "tone map input");
    Image out(linear.width, linear.height, linear.channels);
    const std::size_t bytes = out.data.size() * sizeof(float);
    detail::ensure_buffer(im.ctx, im.out, bytes, "tone map output");
    const int count = int(out.data.size());
    im.tonemap.args(im.aux[0], im.out, count, std::exp2(options.exposure_ev), int(options.curve), int(options.srgb));
    const std::size_t g[1] = {detail::tonemap_items(count)};
    im.ctx.launch(im.tonemap, 1, g, detail::kLocal1);
    im.ctx.read(im.out, 0, bytes, out.data.data(), "tone map output");
    return out;
}

}  // namespace ngi

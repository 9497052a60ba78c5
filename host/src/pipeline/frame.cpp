// One frame in one call: SurroundPipeline::enqueue (device in, device out) and run (host in, host out, built on
// enqueue with one upload and one download). The stages are those of the step-by-step calls (preprocess.cpp,
// compose.cpp); here they stay on the device from the raw planes to the outputs.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "models/model_access.hpp"
#include "models/ssgi_config.hpp"
#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace ngi {

namespace {

using Clock = std::chrono::steady_clock;

void check_frame_buffer(const DeviceBuffer& b, const Device& device, std::size_t need, bool write, const char* what) {
    const std::string where = std::string("enqueue frame: the ") + what + " buffer";
    if (!b) throw InputError(where + " is empty");
    if (detail::shared_context_of(b.device()) != detail::shared_context_of(device))
        throw InputError(where + " belongs to another device than the pipeline");
    if (b.bytes() < need)
        throw InputError(where + " holds " + std::to_string(b.bytes()) + " bytes, the frame needs " +
                         std::to_string(need));
    if (write && !b.writable()) throw InputError(where + " was created CL_MEM_READ_ONLY");
}

void check_tonemap(const ToneMapOptions& t) {
    if (!std::isfinite(t.exposure_ev) || std::abs(t.exposure_ev) > 64.0f)
        throw InputError("tone map: exposure " + std::to_string(t.exposure_ev) + " EV is not in [-64, 64]");
}

}  // namespace

void SurroundPipeline::Impl::check_frame_buffers(const DeviceBuffer& planes, int faces_used,
                                                 const FrameOutputs& outputs) {
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    check_frame_buffer(planes, device, frame_planes_bytes(n, faces_used), false, "planes");
    const DeviceBuffer* outs[3] = {&outputs.lightmap, &outputs.final_image, &outputs.display};
    const char* names[3] = {"lightmap", "final image", "display"};
    for (int i = 0; i < 3; ++i)
        if (*outs[i]) check_frame_buffer(*outs[i], device, out_bytes, true, names[i]);
    if (outputs.display) check_tonemap(outputs.tonemap);
}

// Family "ssgi": no network. The gather writes the lightmap (direct + its indirect light), then compose and tone map
// as for a network. The preprocessing runs only when the counters are asked for (`stats`): it is the same sanitizing
// report a network's input gives, and the gather needs nothing else from it.
void SurroundPipeline::Impl::enqueue_ssgi(const ModelConfig& config, const DeviceBuffer& planes, const FrameDesc& desc,
                                          const FrameOutputs& outputs, PreprocessStats* stats, FrameTimings* timings) {
    const int faces_used = detail::frame_faces(config);
    if (desc.faces < faces_used)
        throw InputError("enqueue frame: the ssgi rung (view \"" + config.ssgi.view + "\") gathers from all 6 faces, "
                         "the frame holds " + std::to_string(desc.faces));
    check_frame_buffers(planes, faces_used, outputs);
    if (!ssgi) ssgi = std::make_unique<detail::Ssgi>(ctx);
    detail::StageClock lap(ctx, timings);
    if (stats)
        enqueue_input(planes.opencl_mem(), faces_used, desc.has_emission, desc.has_env, desc.look, desc.up, config,
                      false);
    lap(&FrameTimings::input_ms);
    cl_mem light_dst = outputs.lightmap.opencl_mem();
    if (!light_dst) {
        detail::ensure_buffer(ctx, frame_light, 3 * std::size_t(n) * n * sizeof(float), "frame lightmap");
        light_dst = frame_light.get();
    }
    ssgi->enqueue(ctx, planes.opencl_mem(), faces_used, n, desc.has_emission,
                  CameraCluster::from_look_up(desc.look, desc.up), config.ssgi, light_dst);
    lap(&FrameTimings::network_ms);
    enqueue_final(light_dst, planes.opencl_mem(), desc.has_emission, desc.has_env, outputs.final_image.opencl_mem(),
                  outputs.display.opencl_mem(), outputs.tonemap);
    lap(&FrameTimings::outputs_ms);
    if (stats) read_stats(*stats);
}

void SurroundPipeline::Impl::enqueue_outputs(cl_mem model_out, bool global, const ModelConfig& config, cl_mem planes,
                                             bool has_emission, bool has_env, cl_mem light_dst, cl_mem final_dst,
                                             cl_mem display_dst, const ToneMapOptions& tm, cl_mem residual_input) {
    const std::size_t face_plane = std::size_t(n) * n, bytes = 3 * face_plane * sizeof(float);
    const int count = int(3 * face_plane);
    const std::size_t g[1] = {std::size_t(count)};
    // The lightmap: extracted from the global view (or the front view as it is), then decoded in place.
    if (!light_dst) {
        detail::ensure_buffer(ctx, frame_light, bytes, "frame lightmap");
        light_dst = frame_light.get();
    }
    if (global)
        gather_planes(model_out, int(8 * face_plane), extract_idx, extract_w, int(face_plane), 3, light_dst,
                      int(face_plane));
    else
        ctx.copy(model_out, 0, light_dst, 0, bytes, "front lightmap");
    const int direct_off = int(std::size_t(frame_plane(Feature::Direct)) * face_plane);
    if (config.output_mode == "ssgi_residual") {
        // The correction plus the SSGI estimate the network saw (its input planes 10-12), decoded, plus direct light.
        if (!residual_input) throw Error("enqueue frame: an ssgi_residual model's output needs its input");
        decode_residual.args(light_dst, count, config.output_range[0], config.output_range[1], int(transfer),
                             residual_input, int((detail::kSsgiResidualInputs - 3) * face_plane), planes, direct_off);
        ctx.launch(decode_residual, 1, g, detail::kLocal1);
    } else if (detail::indirect_output(config, "enqueue frame")) {
        // The decoded indirect light plus the front face's direct light, read in place from the planes (planes
        // 7-9 of face 0: contiguous RGB, the lightmap's own layout), so the frame stays on the device.
        decode_indirect.args(light_dst, count, config.output_range[0], config.output_range[1], int(transfer), planes,
                             direct_off);
        ctx.launch(decode_indirect, 1, g, detail::kLocal1);
    } else {
        decode.args(light_dst, count, config.output_range[0], config.output_range[1], int(transfer));
        ctx.launch(decode, 1, g, detail::kLocal1);
    }
    enqueue_final(light_dst, planes, has_emission, has_env, final_dst, display_dst, tm);
}

void SurroundPipeline::Impl::enqueue_final(cl_mem light_dst, cl_mem planes, bool has_emission, bool has_env,
                                           cl_mem final_dst, cl_mem display_dst, const ToneMapOptions& tm) {
    if (!final_dst && !display_dst) return;
    const std::size_t face_plane = std::size_t(n) * n, bytes = 3 * face_plane * sizeof(float);
    const int count = int(3 * face_plane);
    const std::size_t g[1] = {std::size_t(count)};

    // The front face's albedo, emission and env planes (contiguous RGB triples of face 0) for compose_final.
    auto front_planes = [&](Feature f, detail::Buffer& dst, const char* what) {
        detail::ensure_buffer(ctx, dst, bytes, what);
        ctx.copy(planes, std::size_t(frame_plane(f)) * face_plane * sizeof(float), dst.get(), 0, bytes, what);
    };
    front_planes(Feature::Albedo, aux[0], "front albedo");
    if (has_emission) front_planes(Feature::Emission, aux[1], "front emission");
    if (has_env) front_planes(Feature::Env, aux[2], "front env");
    if (!final_dst) {
        detail::ensure_buffer(ctx, frame_final, bytes, "frame final image");
        final_dst = frame_final.get();
    }
    compose.args(light_dst, aux[0], has_emission ? aux[1] : aux[0], has_env ? aux[2] : aux[0], int(has_emission),
                 int(has_env), final_dst, count);
    ctx.launch(compose, 1, g, detail::kLocal1);
    if (!display_dst) return;
    tonemap.args(final_dst, display_dst, count, std::exp2(tm.exposure_ev), int(tm.curve), int(tm.srgb));
    const std::size_t gt[1] = {detail::tonemap_items(count)};
    ctx.launch(tonemap, 1, gt, detail::kLocal1);
}

void SurroundPipeline::enqueue(Model& model, const DeviceBuffer& planes, const FrameDesc& desc,
                               const FrameOutputs& outputs, PreprocessStats* stats, FrameTimings* timings) {
    Impl& im = *impl_;
    const ModelConfig& config = model.config();
    if (detail::shared_context_of(detail::ModelAccess::device(model)) != detail::shared_context_of(im.device))
        throw InputError("enqueue frame: the model was loaded on another device than the pipeline's");
    if (desc.faces != 1 && desc.faces != kFaceCount)
        throw InputError("enqueue frame: faces must be 1 (front only) or 6, got " + std::to_string(desc.faces));
    if (!config.has_network) {  // an SSGI rung: the gather of its `ssgi` settings instead of a network
        im.enqueue_ssgi(config, planes, desc, outputs, stats, timings);
        return;
    }
    const bool surround = detail::check_model_input(config);
    const bool residual = config.output_mode == "ssgi_residual";
    if (residual && desc.faces < detail::frame_faces(config))
        throw InputError("enqueue frame: the model corrects the SSGI rung (view \"" + config.ssgi.view +
                         "\"), which gathers from all 6 faces; the frame holds " + std::to_string(desc.faces));
    if (surround && desc.faces != kFaceCount)
        throw InputError("enqueue frame: the model is surround-aware (12 input channels) and needs all 6 faces, "
                         "the frame holds " + std::to_string(desc.faces));
    const float lo = config.output_range[0], hi = config.output_range[1];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
        throw InputError("enqueue frame: the model's output_range [" + std::to_string(lo) + ", " + std::to_string(hi) +
                         "] is not a finite increasing range");
    if (config.output_nc != 3)
        throw InputError("enqueue frame: the model outputs " + std::to_string(config.output_nc) +
                         " channels; a lightmap needs 3");
    detail::indirect_output(config, "enqueue frame");  // an unknown output_mode fails before anything is enqueued
    // The generator's size: the global view (2N x 4N) or the front face; it must be divisible by 2^num_downs.
    const int h = surround ? 2 * im.n : im.n, w = surround ? 4 * im.n : im.n;
    const int step = 1 << config.unet.num_downs;
    if (h % step || w % step)
        throw InputError("enqueue frame: the model needs sizes divisible by 2^num_downs = " + std::to_string(step) +
                         "; this pipeline's network input is " + std::to_string(h) + "x" + std::to_string(w) +
                         " (N = " + std::to_string(im.n) + ")");
    // Only the faces the model reads must be present, but they must all be there.
    const int faces_used = residual ? detail::frame_faces(config) : surround ? kFaceCount : 1;
    im.check_frame_buffers(planes, faces_used, outputs);
    detail::StageClock lap(im.ctx, timings);
    const detail::Buffer& input =
        residual ? im.enqueue_residual_input(planes.opencl_mem(), faces_used, desc.has_emission, desc.has_env,
                                             desc.look, desc.up, config)
                 : im.enqueue_input(planes.opencl_mem(), faces_used, desc.has_emission, desc.has_env, desc.look,
                                    desc.up, config, surround);
    lap(&FrameTimings::input_ms);
    detail::ensure_buffer(im.ctx, im.frame_out, std::size_t(3) * h * w * sizeof(float), "model output");
    detail::ModelAccess::enqueue(model, input.get(), 0, im.frame_out.get(), 0, h, w);
    lap(&FrameTimings::network_ms);
    im.enqueue_outputs(im.frame_out.get(), surround, config, planes.opencl_mem(), desc.has_emission, desc.has_env,
                       outputs.lightmap.opencl_mem(), outputs.final_image.opencl_mem(), outputs.display.opencl_mem(),
                       outputs.tonemap, residual ? input.get() : nullptr);
    lap(&FrameTimings::outputs_ms);
    if (stats) im.read_stats(*stats);
}

FrameImages SurroundPipeline::run(Model& model, const Frame& frame, bool lightmap, bool final_image, bool display,
                                  const ToneMapOptions& tonemap, PreprocessStats* stats, FrameTimings* timings) {
    const int faces = detail::frame_faces(model.config());
    if (frame.n != 0 && frame.n != impl_->n)
        throw InputError("run frame: the frame has N = " + std::to_string(frame.n) + ", this pipeline N = " +
                         std::to_string(impl_->n));
    const std::vector<float> planes = pack_frame_planes(frame, faces);  // checks every image it packs
    return run(model, planes.data(), planes.size() * sizeof(float), FrameDesc::of(frame, faces), lightmap,
               final_image, display, tonemap, stats, timings);
}

FrameImages SurroundPipeline::run(Model& model, const float* planes, std::size_t planes_bytes, const FrameDesc& desc,
                                  bool lightmap, bool final_image, bool display, const ToneMapOptions& tonemap,
                                  PreprocessStats* stats, FrameTimings* timings) {
    Impl& im = *impl_;
    if (!planes) throw InputError("run frame: the planes pointer is NULL");
    if (desc.faces != 1 && desc.faces != kFaceCount)
        throw InputError("run frame: faces must be 1 (front only) or 6, got " + std::to_string(desc.faces));
    const std::size_t need = frame_planes_bytes(im.n, desc.faces);
    if (planes_bytes < need)
        throw InputError("run frame: the planes hold " + std::to_string(planes_bytes) + " bytes, " +
                         std::to_string(desc.faces) + " faces of N = " + std::to_string(im.n) + " need " +
                         std::to_string(need));
    if (display) check_tonemap(tonemap);
    // Negative depth (-Inf included, NaN not) is refused, as a frame folder refuses it (io/frame_io.cpp).
    const std::size_t plane = std::size_t(im.n) * im.n;
    for (int f = 0; f < desc.faces; ++f) {
        const float* depth = planes + (std::size_t(f) * kFramePlanes + frame_plane(Feature::Depth)) * plane;
        const long k = long(std::count_if(depth, depth + plane, [](float v) { return v < 0.0f; }));
        if (k)
            throw InputError("run frame: " + std::to_string(k) + " of " + std::to_string(plane) + " depth values of "
                             "face '" + face_name(Face(f)) + "' are negative (depth is a distance)");
    }

    // The raw planes live in a pipeline-owned buffer, handed to enqueue() as a DeviceBuffer; their upload is the
    // frame's "gather" stage.
    const auto t0 = Clock::now();
    if (detail::ensure_buffer(im.ctx, im.raw, need, "frame planes") || !im.raw_handle)
        im.raw_handle = DeviceBuffer::wrap(im.device, im.raw.get(), 0, im.raw.bytes());
    im.ctx.write(im.raw, 0, need, planes, "frame planes");
    if (timings) timings->gather_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    const FrameOutputs outs = im.scratch_outputs(lightmap, final_image, display, tonemap);
    // Checks the model against the frame; with `stats` it downloads the counters too (an ssgi rung preprocesses only
    // then).
    enqueue(model, im.raw_handle, desc, outs, stats, timings);
    return im.download_outputs(outs, timings);
}

FrameOutputs SurroundPipeline::Impl::scratch_outputs(bool lightmap, bool final_image, bool display,
                                                     const ToneMapOptions& tonemap) {
    // Each wanted output gets its own scratch DeviceBuffer, kept between frames.
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    FrameOutputs outs;
    outs.tonemap = tonemap;
    auto scratch = [&](int i) -> const DeviceBuffer& {
        if (!out_handles[i]) out_handles[i] = DeviceBuffer::allocate(device, out_bytes);
        return out_handles[i];
    };
    if (lightmap) outs.lightmap = scratch(0);
    if (final_image) outs.final_image = scratch(1);
    if (display) outs.display = scratch(2);
    return outs;
}

FrameImages SurroundPipeline::Impl::download_outputs(const FrameOutputs& outs, FrameTimings* timings) {
    // The outputs are copied side by side on the device and downloaded at once (the download counts as part of
    // the outputs stage).
    const auto t0 = Clock::now();
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    const int wanted = int(bool(outs.lightmap)) + int(bool(outs.final_image)) + int(bool(outs.display));
    detail::ensure_buffer(ctx, frame_result, std::size_t(std::max(1, wanted)) * out_bytes, "frame results");
    FrameImages result;
    std::vector<Image*> images;
    const DeviceBuffer* sources[3] = {&outs.lightmap, &outs.final_image, &outs.display};
    Image* targets[3] = {&result.lightmap, &result.final_image, &result.display};
    std::size_t at = 0;
    for (int i = 0; i < 3; ++i) {
        if (!*sources[i]) continue;
        ctx.copy(sources[i]->opencl_mem(), 0, frame_result.get(), at, out_bytes, "frame results");
        *targets[i] = Image(n, n, 3);
        images.push_back(targets[i]);
        at += out_bytes;
    }
    if (at) {
        std::vector<float> all(at / sizeof(float));
        ctx.read(frame_result, 0, at, all.data(), "frame results");
        for (std::size_t k = 0; k < images.size(); ++k)
            std::copy(all.begin() + std::ptrdiff_t(k * out_bytes / sizeof(float)),
                      all.begin() + std::ptrdiff_t((k + 1) * out_bytes / sizeof(float)), images[k]->data.begin());
    }
    if (timings) timings->outputs_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return result;
}

}  // namespace ngi

// One frame from image descriptors (ngi/image_desc.hpp): every image is checked, host images are uploaded in one
// transfer, each image is gathered into the pipeline's frame planes by one kernel, and the frame then runs as frame
// planes do (frame.cpp). The planes are the pipeline's own buffer, so the application's memory is only read.
#include <chrono>
#include <cstring>

#include "base/half.hpp"
#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace ngi {

namespace {

using Clock = std::chrono::steady_clock;

// Host images are packed into the staging upload at this alignment, above every format's value size (and a
// multiple of what vload_half and float reads need).
constexpr std::size_t kStagingAlign = 64;

// The faces a model reads, and whether emission / env are given (on all of them, or on none).
struct InputPlan {
    int faces = 0;
    bool has_emission = false, has_env = false;
};

// Negative values of a host depth image (decoded, scaled and biased as the gather kernel does; -Inf counts, NaN
// does not): a frame folder refuses them (io/frame_io.cpp), and so does every host input. Images in device memory
// are not read back for this (the preprocessing clamps a negative depth to 0 there).
long negative_depths(const ImageDesc& raw) {
    if (raw.depth_encoding == DepthEncoding::Perspective) return 0;  // decodes to (0, far] or "no surface" by design
    const ImageDesc d = raw.resolved();
    const auto* base = static_cast<const unsigned char*>(d.host) + d.offset;
    long count = 0;
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x) {
            const unsigned char* at = base + std::size_t(y) * d.row_stride + std::size_t(x) * d.pixel_stride;
            float v = 0.0f;
            if (d.format == PixelFormat::F32) std::memcpy(&v, at, sizeof v);
            else if (d.format == PixelFormat::F16) {
                std::uint16_t h = 0;
                std::memcpy(&h, at, sizeof h);
                v = detail::half_to_float(h);
            }  // linear depth is F32 or F16 (validate_image_desc)
            count += v * d.scale + d.bias < 0.0f;
        }
    return count;
}

InputPlan plan_inputs(const FrameInputs& in, const ModelConfig& config, int n, const Device& device) {
    InputPlan plan;
    plan.faces = detail::frame_faces(config);
    for (int f = 0; f < plan.faces; ++f)
        for (Feature feat : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct})
            validate_image_desc(in.at(Face(f), feat), Face(f), feat, n, device);
    for (int f = 0; f < plan.faces; ++f)
        if (const ImageDesc& d = in.at(Face(f), Feature::Depth); d.host)
            if (const long k = negative_depths(d))
                throw InputError("image 'depth' of face '" + std::string(face_name(Face(f))) + "': " +
                                 std::to_string(k) + " of " + std::to_string(long(d.width) * d.height) +
                                 " pixels have a negative depth (depth is a distance)");
    for (Feature feat : {Feature::Emission, Feature::Env}) {
        int present = 0;
        for (int f = 0; f < plan.faces; ++f) present += in.at(Face(f), feat).present();
        if (present != 0 && present != plan.faces)
            for (int f = 0; f < plan.faces; ++f)
                if (!in.at(Face(f), feat).present())
                    throw InputError(std::string("image '") + feature_name(feat) + "' of face '" + face_name(Face(f)) +
                                     "' is missing while other faces have one (give it for every face or none)");
        for (int f = 0; present && f < plan.faces; ++f) validate_image_desc(in.at(Face(f), feat), Face(f), feat, n, device);
        (feat == Feature::Emission ? plan.has_emission : plan.has_env) = present != 0;
    }
    return plan;
}

}  // namespace

void SurroundPipeline::enqueue(Model& model, const FrameInputs& inputs, const FrameOutputs& outputs,
                               PreprocessStats* stats, FrameTimings* timings) {
    Impl& im = *impl_;
    const auto t0 = Clock::now();
    const InputPlan plan = plan_inputs(inputs, model.config(), im.n, im.device);
    const std::size_t planes_bytes = frame_planes_bytes(im.n, plan.faces);
    if (detail::ensure_buffer(im.ctx, im.raw, planes_bytes, "frame planes") || !im.raw_handle)
        im.raw_handle = DeviceBuffer::wrap(im.device, im.raw.get(), 0, im.raw.bytes());
    if (!im.gather_image) im.gather_image = std::make_unique<detail::GatherImage>(im.ctx);

    // The images in use, in [face][feature] order.
    std::vector<std::pair<int, Feature>> used;
    for (int f = 0; f < plan.faces; ++f)
        for (int k = 0; k < kFeatureCount; ++k) {
            const Feature feat = Feature(k);
            if ((feat == Feature::Emission && !plan.has_emission) || (feat == Feature::Env && !plan.has_env)) continue;
            used.emplace_back(f, feat);
        }
    // Host images: each one's byte span [offset, offset + span) packed at an aligned place of one staging upload.
    std::vector<std::size_t> staged(used.size(), 0);
    std::size_t staging_bytes = 0;
    for (std::size_t i = 0; i < used.size(); ++i) {
        const ImageDesc& d = inputs.images[std::size_t(used[i].first)][std::size_t(used[i].second)];
        if (!d.host) continue;
        staged[i] = staging_bytes;
        staging_bytes += (d.span_bytes() + kStagingAlign - 1) / kStagingAlign * kStagingAlign;
    }
    if (staging_bytes) {
        // Packed straight into the mapped staging buffer (device memory is host memory on a CPU device; a pinned
        // transfer on a GPU): no host copy of every image, which at N = 2048 was 1 GiB held between frames.
        detail::ensure_buffer(im.ctx, im.staging, staging_bytes, "staged host images");
        im.ctx.write_in_place(im.staging, staging_bytes, "staged host images", [&](void* dst) {
            for (std::size_t i = 0; i < used.size(); ++i) {
                const ImageDesc& d = inputs.images[std::size_t(used[i].first)][std::size_t(used[i].second)];
                if (d.host)
                    std::memcpy(static_cast<unsigned char*>(dst) + staged[i],
                                static_cast<const unsigned char*>(d.host) + d.offset, d.span_bytes());
            }
        });
    }
    const int plane = im.n * im.n;
    // Normals last: an octahedral normal reads its face's gathered depth to tell "no surface" (gather_image.cl).
    std::vector<std::size_t> order;
    for (int pass = 0; pass < 2; ++pass)
        for (std::size_t i = 0; i < used.size(); ++i)
            if ((used[i].second == Feature::Normal) == (pass == 1)) order.push_back(i);
    for (const std::size_t i : order) {
        const auto [face, feat] = used[i];
        const ImageDesc d = inputs.images[std::size_t(face)][std::size_t(feat)].resolved();
        detail::GatherSource src;
        src.memory = d.host ? im.staging.get() : d.buffer.opencl_mem();
        src.offset = d.host ? staged[i] : d.offset;
        src.channel_stride = d.channel_stride;
        src.pixel_stride = d.pixel_stride;
        src.row_stride = d.row_stride;
        src.format = d.format;
        src.bottom_up = d.bottom_up;
        src.scale = d.scale;
        src.bias = d.bias;
        src.normal_encoding = d.normal_encoding;
        src.normal_to_world = d.normal_to_world;
        src.depth_encoding = d.depth_encoding;
        src.near_m = d.near_m;
        src.far_m = d.far_m;
        src.reversed_z = d.reversed_z;
        im.gather_image->enqueue(im.ctx, src, feature_channels(feat), im.n, im.raw.get(),
                                 (face * kFramePlanes + frame_plane(feat)) * plane, plane,
                                 (face * kFramePlanes + frame_plane(Feature::Depth)) * plane);
    }
    if (timings) {
        im.ctx.finish();
        timings->gather_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    }
    FrameDesc desc;
    desc.faces = plan.faces;
    desc.has_emission = plan.has_emission;
    desc.has_env = plan.has_env;
    desc.look = inputs.look;
    desc.up = inputs.up;
    enqueue(model, im.raw_handle, desc, outputs, stats, timings);
}

FrameImages SurroundPipeline::run(Model& model, const FrameInputs& inputs, bool lightmap, bool final_image,
                                  bool display, const ToneMapOptions& tonemap, PreprocessStats* stats,
                                  FrameTimings* timings) {
    Impl& im = *impl_;
    const FrameOutputs outs = im.scratch_outputs(lightmap, final_image, display, tonemap);
    enqueue(model, inputs, outs, stats, timings);  // with `stats`, the counters' download too
    return im.download_outputs(outs, timings);
}

}  // namespace ngi

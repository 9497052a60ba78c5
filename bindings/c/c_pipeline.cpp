// The surround pipeline: one frame of six (or one) faces -> lightmap, final image and display image, from frame planes
// (host or device) or from an engine's render targets described image by image (ngi_image_desc, with their encodings).
// The pipeline handle also holds the camera and the tone mapping its frames use.
#include "c_handles.hpp"

using namespace c_abi;

static_assert(int(NGI_FORMAT_F32) == int(ngi::PixelFormat::F32) && int(NGI_FORMAT_F16) == int(ngi::PixelFormat::F16) &&
                  int(NGI_FORMAT_U8_UNORM) == int(ngi::PixelFormat::U8Unorm) &&
                  int(NGI_FORMAT_U8_SRGB) == int(ngi::PixelFormat::U8Srgb) &&
                  int(NGI_FORMAT_U16_UNORM) == int(ngi::PixelFormat::U16Unorm) &&
                  int(NGI_FORMAT_S16_SNORM) == int(ngi::PixelFormat::S16Snorm) &&
                  int(NGI_FORMAT_R11G11B10F) == int(ngi::PixelFormat::R11G11B10F) &&
                  int(NGI_FORMAT_RGB10A2_UNORM) == int(ngi::PixelFormat::RGB10A2Unorm),
              "ngi_pixel_format mirrors ngi::PixelFormat");
static_assert(int(NGI_NORMAL_OCTAHEDRAL) == int(ngi::NormalEncoding::Octahedral) &&
                  int(NGI_DEPTH_PERSPECTIVE) == int(ngi::DepthEncoding::Perspective),
              "ngi_normal_encoding / ngi_depth_encoding mirror ngi::NormalEncoding / ngi::DepthEncoding");
static_assert(int(NGI_FEATURE_ENV) == int(ngi::Feature::Env) && int(NGI_FEATURE_DEPTH) == int(ngi::Feature::Depth) &&
                  NGI_FEATURE_COUNT == ngi::kFeatureCount,
              "ngi_feature mirrors ngi::Feature");

namespace {

ngi::FrameDesc frame_desc(const ngi_pipeline& p, int faces, unsigned flags) {
    require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces));
    require((flags & ~unsigned(NGI_FRAME_EMISSION | NGI_FRAME_ENV)) == 0,
            "flags " + std::to_string(flags) + " holds bits that are not ngi_frame_flags");
    ngi::FrameDesc d;
    d.faces = faces;
    d.has_emission = flags & NGI_FRAME_EMISSION;
    d.has_env = flags & NGI_FRAME_ENV;
    d.look = p.look;
    d.up = p.up;
    return d;
}

ngi::FrameInputs frame_inputs(const ngi_pipeline& p, const ngi_image_desc* images,
                              const ngi_image_encoding* encodings = nullptr) {
    require(images, "images is NULL (36 descriptors expected)");
    ngi::FrameInputs in;
    in.look = p.look;
    in.up = p.up;
    for (int f = 0; f < ngi::kFaceCount; ++f)
        for (int k = 0; k < ngi::kFeatureCount; ++k) {
            const ngi_image_desc& c = images[f * ngi::kFeatureCount + k];
            ngi::ImageDesc& d = in.images[std::size_t(f)][std::size_t(k)];
            if (c.buffer) d.buffer = live(c.buffer, "image buffer").buffer;
            d.host = c.host;
            d.host_bytes = c.host_bytes;
            d.format = ngi::PixelFormat(int(c.format));
            d.channels = c.channels;
            d.width = c.width;
            d.height = c.height;
            d.offset = c.offset;
            d.pixel_stride = c.pixel_stride;
            d.row_stride = c.row_stride;
            d.channel_stride = c.channel_stride;
            d.bottom_up = c.bottom_up != 0;
            d.scale = c.scale == 0.0f ? 1.0f : c.scale;
            d.bias = c.bias;
            if (!encodings) continue;
            const ngi_image_encoding& e = encodings[f * ngi::kFeatureCount + k];
            d.normal_encoding = ngi::NormalEncoding(int(e.normal_encoding));
            bool any = false;
            for (float v : e.normal_to_world) any = any || v != 0.0f;
            if (any)  // row-major in C; glm is column-major: m[column][row]
                for (int r = 0; r < 3; ++r)
                    for (int col = 0; col < 3; ++col) d.normal_to_world[col][r] = e.normal_to_world[r * 3 + col];
            d.depth_encoding = ngi::DepthEncoding(int(e.depth_encoding));
            d.near_m = e.near_m;
            d.far_m = e.far_m;
            d.reversed_z = e.reversed_z != 0;
        }
    return in;
}

// The sizes of host outputs: each given one must hold N x N x 3 floats.
void check_output_sizes(const ngi_pipeline& p, const float* lightmap, std::size_t lightmap_bytes, const float* final_image,
                        std::size_t final_bytes, const float* display, std::size_t display_bytes) {
    require(lightmap || final_image || display, "lightmap, final_image and display are all NULL: nothing to make");
    const std::size_t need = 3 * std::size_t(p.pipeline.n()) * std::size_t(p.pipeline.n()) * sizeof(float);
    const std::pair<std::size_t, const char*> sizes[3] = {{lightmap ? lightmap_bytes : need, "lightmap_bytes"},
                                                          {final_image ? final_bytes : need, "final_bytes"},
                                                          {display ? display_bytes : need, "display_bytes"}};
    for (const auto& [bytes, name] : sizes)
        require(bytes >= need, std::string(name) + " is " + std::to_string(bytes) + ", an N x N x 3 image needs " +
                                   std::to_string(need));
}

void copy_outputs(const ngi::FrameImages& r, float* lightmap, float* final_image, float* display) {
    if (lightmap) std::memcpy(lightmap, r.lightmap.data.data(), r.lightmap.data.size() * sizeof(float));
    if (final_image) std::memcpy(final_image, r.final_image.data.data(), r.final_image.data.size() * sizeof(float));
    if (display) std::memcpy(display, r.display.data.data(), r.display.data.size() * sizeof(float));
}

ngi::FrameOutputs device_outputs(const ngi_pipeline& p, ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display) {
    require(lightmap || final_image || display, "lightmap, final_image and display are all NULL: nothing to make");
    ngi::FrameOutputs outs;
    const std::size_t need = 3 * std::size_t(p.pipeline.n()) * std::size_t(p.pipeline.n()) * sizeof(float);
    const std::string what = "an N x N x 3 image (N = " + std::to_string(p.pipeline.n()) + ")";
    const std::pair<ngi_buffer*, const char*> given[3] = {{lightmap, "lightmap"}, {final_image, "final_image"},
                                                          {display, "display"}};
    for (const auto& [b, name] : given)
        if (b) require_buffer(live(b, name), need, name, what);
    if (lightmap) outs.lightmap = live(lightmap, "lightmap").buffer;
    if (final_image) outs.final_image = live(final_image, "final_image").buffer;
    if (display) outs.display = live(display, "display").buffer;
    outs.tonemap = p.tonemap;
    return outs;
}

// The image-descriptor calls with and without encodings share these; `call` is the public name the caller used
// (what an error names).
ngi_status enqueue_images(const char* call, ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                          const ngi_image_encoding* encodings, ngi_buffer* lightmap, ngi_buffer* final_image,
                          ngi_buffer* display) {
    return guarded(call, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        p.pipeline.enqueue(m.model, frame_inputs(p, images, encodings), device_outputs(p, lightmap, final_image, display));
        m.last_was_enqueue = true;
    });
}

ngi_status run_images(const char* call, ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                      const ngi_image_encoding* encodings, float* lightmap, size_t lightmap_bytes, float* final_image,
                      size_t final_bytes, float* display, size_t display_bytes) {
    return guarded(call, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        check_output_sizes(p, lightmap, lightmap_bytes, final_image, final_bytes, display, display_bytes);
        copy_outputs(p.pipeline.run(m.model, frame_inputs(p, images, encodings), lightmap != nullptr,
                                    final_image != nullptr, display != nullptr, p.tonemap),
                     lightmap, final_image, display);
        m.last_was_enqueue = true;
    });
}

}  // namespace

extern "C" {

ngi_status ngi_pipeline_new(ngi_device* device, int n, ngi_global_view_mode mode, ngi_lumination_transfer transfer,
                            ngi_pipeline** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(mode == NGI_GLOBAL_VIEW_THESIS || mode == NGI_GLOBAL_VIEW_EQUIRECT,
                "mode " + std::to_string(int(mode)) + " is not an ngi_global_view_mode");
        require(transfer == NGI_TRANSFER_REINHARD || transfer == NGI_TRANSFER_CLAMP,
                "transfer " + std::to_string(int(transfer)) + " is not an ngi_lumination_transfer");
        *out = track(std::make_unique<ngi_pipeline>(d.device, n, ngi::GlobalViewMode(int(mode)),
                                                    ngi::LuminationTransfer(int(transfer))));
    });
}

ngi_status ngi_pipeline_frame_bytes(const ngi_pipeline* pipeline, int faces, size_t* bytes) {
    return guarded(__func__, [&] {
        const ngi_pipeline& p = live(pipeline, "pipeline");
        require(bytes, "bytes is NULL");
        require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces));
        *bytes = ngi::frame_planes_bytes(p.pipeline.n(), faces);
    });
}

ngi_status ngi_pipeline_set_camera(ngi_pipeline* pipeline, const float look[3], const float up[3]) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        require(look && up, "look and up must not be NULL");
        const glm::vec3 l(look[0], look[1], look[2]), u(up[0], up[1], up[2]);
        for (int i = 0; i < 3; ++i) require(std::isfinite(l[i]) && std::isfinite(u[i]), "look and up must be finite");
        require(glm::length(l) > 0 && glm::length(glm::cross(l, u)) > 1e-6f * glm::length(l) * glm::length(u),
                "look must be non-zero and not parallel to up");
        p.look = l;
        p.up = u;
    });
}

ngi_status ngi_pipeline_set_tonemap(ngi_pipeline* pipeline, float exposure_ev, ngi_tone_curve curve, int srgb) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        require(std::isfinite(exposure_ev) && std::abs(exposure_ev) <= 64.0f,
                "exposure_ev " + std::to_string(exposure_ev) + " is not in [-64, 64]");
        require(curve == NGI_TONE_ACES || curve == NGI_TONE_REINHARD || curve == NGI_TONE_CLAMP,
                "curve " + std::to_string(int(curve)) + " is not an ngi_tone_curve");
        p.tonemap = {exposure_ev, ngi::ToneCurve(int(curve)), srgb != 0};
    });
}

ngi_status ngi_pipeline_enqueue(ngi_pipeline* pipeline, ngi_model* model, ngi_buffer* planes, int faces, unsigned flags,
                                ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        const ngi_buffer& in = live(planes, "planes");
        const ngi::FrameDesc desc = frame_desc(p, faces, flags);
        require_buffer(in, ngi::frame_planes_bytes(p.pipeline.n(), faces), "planes", face_string(p.pipeline.n(), faces));
        p.pipeline.enqueue(m.model, in.buffer, desc, device_outputs(p, lightmap, final_image, display));
        m.last_was_enqueue = true;
    });
}


ngi_status ngi_pipeline_enqueue_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                       ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display) {
    return enqueue_images(__func__, pipeline, model, images, nullptr, lightmap, final_image, display);
}

ngi_status ngi_pipeline_enqueue_images_encoded(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                               const ngi_image_encoding* encodings, ngi_buffer* lightmap,
                                               ngi_buffer* final_image, ngi_buffer* display) {
    return enqueue_images(__func__, pipeline, model, images, encodings, lightmap, final_image, display);
}

ngi_status ngi_pipeline_run_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                   float* lightmap, size_t lightmap_bytes, float* final_image, size_t final_bytes,
                                   float* display, size_t display_bytes) {
    return run_images(__func__, pipeline, model, images, nullptr, lightmap, lightmap_bytes, final_image, final_bytes,
                      display, display_bytes);
}

ngi_status ngi_pipeline_run_images_encoded(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                           const ngi_image_encoding* encodings, float* lightmap, size_t lightmap_bytes,
                                           float* final_image, size_t final_bytes, float* display,
                                           size_t display_bytes) {
    return run_images(__func__, pipeline, model, images, encodings, lightmap, lightmap_bytes, final_image, final_bytes,
                      display, display_bytes);
}

ngi_status ngi_pipeline_run(ngi_pipeline* pipeline, ngi_model* model, const float* planes, size_t planes_bytes,
                            int faces, unsigned flags, float* lightmap, size_t lightmap_bytes, float* final_image,
                            size_t final_bytes, float* display, size_t display_bytes) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        require(planes, "planes is NULL");
        const ngi::FrameDesc desc = frame_desc(p, faces, flags);
        require_bytes(planes_bytes, ngi::frame_planes_bytes(p.pipeline.n(), faces), "planes_bytes",
                      face_string(p.pipeline.n(), faces));
        check_output_sizes(p, lightmap, lightmap_bytes, final_image, final_bytes, display, display_bytes);
        copy_outputs(p.pipeline.run(m.model, planes, planes_bytes, desc, lightmap != nullptr,
                                    final_image != nullptr, display != nullptr, p.tonemap),
                     lightmap, final_image, display);
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_pipeline_retain(ngi_pipeline* pipeline) { return guarded(__func__, [&] { retain_handle(pipeline, "pipeline"); }); }
ngi_status ngi_pipeline_release(ngi_pipeline* pipeline) { return guarded(__func__, [&] { release_handle(pipeline, "pipeline"); }); }

}  // extern "C"

// The C ABI over the C++ API: opaque reference-counted handles checked against a registry of live handles,
// exceptions turned into status codes, a thread-local last error reset by every call, and an error callback.
#include "ngi.h"

#include <CL/cl.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <string>
#include <unordered_set>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"

// Every handle starts with its reference count; the object is deleted with its last reference.
struct ngi_handle {
    std::atomic<int> refs{1};
    virtual ~ngi_handle() = default;
};
struct ngi_device : ngi_handle {
    explicit ngi_device(ngi::Device d) : device(std::move(d)) {}
    ngi::Device device;
};
struct ngi_model : ngi_handle {
    explicit ngi_model(ngi::Model m) : model(std::move(m)) {}
    ngi::Model model;
    int sanitized_inputs = 0;  // of the last blocking run
    bool last_was_enqueue = false;
};
struct ngi_buffer : ngi_handle {
    explicit ngi_buffer(ngi::DeviceBuffer b) : buffer(std::move(b)) {}
    ngi::DeviceBuffer buffer;
};
struct ngi_pipeline : ngi_handle {
    ngi_pipeline(const ngi::Device& d, int n, ngi::GlobalViewMode m, ngi::LuminationTransfer t) : pipeline(d, n, m, t) {}
    ngi::SurroundPipeline pipeline;
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};
    ngi::ToneMapOptions tonemap;
};

namespace {

thread_local std::string g_last_error;
thread_local int g_last_cl_error = 0;
std::mutex g_callback_mutex;
ngi_error_callback g_callback = nullptr;
void* g_callback_user = nullptr;

// The handles alive now. A handle is checked here before every use, so one released and used again is refused
// (as long as its address has not been reused by a new handle, which no check can tell apart).
std::mutex g_live_mutex;
std::unordered_set<const ngi_handle*> g_live;

// A failure with its status, thrown inside a call and turned into the return value by guarded().
struct ApiError {
    ngi_status status;
    std::string message;
};

[[noreturn]] void fail(ngi_status status, const std::string& message) { throw ApiError{status, message}; }

template <class H>
H* track(H* h) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    g_live.insert(h);
    return h;
}

// The handle `h` (argument `arg` of `call`) if it is alive, else an ApiError.
template <class H>
H& live(H* h, const char* arg) {
    if (!h) fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is NULL");
    std::lock_guard<std::mutex> lock(g_live_mutex);
    if (!g_live.count(h))
        fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is not a live handle (released, or never created)");
    return *h;
}

void report(const char* call, ngi_status status, const std::string& message) {
    g_last_error = std::string(call) + ": " + message;
    ngi_error_callback cb;
    void* user;
    {
        std::lock_guard<std::mutex> lock(g_callback_mutex);
        cb = g_callback;
        user = g_callback_user;
    }
    if (cb) cb(user, status, g_last_error.c_str());
}

bool is_out_of_memory(int cl) {
    return cl == CL_MEM_OBJECT_ALLOCATION_FAILURE || cl == CL_OUT_OF_RESOURCES || cl == CL_OUT_OF_HOST_MEMORY;
}

// Runs f for C entry point `call`: the last error is reset first; every exception becomes a status and a message.
template <class F>
ngi_status guarded(const char* call, F&& f) noexcept {
    g_last_error.clear();
    g_last_cl_error = 0;
    ngi_status status = NGI_OK;
    std::string message;
    try {
        f();
        return NGI_OK;
    } catch (const ApiError& e) {
        status = e.status;
        message = e.message;
    } catch (const ngi::ClError& e) {
        g_last_cl_error = e.code();
        status = is_out_of_memory(e.code()) ? NGI_ERROR_OUT_OF_MEMORY : NGI_ERROR_OPENCL;
        message = e.what();
    } catch (const ngi::OutOfMemoryError& e) {
        status = NGI_ERROR_OUT_OF_MEMORY;
        message = e.what();
    } catch (const ngi::InputError& e) {
        status = NGI_ERROR_INPUT;
        message = e.what();
    } catch (const std::bad_alloc&) {
        status = NGI_ERROR_OUT_OF_MEMORY;
        message = "out of host memory";
    } catch (const std::exception& e) {
        status = NGI_ERROR_INTERNAL;
        message = e.what();
    } catch (...) {
        status = NGI_ERROR_INTERNAL;
        message = "unknown exception";
    }
    try {
        report(call, status, message);
    } catch (...) {  // no memory even for the message: the status still says what happened
    }
    return status;
}

void require(bool ok, const std::string& what) {
    if (!ok) fail(NGI_ERROR_INVALID_ARGUMENT, what);
}

template <class H>
void retain_handle(H* h, const char* arg) {
    live(h, arg).refs.fetch_add(1);
}

template <class H>
void release_handle(H* h, const char* arg) {
    if (!h) return;  // like free(NULL)
    {
        std::lock_guard<std::mutex> lock(g_live_mutex);
        if (!g_live.count(h))
            fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is not a live handle (released twice?)");
        if (h->refs.fetch_sub(1) != 1) return;
        g_live.erase(h);
    }
    delete h;
}

void copy_string(const std::string& s, char* buf, std::size_t size, std::size_t* needed) {
    if (needed) *needed = s.size() + 1;
    require(buf || size == 0, "buf is NULL with a non-zero size");
    if (size == 0) {
        require(needed != nullptr, "buf and needed are both empty: nothing to return");
        return;
    }
    const std::size_t n = std::min(s.size(), size - 1);
    std::memcpy(buf, s.data(), n);
    buf[n] = '\0';
    if (n < s.size()) fail(NGI_ERROR_INVALID_ARGUMENT, "buf of " + std::to_string(size) + " bytes is too small; " +
                                                           std::to_string(s.size() + 1) + " needed (truncated)");
}

std::string property_string(const ngi::DeviceInfo& info, ngi_device_property p) {
    switch (p) {
        case NGI_DEVICE_NAME: return info.name;
        case NGI_DEVICE_PLATFORM: return info.platform_name;
        case NGI_DEVICE_VENDOR: return info.vendor;
        case NGI_DEVICE_DRIVER_VERSION: return info.driver_version;
        default: fail(NGI_ERROR_INVALID_ARGUMENT, "property " + std::to_string(int(p)) + " is not a string property");
    }
}

long long property_integer(const ngi::DeviceInfo& info, ngi_device_property p) {
    switch (p) {
        case NGI_DEVICE_IS_GPU: return info.is_gpu;
        case NGI_DEVICE_IS_CPU: return info.is_cpu;
        case NGI_DEVICE_FP16: return info.fp16;
        case NGI_DEVICE_GLOBAL_MEM_BYTES: return (long long)info.global_mem_bytes;
        case NGI_DEVICE_MAX_ALLOC_BYTES: return (long long)info.max_alloc_bytes;
        case NGI_DEVICE_LOCAL_MEM_BYTES: return (long long)info.local_mem_bytes;
        case NGI_DEVICE_COMPUTE_UNITS: return info.compute_units;
        case NGI_DEVICE_PLATFORM_INDEX: return info.platform_index;
        case NGI_DEVICE_DEVICE_INDEX: return info.device_index;
        default: fail(NGI_ERROR_INVALID_ARGUMENT, "property " + std::to_string(int(p)) + " is not an integer property");
    }
}

ngi::DeviceInfo listed(int index) {
    const auto all = ngi::list_devices();
    require(index >= 0 && std::size_t(index) < all.size(),
            "index " + std::to_string(index) + " is not in 0.." + std::to_string(int(all.size()) - 1));
    return all[std::size_t(index)];
}

// Bytes of a c x h x w float image, or an error when it does not fit in size_t.
std::size_t image_bytes(int c, int h, int w) {
    require(h > 0 && w > 0, "height and width must be positive, got " + std::to_string(h) + "x" + std::to_string(w));
    const std::size_t n = std::size_t(c) * std::size_t(h) * std::size_t(w);
    require(n / std::size_t(h) / std::size_t(w) == std::size_t(c) &&
                n <= std::numeric_limits<std::size_t>::max() / sizeof(float),
            "height x width overflows");
    return n * sizeof(float);
}

}  // namespace

extern "C" {

int ngi_version(void) { return NGI_VERSION; }

const char* ngi_status_name(ngi_status s) {
    switch (s) {
        case NGI_OK: return "NGI_OK";
        case NGI_ERROR_INVALID_ARGUMENT: return "NGI_ERROR_INVALID_ARGUMENT";
        case NGI_ERROR_INPUT: return "NGI_ERROR_INPUT";
        case NGI_ERROR_OPENCL: return "NGI_ERROR_OPENCL";
        case NGI_ERROR_OUT_OF_MEMORY: return "NGI_ERROR_OUT_OF_MEMORY";
        case NGI_ERROR_INVALID_HANDLE: return "NGI_ERROR_INVALID_HANDLE";
        case NGI_ERROR_INTERNAL: return "NGI_ERROR_INTERNAL";
        case NGI_STATUS_MAX_ENUM: break;
    }
    return "NGI_UNKNOWN_STATUS";
}

const char* ngi_last_error(void) { return g_last_error.c_str(); }
int ngi_last_cl_error(void) { return g_last_cl_error; }

void ngi_set_error_callback(ngi_error_callback callback, void* user) {
    std::lock_guard<std::mutex> lock(g_callback_mutex);
    g_callback = callback;
    g_callback_user = user;
}

// --- devices ---------------------------------------------------------------------------------------------------

ngi_status ngi_device_count(int* count) {
    return guarded(__func__, [&] {
        require(count, "count is NULL");
        *count = int(ngi::list_devices().size());
    });
}

ngi_status ngi_device_list_string(int index, ngi_device_property p, char* buf, size_t size, size_t* needed) {
    return guarded(__func__, [&] { copy_string(property_string(listed(index), p), buf, size, needed); });
}

ngi_status ngi_device_list_integer(int index, ngi_device_property p, long long* value) {
    return guarded(__func__, [&] {
        require(value, "value is NULL");
        *value = property_integer(listed(index), p);
    });
}

ngi_status ngi_device_open(const char* spec, ngi_device** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        *out = track(new ngi_device(ngi::Device::open(spec ? spec : "")));
    });
}

ngi_status ngi_device_from_opencl(struct _cl_context* context, struct _cl_device_id* device,
                                  struct _cl_command_queue* queue, ngi_device** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require(context && device && queue, "context, device and queue must not be NULL");
        *out = track(new ngi_device(ngi::Device::from_opencl(context, device, queue)));
    });
}

ngi_status ngi_device_string(const ngi_device* device, ngi_device_property p, char* buf, size_t size, size_t* needed) {
    return guarded(__func__, [&] { copy_string(property_string(live(device, "device").device.info(), p), buf, size, needed); });
}

ngi_status ngi_device_integer(const ngi_device* device, ngi_device_property p, long long* value) {
    return guarded(__func__, [&] {
        const ngi_device& d = live(device, "device");
        require(value, "value is NULL");
        *value = property_integer(d.device.info(), p);
    });
}

ngi_status ngi_device_opencl(const ngi_device* device, struct _cl_context** context, struct _cl_command_queue** queue) {
    return guarded(__func__, [&] {
        const ngi_device& d = live(device, "device");
        if (context) *context = d.device.opencl_context();
        if (queue) *queue = d.device.opencl_queue();
    });
}

ngi_status ngi_device_sync(ngi_device* device) {
    return guarded(__func__, [&] { live(device, "device").device.finish(); });
}

ngi_status ngi_device_marker(ngi_device* device, struct _cl_event** event) {
    return guarded(__func__, [&] {
        const ngi_device& d = live(device, "device");
        require(event, "event is NULL");
        *event = d.device.marker();
    });
}

ngi_status ngi_device_host_transfers(const ngi_device* device, long long* uploads, long long* downloads) {
    return guarded(__func__, [&] {
        const ngi::HostTransfers t = live(device, "device").device.host_transfers();
        if (uploads) *uploads = t.uploads;
        if (downloads) *downloads = t.downloads;
    });
}

ngi_status ngi_device_retain(ngi_device* device) { return guarded(__func__, [&] { retain_handle(device, "device"); }); }
ngi_status ngi_device_release(ngi_device* device) { return guarded(__func__, [&] { release_handle(device, "device"); }); }

// --- buffers ---------------------------------------------------------------------------------------------------

ngi_status ngi_buffer_new(ngi_device* device, size_t bytes, ngi_buffer** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(bytes > 0, "bytes is 0");
        *out = track(new ngi_buffer(ngi::DeviceBuffer::allocate(d.device, bytes)));
    });
}

ngi_status ngi_buffer_wrap(ngi_device* device, struct _cl_mem* mem, size_t offset, size_t bytes, ngi_buffer** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(mem, "mem is NULL");
        require(bytes > 0, "bytes is 0");
        *out = track(new ngi_buffer(ngi::DeviceBuffer::wrap(d.device, mem, offset, bytes)));
    });
}

ngi_status ngi_buffer_size(const ngi_buffer* buffer, size_t* bytes) {
    return guarded(__func__, [&] {
        const ngi_buffer& b = live(buffer, "buffer");
        require(bytes, "bytes is NULL");
        *bytes = b.buffer.bytes();
    });
}

ngi_status ngi_buffer_write(ngi_buffer* buffer, size_t offset, const void* src, size_t bytes) {
    return guarded(__func__, [&] {
        ngi_buffer& b = live(buffer, "buffer");
        require(src || bytes == 0, "src is NULL");
        b.buffer.upload(src, bytes, offset);
    });
}

ngi_status ngi_buffer_read(const ngi_buffer* buffer, size_t offset, void* dst, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi_buffer& b = live(buffer, "buffer");
        require(dst || bytes == 0, "dst is NULL");
        b.buffer.download(dst, bytes, offset);
    });
}

ngi_status ngi_buffer_retain(ngi_buffer* buffer) { return guarded(__func__, [&] { retain_handle(buffer, "buffer"); }); }
ngi_status ngi_buffer_release(ngi_buffer* buffer) { return guarded(__func__, [&] { release_handle(buffer, "buffer"); }); }

// --- models ----------------------------------------------------------------------------------------------------

ngi_status ngi_model_load_with_options(ngi_device* device, const char* path, ngi_bn_mode bn_mode, ngi_dropout dropout,
                                       ngi_model** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(path, "path is NULL");
        ngi::ModelOptions options;
        switch (bn_mode) {
            case NGI_BN_FROM_FILE: break;
            case NGI_BN_RUNNING: options.bn_mode = "running"; break;
            case NGI_BN_PER_IMAGE: options.bn_mode = "per_image"; break;
            default: fail(NGI_ERROR_INVALID_ARGUMENT, "bn_mode " + std::to_string(int(bn_mode)) + " is not an ngi_bn_mode");
        }
        switch (dropout) {
            case NGI_DROPOUT_FROM_FILE: break;
            case NGI_DROPOUT_OFF: options.dropout = "off"; break;
            case NGI_DROPOUT_SEEDED: options.dropout = "seeded"; break;
            default: fail(NGI_ERROR_INVALID_ARGUMENT, "dropout " + std::to_string(int(dropout)) + " is not an ngi_dropout");
        }
        *out = track(new ngi_model(ngi::Model::load(d.device, path, options)));
    });
}

ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out) {
    return ngi_model_load_with_options(device, path, NGI_BN_FROM_FILE, NGI_DROPOUT_FROM_FILE, out);
}

ngi_status ngi_model_channels(const ngi_model* model, int* input_nc, int* output_nc, int* num_downs) {
    return guarded(__func__, [&] {
        const auto& c = live(model, "model").model.config();
        if (input_nc) *input_nc = c.input_nc;
        if (output_nc) *output_nc = c.output_nc;
        if (num_downs) *num_downs = c.num_downs;
    });
}

ngi_status ngi_model_output_mode(const ngi_model* model, ngi_output_mode* mode) {
    return guarded(__func__, [&] {
        const auto& c = live(model, "model").model.config();
        require(mode, "mode is NULL");
        // The loader admits exactly these two values (host/src/models/unet.cpp).
        *mode = c.output_mode == "indirect" ? NGI_OUTPUT_INDIRECT : NGI_OUTPUT_LIGHTMAP;
    });
}

ngi_status ngi_model_run(ngi_model* model, const float* input, size_t input_bytes, int height, int width,
                         float* output, size_t output_bytes) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        require(input, "input is NULL");
        require(output, "output is NULL");
        const auto& c = m.model.config();
        const std::size_t in_need = image_bytes(c.input_nc, height, width);
        const std::size_t out_need = image_bytes(c.output_nc, height, width);
        require(input_bytes >= in_need, "input_bytes is " + std::to_string(input_bytes) + ", the model needs " +
                                            std::to_string(in_need) + " for " + std::to_string(c.input_nc) + "x" +
                                            std::to_string(height) + "x" + std::to_string(width) + " floats");
        require(output_bytes >= out_need, "output_bytes is " + std::to_string(output_bytes) + ", the model writes " +
                                              std::to_string(out_need));
        ngi::Tensor in({1, c.input_nc, height, width});
        std::memcpy(in.data.data(), input, in_need);
        ngi::RunInfo info;
        const ngi::Tensor y = m.model.run(in, &info);
        std::memcpy(output, y.data.data(), out_need);
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_model_enqueue(ngi_model* model, ngi_buffer* input, ngi_buffer* output, int height, int width) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        const ngi_buffer& in = live(input, "input");
        const ngi_buffer& out = live(output, "output");
        m.model.enqueue(in.buffer, out.buffer, height, width);
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_model_sanitized_inputs(ngi_model* model, int* count) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        require(count, "count is NULL");
        *count = m.last_was_enqueue ? m.model.sanitized_inputs() : m.sanitized_inputs;
    });
}

ngi_status ngi_model_retain(ngi_model* model) { return guarded(__func__, [&] { retain_handle(model, "model"); }); }
ngi_status ngi_model_release(ngi_model* model) { return guarded(__func__, [&] { release_handle(model, "model"); }); }

// --- pipeline --------------------------------------------------------------------------------------------------

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
        *out = track(new ngi_pipeline(d.device, n, ngi::GlobalViewMode(int(mode)), ngi::LuminationTransfer(int(transfer))));
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
}  // namespace

static_assert(int(NGI_FORMAT_F32) == int(ngi::PixelFormat::F32) && int(NGI_FORMAT_F16) == int(ngi::PixelFormat::F16) &&
                  int(NGI_FORMAT_U8_UNORM) == int(ngi::PixelFormat::U8Unorm) &&
                  int(NGI_FORMAT_U8_SRGB) == int(ngi::PixelFormat::U8Srgb),
              "ngi_pixel_format mirrors ngi::PixelFormat");
static_assert(int(NGI_FEATURE_ENV) == int(ngi::Feature::Env) && int(NGI_FEATURE_DEPTH) == int(ngi::Feature::Depth) &&
                  NGI_FEATURE_COUNT == ngi::kFeatureCount,
              "ngi_feature mirrors ngi::Feature");

namespace {

ngi::FrameInputs frame_inputs(const ngi_pipeline& p, const ngi_image_desc* images) {
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
    if (lightmap) outs.lightmap = live(lightmap, "lightmap").buffer;
    if (final_image) outs.final_image = live(final_image, "final_image").buffer;
    if (display) outs.display = live(display, "display").buffer;
    outs.tonemap = p.tonemap;
    return outs;
}

}  // namespace

ngi_status ngi_pipeline_enqueue(ngi_pipeline* pipeline, ngi_model* model, ngi_buffer* planes, int faces, unsigned flags,
                                ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        const ngi_buffer& in = live(planes, "planes");
        p.pipeline.enqueue(m.model, in.buffer, frame_desc(p, faces, flags),
                           device_outputs(p, lightmap, final_image, display));
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_pipeline_enqueue_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                       ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        p.pipeline.enqueue(m.model, frame_inputs(p, images), device_outputs(p, lightmap, final_image, display));
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_pipeline_run_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                   float* lightmap, size_t lightmap_bytes, float* final_image, size_t final_bytes,
                                   float* display, size_t display_bytes) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        check_output_sizes(p, lightmap, lightmap_bytes, final_image, final_bytes, display, display_bytes);
        copy_outputs(p.pipeline.run(m.model, frame_inputs(p, images), lightmap != nullptr, final_image != nullptr,
                                    display != nullptr, p.tonemap),
                     lightmap, final_image, display);
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_pipeline_run(ngi_pipeline* pipeline, ngi_model* model, const float* planes, size_t planes_bytes,
                            int faces, unsigned flags, float* lightmap, size_t lightmap_bytes, float* final_image,
                            size_t final_bytes, float* display, size_t display_bytes) {
    return guarded(__func__, [&] {
        ngi_pipeline& p = live(pipeline, "pipeline");
        ngi_model& m = live(model, "model");
        require(planes, "planes is NULL");
        check_output_sizes(p, lightmap, lightmap_bytes, final_image, final_bytes, display, display_bytes);
        copy_outputs(p.pipeline.run(m.model, planes, planes_bytes, frame_desc(p, faces, flags), lightmap != nullptr,
                                    final_image != nullptr, display != nullptr, p.tonemap),
                     lightmap, final_image, display);
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_pipeline_retain(ngi_pipeline* pipeline) { return guarded(__func__, [&] { retain_handle(pipeline, "pipeline"); }); }
ngi_status ngi_pipeline_release(ngi_pipeline* pipeline) { return guarded(__func__, [&] { release_handle(pipeline, "pipeline"); }); }

// --- files -----------------------------------------------------------------------------------------------------

ngi_status ngi_read_frame_planes(const char* folder, int faces, float* planes, size_t bytes, int* n, size_t* needed,
                                 unsigned* flags, float look[3], float up[3]) {
    return guarded(__func__, [&] {
        require(folder, "folder is NULL");
        require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces));
        const ngi::Frame frame = ngi::read_frame(folder);
        const std::size_t need = ngi::frame_planes_bytes(frame.n, faces);
        if (n) *n = frame.n;
        if (needed) *needed = need;
        const ngi::FrameDesc d = ngi::FrameDesc::of(frame, faces);
        if (flags) *flags = (d.has_emission ? unsigned(NGI_FRAME_EMISSION) : 0u) | (d.has_env ? unsigned(NGI_FRAME_ENV) : 0u);
        for (int i = 0; i < 3; ++i) {
            if (look) look[i] = d.look[i];
            if (up) up[i] = d.up[i];
        }
        if (!planes) return;
        require(bytes >= need, "bytes is " + std::to_string(bytes) + ", the frame's planes need " + std::to_string(need));
        const std::vector<float> packed = ngi::pack_frame_planes(frame, faces);
        std::memcpy(planes, packed.data(), need);
    });
}

ngi_status ngi_write_image(const char* path, const float* data, size_t bytes, int width, int height, int channels) {
    return guarded(__func__, [&] {
        require(path, "path is NULL");
        require(data, "data is NULL");
        require(channels > 0 && channels <= 4, "channels must be 1..4, got " + std::to_string(channels));
        const std::size_t need = image_bytes(channels, height, width);
        require(bytes >= need, "bytes is " + std::to_string(bytes) + ", the image needs " + std::to_string(need));
        ngi::Image im(width, height, channels);
        std::memcpy(im.data.data(), data, need);
        ngi::write_image(path, im);
    });
}

}  // extern "C"

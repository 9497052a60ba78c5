// The C ABI over the C++ API: opaque, typed, reference-counted handles checked against a registry of live handles
// and their types, exceptions turned into status codes, a thread-local last error reset by every call, and an error
// callback. The rules: bindings/c/README.md.
#include "ngi.h"

#include <CL/cl.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <unordered_map>

#include "ngi/ao.hpp"
#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/display.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/model.hpp"
#include "ngi/neural_gi.hpp"
#include "ngi/pipeline.hpp"
#include "ngi/warmup.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/voxel_field.hpp"
#include "ngi/voxel_gi.hpp"

// The type of a handle: its tag in the registry of live handles, checked by every call before the handle is used.
enum class HandleKind { Device, Buffer, Model, Pipeline, Display, Frame, Ao, Voxels, NeuralGi };

static const char* kind_name(HandleKind k) {
    switch (k) {
        case HandleKind::Device: return "ngi_device";
        case HandleKind::Buffer: return "ngi_buffer";
        case HandleKind::Model: return "ngi_model";
        case HandleKind::Pipeline: return "ngi_pipeline";
        case HandleKind::Display: return "ngi_display";
        case HandleKind::Frame: return "ngi_frame";
        case HandleKind::Ao: return "ngi_ao";
        case HandleKind::Voxels: return "ngi_voxels";
        case HandleKind::NeuralGi: return "ngi_neural_gi";
    }
    return "unknown handle type";
}

// Every handle starts with its reference count; the object is deleted with its last reference.
struct ngi_handle {
    std::atomic<int> refs{1};
    virtual ~ngi_handle() = default;
};
struct ngi_device : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Device;
    explicit ngi_device(ngi::Device d) : device(std::move(d)) {}
    ngi::Device device;
};
struct ngi_model : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Model;
    explicit ngi_model(ngi::Model m) : model(std::move(m)) {}
    ngi::Model model;
    int sanitized_inputs = 0;  // of the last blocking run
    bool last_was_enqueue = false;
};
struct ngi_buffer : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Buffer;
    explicit ngi_buffer(ngi::DeviceBuffer b) : buffer(std::move(b)) {}
    ngi::DeviceBuffer buffer;
};
struct ngi_pipeline : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Pipeline;
    ngi_pipeline(const ngi::Device& d, int n, ngi::GlobalViewMode m, ngi::LuminationTransfer t) : pipeline(d, n, m, t) {}
    ngi::SurroundPipeline pipeline;
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};
    ngi::ToneMapOptions tonemap;
};
struct ngi_display : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Display;
    ngi_display(const ngi::Device& d, int size, const ngi::DisplaySettings& s) : view(d, size, s) {}
    ngi::DisplayView view;
};
struct ngi_frame : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Frame;
    explicit ngi_frame(ngi::Frame f) : frame(std::move(f)) {}
    ngi::Frame frame;
};
struct ngi_ao : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Ao;
    explicit ngi_ao(ngi::AoNetwork a) : ao(std::move(a)) {}
    ngi::AoNetwork ao;
};
struct ngi_voxels : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Voxels;
    ngi_voxels(const ngi::Device& d, ngi::VoxelScene s, float h)
        : device(d), scene(std::move(s)), hours(h), lighting(ngi::lighting_at(h, scene.sun_azimuth)),
          voxels(ngi::surface_voxels(device, scene, lighting)), gi(device, voxels) {}
    ngi::Renderer& renderer() {  // uploads the scene at the first call that traces rays
        if (!renderer_) renderer_.emplace(device, scene);
        return *renderer_;
    }
    ngi::Device device;
    ngi::VoxelScene scene;
    float hours;
    ngi::Lighting lighting;
    ngi::SurfaceVoxels voxels;
    ngi::VoxelGi gi;
    std::optional<ngi::Renderer> renderer_;
};
struct ngi_neural_gi : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::NeuralGi;
    explicit ngi_neural_gi(const ngi::Device& d) : renderer(d) {}
    ngi::NeuralGiRenderer renderer;
};

namespace {

thread_local std::string g_last_error;
thread_local int g_last_cl_error = 0;
std::mutex g_callback_mutex;
ngi_error_callback g_callback = nullptr;
void* g_callback_user = nullptr;

// The handles alive now, by the value the application holds, with their types and objects. That value is not the
// object's address but a number never given out twice in the process (g_next_handle), so a released handle stays
// refused even when a new object is allocated at its old address (round three of reliability: with addresses, the
// first handle made after a release reused it, the stale handle then worked on the new object, and a second release
// destroyed it). A handle is looked up here before every use, so one released and used again is refused, and so is
// one of another type.
struct LiveHandle {
    HandleKind kind;
    ngi_handle* object;
};
std::mutex g_live_mutex;
std::unordered_map<const void*, LiveHandle> g_live;
// Handle values: multiples of 16 from 0x10000 (never NULL, never a small integer a bug might pass); 2^60 of them with
// 64-bit pointers (2^28 on a 32-bit build).
std::uintptr_t g_next_handle = 0x10000;

// A failure with its status, thrown inside a call and turned into the return value by guarded().
struct ApiError {
    ngi_status status;
    std::string message;
};

[[noreturn]] void fail(ngi_status status, const std::string& message) { throw ApiError{status, message}; }

// Registers a new object; returns the handle the application gets for it (an opaque value, never dereferenced).
template <class H>
H* track(H* h) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    const std::uintptr_t value = g_next_handle;
    g_next_handle += 16;
    H* handle = reinterpret_cast<H*>(value);
    g_live[static_cast<const void*>(handle)] = {H::kKind, h};
    return handle;
}

// The kind of live handle `h` (argument `arg`), checked to be H's: INVALID_HANDLE when it is NULL or not live,
// INVALID_ARGUMENT naming both types when it is another type's handle. Must be called with g_live_mutex held.
template <class H>
H* check_locked(const H* h, const char* arg) {
    const auto it = g_live.find(static_cast<const void*>(h));
    if (it == g_live.end())
        fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is not a live handle (released, or never created)");
    if (it->second.kind != H::kKind)
        fail(NGI_ERROR_INVALID_ARGUMENT, std::string(arg) + " is an " + kind_name(it->second.kind) +
                                             " handle, not an " + kind_name(H::kKind));
    return static_cast<H*>(it->second.object);
}

// The handle `h` (argument `arg` of the call) if it is alive and of type H, else an ApiError.
template <class H>
H& live(const H* h, const char* arg) {
    if (!h) fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is NULL");
    std::lock_guard<std::mutex> lock(g_live_mutex);
    return *check_locked(h, arg);
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
    if (!h) fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is NULL");
    // Under the lock: a concurrent last release cannot delete the object between the lookup and the increment.
    std::lock_guard<std::mutex> lock(g_live_mutex);
    check_locked(h, arg)->refs.fetch_add(1);
}

template <class H>
void release_handle(H* h, const char* arg) {
    if (!h) return;  // like free(NULL)
    H* object = nullptr;
    {
        std::lock_guard<std::mutex> lock(g_live_mutex);
        object = check_locked(h, arg);
        if (object->refs.fetch_sub(1) != 1) return;
        g_live.erase(static_cast<const void*>(h));
    }
    delete object;
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

// A host size argument `name` of `have` bytes where the call needs `need` for `what`: INVALID_ARGUMENT if smaller.
void require_bytes(std::size_t have, std::size_t need, const char* name, const std::string& what) {
    require(have >= need, std::string(name) + " is " + std::to_string(have) + ", " + what + " needs " +
                              std::to_string(need));
}

// A device buffer argument `name` that the call reads or writes `need` bytes of: INVALID_ARGUMENT if smaller.
void require_buffer(const ngi_buffer& b, std::size_t need, const char* name, const std::string& what) {
    require(b.buffer.bytes() >= need, std::string("the ") + name + " buffer holds " + std::to_string(b.buffer.bytes()) +
                                          " bytes, " + what + " needs " + std::to_string(need));
}

// The byte range [offset, offset + bytes) of a buffer of `size` bytes: INVALID_ARGUMENT when it reaches outside.
void require_range(std::size_t offset, std::size_t bytes, std::size_t size) {
    require(offset <= size && bytes <= size - offset,
            "bytes [" + std::to_string(offset) + ", " + std::to_string(offset) + " + " + std::to_string(bytes) +
                ") reach outside the buffer's " + std::to_string(size) + " bytes");
}

// Three finite floats (argument `name`).
glm::vec3 vec3_arg(const float* v, const char* name) {
    require(v, std::string(name) + " is NULL");
    for (int i = 0; i < 3; ++i)
        require(std::isfinite(v[i]), std::string(name) + "[" + std::to_string(i) + "] is not finite");
    return {v[0], v[1], v[2]};
}

// A camera's look and up: finite, look non-zero and not parallel to up.
void require_camera(glm::vec3 l, glm::vec3 u) {
    require(glm::length(l) > 0 && glm::length(glm::cross(l, u)) > 1e-6f * glm::length(l) * glm::length(u),
            "look must be non-zero and not parallel to up");
}

std::string face_string(int n, int faces) {
    return std::to_string(faces) + " face" + (faces == 1 ? "" : "s") + " of " + std::to_string(n) + " x " +
           std::to_string(n);
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
        std::size_t mem_size = 0;  // an invalid mem is left to the wrap, which names the CL error
        if (clGetMemObjectInfo(mem, CL_MEM_SIZE, sizeof mem_size, &mem_size, nullptr) == CL_SUCCESS)
            require_range(offset, bytes, mem_size);
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
        require_range(offset, bytes, b.buffer.bytes());
        b.buffer.upload(src, bytes, offset);
    });
}

ngi_status ngi_buffer_read(const ngi_buffer* buffer, size_t offset, void* dst, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi_buffer& b = live(buffer, "buffer");
        require(dst || bytes == 0, "dst is NULL");
        require_range(offset, bytes, b.buffer.bytes());
        b.buffer.download(dst, bytes, offset);
    });
}

ngi_status ngi_buffer_retain(ngi_buffer* buffer) { return guarded(__func__, [&] { retain_handle(buffer, "buffer"); }); }
ngi_status ngi_buffer_release(ngi_buffer* buffer) { return guarded(__func__, [&] { release_handle(buffer, "buffer"); }); }

// --- models ----------------------------------------------------------------------------------------------------

namespace {

// ngi_model_load and ngi_model_load_with_options, each reporting its own name: `path` is a file or a shipped model's
// name (ngi::resolve_model: $NGI_MODEL_PATH, the installed models, ...).
ngi_status load_model(const char* call, ngi_device* device, const char* path, ngi_bn_mode bn_mode, ngi_dropout dropout,
                      ngi_model** out) {
    return guarded(call, [&] {
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
        *out = track(new ngi_model(ngi::Model::load(d.device, ngi::resolve_model(path), options)));
    });
}

}  // namespace

ngi_status ngi_model_load_with_options(ngi_device* device, const char* path, ngi_bn_mode bn_mode, ngi_dropout dropout,
                                       ngi_model** out) {
    return load_model(__func__, device, path, bn_mode, dropout, out);
}

ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out) {
    return load_model(__func__, device, path, NGI_BN_FROM_FILE, NGI_DROPOUT_FROM_FILE, out);
}

ngi_status ngi_model_resolve(const char* name_or_path, char* buf, size_t size, size_t* needed) {
    return guarded(__func__, [&] {
        require(name_or_path, "name_or_path is NULL");
        copy_string(ngi::resolve_model(name_or_path), buf, size, needed);
    });
}

ngi_status ngi_device_warmup(ngi_device* device, ngi_model* model, int n, int display_size,
                             ngi_warmup_report* report) {
    return guarded(__func__, [&] {
        const ngi_device& d = live(device, "device");
        ngi_model& m = live(model, "model");
        const ngi::WarmUpReport r = ngi::warm_up(d.device, m.model, n, display_size);
        if (report) *report = ngi_warmup_report{r.programs_built, r.programs_from_cache, r.first_frame_ms,
                                                r.second_frame_ms};
    });
}

ngi_status ngi_program_cache_dir(char* buf, size_t size, size_t* needed) {
    return guarded(__func__, [&] { copy_string(ngi::program_cache_dir().string(), buf, size, needed); });
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
        // The loader admits exactly these three values (host/src/models/unet.cpp).
        *mode = c.output_mode == "indirect"        ? NGI_OUTPUT_INDIRECT
                : c.output_mode == "ssgi_residual" ? NGI_OUTPUT_SSGI_RESIDUAL
                                                   : NGI_OUTPUT_LIGHTMAP;
    });
}

namespace {
bool item_family(const ngi::ModelConfig& c) { return c.family == "mlp" || c.family == "voxel_sh"; }
}  // namespace

ngi_status ngi_model_family(const ngi_model* model, ngi_family* family) {
    return guarded(__func__, [&] {
        const std::string& f = live(model, "model").model.config().family;
        require(family, "family is NULL");
        static const std::pair<const char*, ngi_family> kFamilies[] = {
            {"pix2pix_unet", NGI_FAMILY_PIX2PIX_UNET}, {"deepillumination", NGI_FAMILY_DEEPILLUMINATION},
            {"mlp", NGI_FAMILY_MLP}, {"voxel_sh", NGI_FAMILY_VOXEL_SH}, {"neural_gi", NGI_FAMILY_NEURAL_GI},
            {"graph", NGI_FAMILY_GRAPH}};
        for (const auto& [name, value] : kFamilies)
            if (f == name) {
                *family = value;
                return;
            }
        fail(NGI_ERROR_INTERNAL, "the model's family '" + f + "' has no ngi_family value");
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
        ngi::RunInfo info;
        if (c.family == "voxel_sh") {
            // Model::run takes voxel_sh items by item, [V][10] -> [V][27]; this call's layout is planar, as
            // ngi_model_enqueue's: [10][V] -> [27][V].
            const std::size_t items = std::size_t(height) * std::size_t(width);
            require(items <= std::size_t(std::numeric_limits<int>::max()), "height x width is over 2^31 voxels");
            ngi::Tensor in({int(items), c.input_nc});
            for (std::size_t i = 0; i < items; ++i)
                for (int k = 0; k < c.input_nc; ++k) in.data[i * c.input_nc + k] = input[std::size_t(k) * items + i];
            const ngi::Tensor y = m.model.run(in, &info);
            for (std::size_t i = 0; i < items; ++i)
                for (int k = 0; k < c.output_nc; ++k) output[std::size_t(k) * items + i] = y.data[i * c.output_nc + k];
        } else {
            ngi::Tensor in({1, c.input_nc, height, width});
            std::memcpy(in.data.data(), input, in_need);
            const ngi::Tensor y = m.model.run(in, &info);
            std::memcpy(output, y.data.data(), out_need);
        }
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_model_run_items(ngi_model* model, const float* input, size_t input_bytes, int count, float* output,
                               size_t output_bytes) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        const auto& c = m.model.config();
        if (!item_family(c))
            fail(NGI_ERROR_INPUT, "the model's family is " + c.family +
                                      "; items are for the mlp and voxel_sh families (images: ngi_model_run)");
        require(input, "input is NULL");
        require(output, "output is NULL");
        require(count > 0, "count must be positive, got " + std::to_string(count));
        const std::size_t in_need = image_bytes(c.input_nc, count, 1), out_need = image_bytes(c.output_nc, count, 1);
        require_bytes(input_bytes, in_need, "input_bytes", std::to_string(count) + " items of " +
                                                               std::to_string(c.input_nc) + " floats");
        require_bytes(output_bytes, out_need, "output_bytes", std::to_string(count) + " items of " +
                                                                  std::to_string(c.output_nc) + " floats");
        ngi::Tensor in({count, c.input_nc});
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
        const auto& c = m.model.config();
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_buffer(in, image_bytes(c.input_nc, height, width), "input",
                       std::to_string(c.input_nc) + "x" + shape + " floats");
        require_buffer(out, image_bytes(c.output_nc, height, width), "output",
                       std::to_string(c.output_nc) + "x" + shape + " floats");
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

}  // namespace

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

namespace {
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

// --- display resolution ----------------------------------------------------------------------------------------

ngi_status ngi_display_new(ngi_device* device, int size, ngi_display_upsampler upsampler, int temporal,
                           ngi_display** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(upsampler == NGI_DISPLAY_JBU || upsampler == NGI_DISPLAY_BILINEAR,
                "upsampler " + std::to_string(int(upsampler)) + " is not an ngi_display_upsampler");
        ngi::DisplaySettings s;
        s.upsampler = upsampler == NGI_DISPLAY_JBU ? ngi::DisplayUpsampler::Jbu : ngi::DisplayUpsampler::Bilinear;
        s.temporal = temporal != 0;
        *out = track(new ngi_display(d.device, size, s));
    });
}

ngi_status ngi_display_reset(ngi_display* display) {
    return guarded(__func__, [&] { live(display, "display").view.reset(); });
}

ngi_status ngi_display_enqueue(ngi_display* display, int n, ngi_buffer* low_planes, ngi_buffer* low_lightmap,
                               ngi_buffer* display_planes, unsigned flags, const float position[3], const float look[3],
                               const float up[3], ngi_buffer* lightmap, ngi_buffer* final_image,
                               ngi_buffer* display_image) {
    return guarded(__func__, [&] {
        ngi_display& v = live(display, "display");
        require(position && look && up, "position, look and up must not be NULL");
        require((flags & ~unsigned(NGI_FRAME_EMISSION | NGI_FRAME_ENV)) == 0,
                "flags " + std::to_string(flags) + " are not ngi_frame_flags");
        require(lightmap || final_image || display_image, "lightmap, final_image and display_image are all NULL: "
                                                          "nothing to make");
        ngi::FrameDesc desc;
        desc.faces = 1;
        desc.has_emission = (flags & NGI_FRAME_EMISSION) != 0;
        desc.has_env = (flags & NGI_FRAME_ENV) != 0;
        desc.look = glm::vec3(look[0], look[1], look[2]);
        desc.up = glm::vec3(up[0], up[1], up[2]);
        ngi::FrameOutputs outs;
        if (lightmap) outs.lightmap = live(lightmap, "lightmap").buffer;
        if (final_image) outs.final_image = live(final_image, "final_image").buffer;
        if (display_image) outs.display = live(display_image, "display_image").buffer;
        v.view.enqueue(n, live(low_planes, "low_planes").buffer, live(low_lightmap, "low_lightmap").buffer,
                       live(display_planes, "display_planes").buffer, desc,
                       glm::vec3(position[0], position[1], position[2]), outs);
    });
}

ngi_status ngi_display_retain(ngi_display* display) { return guarded(__func__, [&] { retain_handle(display, "display"); }); }
ngi_status ngi_display_release(ngi_display* display) { return guarded(__func__, [&] { release_handle(display, "display"); }); }

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

// --- frames ----------------------------------------------------------------------------------------------------

namespace {

constexpr int kFirstPlane[ngi::kFeatureCount] = {0, 3, 6, 7, 10, 13};  // of each feature in a face's 16 planes

bool has_face(const ngi::Frame& f, int face) {
    const ngi::Image& d = f.get(ngi::Feature::Depth, ngi::Face(face));
    return d.width == f.n && d.height == f.n && f.n > 0;
}

int frame_faces(const ngi::Frame& f) {
    for (int face = 0; face < ngi::kFaceCount; ++face)
        if (!has_face(f, face)) return 1;
    return ngi::kFaceCount;
}

bool has_feature(const ngi::Frame& f, ngi::Feature k) { return !f.get(k, ngi::Face::Front).data.empty(); }

void require_faces(int faces) { require(faces == 1 || faces == 6, "faces must be 1 or 6, got " + std::to_string(faces)); }

void require_face_size(int n) {
    require(n >= 2 && n <= 2048, "n must be in 2..2048, got " + std::to_string(n));
}

const char* const kFaceNames[ngi::kFaceCount] = {"front", "back", "left", "right", "up", "down"};

}  // namespace

ngi_status ngi_frame_read(const char* folder, ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require(folder, "folder is NULL");
        *out = track(new ngi_frame(ngi::read_frame(folder)));
    });
}

ngi_status ngi_frame_from_planes(int n, const float* planes, size_t planes_bytes, int faces, unsigned flags,
                                 const float look[3], const float up[3], ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require_face_size(n);
        require_faces(faces);
        require((flags & ~unsigned(NGI_FRAME_EMISSION | NGI_FRAME_ENV)) == 0,
                "flags " + std::to_string(flags) + " holds bits that are not ngi_frame_flags");
        require(planes, "planes is NULL");
        require_bytes(planes_bytes, ngi::frame_planes_bytes(n, faces), "planes_bytes", face_string(n, faces));
        ngi::Frame f;
        f.n = n;
        f.look = vec3_arg(look, "look");
        f.up = vec3_arg(up, "up");
        require_camera(f.look, f.up);
        const std::size_t plane = std::size_t(n) * std::size_t(n);
        for (int face = 0; face < faces; ++face)
            for (int k = 0; k < ngi::kFeatureCount; ++k) {
                if (k == int(ngi::Feature::Emission) && !(flags & NGI_FRAME_EMISSION)) continue;
                if (k == int(ngi::Feature::Env) && !(flags & NGI_FRAME_ENV)) continue;
                const int c = ngi::feature_channels(ngi::Feature(k));
                ngi::Image im(n, n, c);
                std::memcpy(im.data.data(), planes + (std::size_t(face) * 16 + std::size_t(kFirstPlane[k])) * plane,
                            std::size_t(c) * plane * sizeof(float));
                f.faces[std::size_t(k)][std::size_t(face)] = std::move(im);
            }
        *out = track(new ngi_frame(std::move(f)));
    });
}

ngi_status ngi_frame_set_position(ngi_frame* frame, const float position[3]) {
    return guarded(__func__, [&] {
        ngi_frame& f = live(frame, "frame");
        f.frame.position = vec3_arg(position, "position");
    });
}

ngi_status ngi_frame_set_area_light(ngi_frame* frame, const float centre[3], const float half_u[3],
                                    const float half_v[3], const float radiance[3]) {
    return guarded(__func__, [&] {
        ngi_frame& f = live(frame, "frame");
        ngi::AreaLight light;
        light.centre = vec3_arg(centre, "centre");
        light.half_u = vec3_arg(half_u, "half_u");
        light.half_v = vec3_arg(half_v, "half_v");
        light.radiance = vec3_arg(radiance, "radiance");
        try {
            ngi::check_area_light(light, "-");
        } catch (const ngi::InputError& e) {  // the numbers are this call's arguments: "-: area light half_u ..."
            const std::string m = e.what();
            fail(NGI_ERROR_INVALID_ARGUMENT, m.rfind("-: ", 0) == 0 ? m.substr(3) : m);
        }
        if (light.enabled())
            f.frame.area_light = light;
        else
            f.frame.area_light.reset();
    });
}

ngi_status ngi_frame_info(const ngi_frame* frame, int* n, int* faces, unsigned* flags, int* has_position,
                          int* has_area_light) {
    return guarded(__func__, [&] {
        const ngi::Frame& f = live(frame, "frame").frame;
        if (n) *n = f.n;
        if (faces) *faces = frame_faces(f);
        if (flags)
            *flags = (has_feature(f, ngi::Feature::Emission) ? unsigned(NGI_FRAME_EMISSION) : 0u) |
                     (has_feature(f, ngi::Feature::Env) ? unsigned(NGI_FRAME_ENV) : 0u);
        if (has_position) *has_position = f.position.has_value();
        if (has_area_light) *has_area_light = f.area_light.has_value() && f.area_light->enabled();
    });
}

ngi_status ngi_frame_planes(const ngi_frame* frame, int faces, float* planes, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi::Frame& f = live(frame, "frame").frame;
        require_faces(faces);
        require(planes, "planes is NULL");
        require_bytes(bytes, ngi::frame_planes_bytes(f.n, faces), "bytes", face_string(f.n, faces));
        if (faces > frame_faces(f)) fail(NGI_ERROR_INPUT, "the frame holds the front face only, 6 faces were asked for");
        const std::vector<float> packed = ngi::pack_frame_planes(f, faces);
        std::memcpy(planes, packed.data(), packed.size() * sizeof(float));
    });
}

ngi_status ngi_frame_retain(ngi_frame* frame) { return guarded(__func__, [&] { retain_handle(frame, "frame"); }); }
ngi_status ngi_frame_release(ngi_frame* frame) { return guarded(__func__, [&] { release_handle(frame, "frame"); }); }

// --- ambient occlusion -----------------------------------------------------------------------------------------

namespace {
float ao_radius(float radius_px) {
    require(!std::isnan(radius_px) && radius_px < 1.0e6f, "radius_px " + std::to_string(radius_px) +
                                                              " is not a radius (negative = the trained one)");
    return radius_px < 0 ? -1.0f : radius_px;
}
}  // namespace

ngi_status ngi_ao_load(ngi_device* device, const char* path, ngi_ao** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(path, "path is NULL");
        *out = track(new ngi_ao(ngi::AoNetwork::load(d.device, path)));
    });
}

ngi_status ngi_ao_info(const ngi_ao* ao, float* trained_radius_px, int* trained_size, int* face_normals) {
    return guarded(__func__, [&] {
        const ngi::AoNetwork& a = live(ao, "ao").ao;
        if (trained_radius_px) *trained_radius_px = a.trained_radius_px();
        if (trained_size) *trained_size = a.trained_size();
        if (face_normals) *face_normals = a.normals() == "face";
    });
}

ngi_status ngi_ao_run(ngi_ao* ao, const float* normals, size_t normals_bytes, int height, int width, float radius_px,
                      float* result, size_t result_bytes) {
    return guarded(__func__, [&] {
        ngi_ao& a = live(ao, "ao");
        require(normals, "normals is NULL");
        require(result, "result is NULL");
        const float r = ao_radius(radius_px);
        const std::size_t in_need = image_bytes(3, height, width), out_need = image_bytes(1, height, width);
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_bytes(normals_bytes, in_need, "normals_bytes", "3x" + shape + " floats");
        require_bytes(result_bytes, out_need, "result_bytes", "1x" + shape + " floats");
        ngi::Image n(width, height, 3);
        std::memcpy(n.data.data(), normals, in_need);
        const ngi::Image y = a.ao.run(n, r);
        std::memcpy(result, y.data.data(), out_need);
    });
}

ngi_status ngi_ao_enqueue(ngi_ao* ao, ngi_buffer* normals, ngi_buffer* result, int height, int width, float radius_px) {
    return guarded(__func__, [&] {
        ngi_ao& a = live(ao, "ao");
        const ngi_buffer& in = live(normals, "normals");
        const ngi_buffer& out = live(result, "result");
        const float r = ao_radius(radius_px);
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_buffer(in, image_bytes(3, height, width), "normals", "3x" + shape + " floats");
        require_buffer(out, image_bytes(1, height, width), "result", "1x" + shape + " floats");
        a.ao.enqueue(in.buffer, out.buffer, height, width, r);
    });
}

ngi_status ngi_ao_retain(ngi_ao* ao) { return guarded(__func__, [&] { retain_handle(ao, "ao"); }); }
ngi_status ngi_ao_release(ngi_ao* ao) { return guarded(__func__, [&] { release_handle(ao, "ao"); }); }

// --- voxels: field, LTF, shading -------------------------------------------------------------------------------

namespace {
std::size_t voxel_bytes(const ngi_voxels& v, int per_voxel) {
    return v.voxels.size() * std::size_t(per_voxel) * sizeof(float);
}
std::string voxel_what(const ngi_voxels& v, int per_voxel) {
    return std::to_string(v.voxels.size()) + " voxels x " + std::to_string(per_voxel) + " floats";
}
void copy_voxels(float* dst, const std::vector<float>& src) {
    if (dst) std::memcpy(dst, src.data(), src.size() * sizeof(float));
}
}  // namespace

ngi_status ngi_voxels_new(ngi_device* device, const char* scene, float hours, ngi_voxels** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(scene, "scene is NULL");
        require(!std::isnan(hours) && hours <= 24.0f, "hours " + std::to_string(hours) +
                                                          " is not a time of day (0..24, negative = the scene's)");
        ngi::VoxelScene sc = ngi::make_scene(scene);
        const float h = hours < 0 ? sc.default_time : hours;
        *out = track(new ngi_voxels(d.device, std::move(sc), h));
    });
}

ngi_status ngi_voxels_info(const ngi_voxels* voxels, int* count, int grid[3], float* hours) {
    return guarded(__func__, [&] {
        const ngi_voxels& v = live(voxels, "voxels");
        if (count) *count = int(v.voxels.size());
        if (grid)
            for (int i = 0; i < 3; ++i) grid[i] = v.voxels.grid[i];
        if (hours) *hours = v.hours;
    });
}

ngi_status ngi_voxels_attributes(const ngi_voxels* voxels, float* attributes, size_t bytes) {
    return guarded(__func__, [&] {
        const ngi_voxels& v = live(voxels, "voxels");
        require(attributes, "attributes is NULL");
        require_bytes(bytes, voxel_bytes(v, ngi::kVoxelAttributes), "bytes", voxel_what(v, ngi::kVoxelAttributes));
        copy_voxels(attributes, v.voxels.attributes);
    });
}

ngi_status ngi_voxels_field(ngi_voxels* voxels, const ngi_voxel_field_settings* settings, float* sh, size_t sh_bytes,
                            float* direct, size_t direct_bytes, float* lighting, size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        require(sh || direct || lighting, "sh, direct and lighting are all NULL: nothing to make");
        if (sh) require_bytes(sh_bytes, voxel_bytes(v, 27), "sh_bytes", voxel_what(v, 27));
        if (direct) require_bytes(direct_bytes, voxel_bytes(v, 3), "direct_bytes", voxel_what(v, 3));
        if (lighting) require_bytes(lighting_bytes, voxel_bytes(v, 3), "lighting_bytes", voxel_what(v, 3));
        const ngi_voxel_field_settings defaults = NGI_VOXEL_FIELD_DEFAULTS;
        const ngi_voxel_field_settings& c = settings ? *settings : defaults;
        constexpr int kMax = 1 << 20;
        const int root = int(std::lround(std::sqrt(double(std::max(c.directions, 0)))));
        require(c.directions >= 1 && c.directions <= kMax && root * root == c.directions,
                "settings->directions " + std::to_string(c.directions) + " is not a perfect square in 1..2^20");
        require(c.sun_rays >= 1 && c.sun_rays <= kMax,
                "settings->sun_rays " + std::to_string(c.sun_rays) + " is not in 1..2^20");
        require(c.point_samples >= 1 && c.point_samples <= kMax,
                "settings->point_samples " + std::to_string(c.point_samples) + " is not in 1..2^20");
        require(c.max_bounces >= 0 && c.max_bounces <= 64,
                "settings->max_bounces " + std::to_string(c.max_bounces) + " is not in 0..64");
        require(c.rr_start >= 0, "settings->rr_start " + std::to_string(c.rr_start) + " is negative");
        ngi::VoxelFieldSettings s;
        s.directions = c.directions;
        s.sun_rays = c.sun_rays;
        s.point_samples = c.point_samples;
        s.max_bounces = c.max_bounces;
        s.rr_start = c.rr_start;
        s.seed = c.seed;
        const ngi::VoxelField f = v.renderer().render_voxel_field(v.voxels, v.lighting, s);
        copy_voxels(sh, f.sh);
        copy_voxels(direct, f.direct);
        copy_voxels(lighting, f.lighting);
    });
}

ngi_status ngi_voxels_predict_sh(ngi_voxels* voxels, ngi_model* model, float* sh, size_t sh_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        ngi_model& m = live(model, "model");
        require(sh, "sh is NULL");
        const ngi::ModelConfig& c = m.model.config();
        if (c.family != "voxel_sh") fail(NGI_ERROR_INPUT, "the model's family is " + c.family + ", not voxel_sh");
        c.voxel_sh.check_grid(v.voxels.grid.x, v.voxels.grid.y, v.voxels.grid.z);  // InputError naming both grids
        require_bytes(sh_bytes, voxel_bytes(v, 27), "sh_bytes", voxel_what(v, 27));
        ngi::Tensor in({int(v.voxels.size()), ngi::kVoxelAttributes});
        in.data = v.voxels.attributes;
        ngi::RunInfo info;
        const ngi::Tensor y = m.model.run(in, &info);
        copy_voxels(sh, y.data);
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_voxels_ltf(ngi_voxels* voxels, const float* direct, size_t direct_bytes, int bounces,
                          ngi_ltf_variant variant, int visibility, float* lighting, size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        require(direct, "direct is NULL");
        require(lighting, "lighting is NULL");
        require_bytes(direct_bytes, voxel_bytes(v, 3), "direct_bytes", voxel_what(v, 3));
        require_bytes(lighting_bytes, voxel_bytes(v, 3), "lighting_bytes", voxel_what(v, 3));
        require(bounces >= 0 && bounces <= 64, "bounces " + std::to_string(bounces) + " is not in 0..64");
        require(variant == NGI_LTF_PHYSICAL || variant == NGI_LTF_AS_WRITTEN,
                "variant " + std::to_string(int(variant)) + " is not an ngi_ltf_variant");
        require(visibility == 0 || visibility == 1, "visibility must be 0 or 1, got " + std::to_string(visibility));
        require(!visibility || variant == NGI_LTF_PHYSICAL,
                "visibility 1 needs NGI_LTF_PHYSICAL (the as-written LTF has no shadow term)");
        const std::vector<float> d(direct, direct + v.voxels.size() * 3);
        std::vector<std::uint32_t> mask;
        if (visibility) mask = v.renderer().voxel_visibility(v.voxels);
        copy_voxels(lighting, v.gi.ltf(d, bounces,
                                       variant == NGI_LTF_PHYSICAL ? ngi::LtfVariant::Physical : ngi::LtfVariant::AsWritten,
                                       visibility ? &mask : nullptr));
    });
}

ngi_status ngi_voxels_render_frame(ngi_voxels* voxels, const float position[3], const float look[3],
                                   const float up[3], int n, int feature_spp, unsigned seed, ngi_frame** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        ngi_voxels& v = live(voxels, "voxels");
        ngi::CameraPose pose;
        pose.position = vec3_arg(position, "position");
        pose.look = vec3_arg(look, "look");
        pose.up = vec3_arg(up, "up");
        require_camera(pose.look, pose.up);
        require_face_size(n);
        require(feature_spp >= 1 && feature_spp <= 65536, "feature_spp " + std::to_string(feature_spp) +
                                                               " is not in 1..65536");
        ngi::RenderSettings rs;
        rs.n = n;
        rs.feature_spp = feature_spp;
        rs.reference = false;
        rs.seed = seed;
        ngi::Frame f = v.renderer().render(pose, v.lighting, rs);
        f.position = pose.position;
        *out = track(new ngi_frame(std::move(f)));
    });
}

ngi_status ngi_voxels_shade(ngi_voxels* voxels, const ngi_frame* frame, const float camera_position[3], ngi_face face,
                            const float* field, size_t field_bytes, ngi_voxel_field_kind kind, float* lighting,
                            size_t lighting_bytes) {
    return guarded(__func__, [&] {
        ngi_voxels& v = live(voxels, "voxels");
        const ngi::Frame& f = live(frame, "frame").frame;
        require(int(face) >= 0 && int(face) < ngi::kFaceCount, "face " + std::to_string(int(face)) + " is not an ngi_face");
        require(kind == NGI_FIELD_SH || kind == NGI_FIELD_LIGHTING,
                "kind " + std::to_string(int(kind)) + " is not an ngi_voxel_field_kind");
        require(field, "field is NULL");
        require(lighting, "lighting is NULL");
        const int per_voxel = kind == NGI_FIELD_SH ? 27 : 3;
        require_bytes(field_bytes, voxel_bytes(v, per_voxel), "field_bytes", voxel_what(v, per_voxel));
        require_bytes(lighting_bytes, image_bytes(3, f.n, f.n), "lighting_bytes",
                      "a 3 x " + std::to_string(f.n) + " x " + std::to_string(f.n) + " image");
        glm::vec3 position;
        if (camera_position)
            position = vec3_arg(camera_position, "camera_position");
        else if (f.position)
            position = *f.position;
        else
            fail(NGI_ERROR_INPUT, "camera_position is NULL and the frame records no position");
        if (!has_face(f, int(face)))
            fail(NGI_ERROR_INPUT, std::string("the frame has no ") + kFaceNames[int(face)] + " face");
        const std::vector<float> values(field, field + v.voxels.size() * std::size_t(per_voxel));
        const ngi::Image im = v.gi.shade(f, position, ngi::Face(int(face)), values,
                                         kind == NGI_FIELD_SH ? ngi::VoxelFieldKind::Sh : ngi::VoxelFieldKind::Lighting);
        std::memcpy(lighting, im.data.data(), im.data.size() * sizeof(float));
    });
}

ngi_status ngi_voxels_retain(ngi_voxels* voxels) { return guarded(__func__, [&] { retain_handle(voxels, "voxels"); }); }
ngi_status ngi_voxels_release(ngi_voxels* voxels) { return guarded(__func__, [&] { release_handle(voxels, "voxels"); }); }

// --- Neural GI -------------------------------------------------------------------------------------------------

ngi_status ngi_neural_gi_new(ngi_device* device, ngi_neural_gi** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        *out = track(new ngi_neural_gi(live(device, "device").device));
    });
}

ngi_status ngi_neural_gi_run(ngi_neural_gi* renderer, ngi_model* model, const ngi_frame* frame, int upsample,
                             float* indirect, size_t indirect_bytes, float* lighting, size_t lighting_bytes,
                             int* sanitized_inputs) {
    return guarded(__func__, [&] {
        ngi_neural_gi& r = live(renderer, "renderer");
        ngi_model& m = live(model, "model");
        const ngi::Frame& f = live(frame, "frame").frame;
        require(indirect || lighting, "indirect and lighting are both NULL: nothing to make");
        const std::size_t need = image_bytes(3, f.n, f.n);
        const std::string what = "a 3 x " + std::to_string(f.n) + " x " + std::to_string(f.n) + " image";
        if (indirect) require_bytes(indirect_bytes, need, "indirect_bytes", what);
        if (lighting) require_bytes(lighting_bytes, need, "lighting_bytes", what);
        require(upsample >= 1 && upsample <= 64, "upsample " + std::to_string(upsample) + " is not in 1..64");
        ngi::NeuralGiOptions options;
        options.upsample = upsample;
        const ngi::NeuralGiImages out = r.renderer.run(m.model, f, options);
        if (indirect) std::memcpy(indirect, out.indirect.data.data(), need);
        if (lighting) std::memcpy(lighting, out.lighting.data.data(), need);
        // Every value replaced on the way in: NaN/Inf in the frame's features and the model guard's replacements.
        if (sanitized_inputs)
            *sanitized_inputs = int(std::min<std::size_t>(std::size_t(out.sanitized_inputs) + out.nonfinite_features,
                                                          std::size_t(INT_MAX)));
        m.sanitized_inputs = out.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_neural_gi_retain(ngi_neural_gi* renderer) {
    return guarded(__func__, [&] { retain_handle(renderer, "renderer"); });
}
ngi_status ngi_neural_gi_release(ngi_neural_gi* renderer) {
    return guarded(__func__, [&] { release_handle(renderer, "renderer"); });
}


}  // extern "C"

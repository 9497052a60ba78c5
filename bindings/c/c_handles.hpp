// What every file of the C ABI shares (private to libngi_c): the handles -- opaque, typed, reference-counted, checked
// against a registry of live handles and their types -- the call wrapper that turns exceptions into status codes and
// the thread-local last error, and the argument checks and conversions more than one area uses. The rules:
// bindings/c/README.md. The entry points are in c_<area>.cpp: one file per family of handles (c_device.cpp holds
// devices and buffers), plus c_files.cpp (files without a handle) and c_errors.cpp (version, status names, the last
// error and the error callback); the registry itself in c_handles.cpp.
#pragma once
#include "ngi.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <utility>

#include "ngi/ao.hpp"
#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/display.hpp"
#include "ngi/error.hpp"
#include "ngi/image.hpp"
#include "ngi/model.hpp"
#include "ngi/neural_gi.hpp"
#include "ngi/pipeline.hpp"
#include "ngi/scene_voxels.hpp"

// The type of a handle: its tag in the registry of live handles, checked by every call before the handle is used.
enum class HandleKind { Device, Buffer, Model, Pipeline, Display, Frame, Ao, Voxels, NeuralGi };

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
    explicit ngi_voxels(ngi::SceneVoxels v) : voxels(std::move(v)) {}
    ngi::SceneVoxels voxels;
};
struct ngi_neural_gi : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::NeuralGi;
    explicit ngi_neural_gi(const ngi::Device& d) : renderer(d) {}
    ngi::NeuralGiRenderer renderer;
};

namespace c_abi {

inline const char* kind_name(HandleKind k) {
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

// A failure with its status, thrown inside a call and turned into the return value by guarded().
struct ApiError {
    ngi_status status;
    std::string message;
};

[[noreturn]] inline void fail(ngi_status status, const std::string& message) { throw ApiError{status, message}; }

// The registry of the handles alive now (c_handles.cpp; its table, lock and counter are private to that file), by
// the value the application holds, with their types and objects. That value is not the object's address but a
// number never given out twice in the process, so a released handle stays refused even when a new object is
// allocated at its old address (round three of reliability: with addresses, the first handle made after a release
// reused it, the stale handle then worked on the new object, and a second release destroyed it). A handle is looked
// up here before every use, so one released and used again is refused, and so is one of another type. Handle
// values: multiples of 16 from 0x10000 (never NULL, never a small integer a bug might pass); 2^60 of them with
// 64-bit pointers, 2^28 on a 32-bit build. They are never reused: once all are given out, creating a handle fails
// with NGI_ERROR_OUT_OF_MEMORY (the counter does not wrap to 0 and start again).

// Registers `object` (of type `kind`) and returns its handle value. ApiError when no handle value is left,
// std::bad_alloc when the table cannot grow; either way nothing is registered and the caller still owns `object`.
const void* register_handle(HandleKind kind, ngi_handle* object);
// The object of live handle `h` (argument `arg`), checked to be of type `kind`: INVALID_HANDLE when it is not live,
// INVALID_ARGUMENT naming both types when it is another type's handle.
ngi_handle* find_handle(const void* h, HandleKind kind, const char* arg);
// Checked as find_handle, then one more reference (under the registry's lock: a concurrent last release cannot
// delete the object between the lookup and the increment).
void retain_registered(const void* h, HandleKind kind, const char* arg);
// Checked as find_handle, then one reference less; on the last one the handle is unregistered and its object
// returned for the caller to delete (outside the lock), else nullptr. A refused release releases nothing.
ngi_handle* release_registered(const void* h, HandleKind kind, const char* arg);

// Registers a new object; returns the handle the application gets for it (an opaque value, never dereferenced).
// The object is the registry's only once registered: if registering throws, `h` deletes it (and what it holds,
// device memory included) on the way out.
template <class H>
H* track(std::unique_ptr<H> h) {
    H* handle = static_cast<H*>(const_cast<void*>(register_handle(H::kKind, h.get())));
    h.release();
    return handle;
}

// The handle `h` (argument `arg` of the call) if it is alive and of type H, else an ApiError.
template <class H>
H& live(const H* h, const char* arg) {
    if (!h) fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is NULL");
    return *static_cast<H*>(find_handle(h, H::kKind, arg));
}

template <class H>
void retain_handle(H* h, const char* arg) {
    if (!h) fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is NULL");
    retain_registered(h, H::kKind, arg);
}

template <class H>
void release_handle(H* h, const char* arg) {
    if (!h) return;  // like free(NULL)
    delete static_cast<H*>(release_registered(h, H::kKind, arg));
}

// The last error and the error callback (c_errors.cpp).
void reset_last_error() noexcept;          // a call begins: "" and no CL error
void set_last_cl_error(int code) noexcept;  // the code ngi_last_cl_error() returns
// Sets the thread's last error to "<call>: <message>" and calls the error callback.
void report(const char* call, ngi_status status, const std::string& message);
bool is_out_of_memory(int cl_error);  // the CL codes reported as NGI_ERROR_OUT_OF_MEMORY

// Runs f for C entry point `call`: the last error is reset first; every exception becomes a status and a message.
template <class F>
ngi_status guarded(const char* call, F&& f) noexcept {
    reset_last_error();
    ngi_status status = NGI_OK;
    std::string message;
    try {
        f();
        return NGI_OK;
    } catch (const ApiError& e) {
        status = e.status;
        message = e.message;
    } catch (const ngi::ClError& e) {
        set_last_cl_error(e.code());
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

// --- argument checks and conversions of more than one area ------------------------------------------------------

inline void require(bool ok, const std::string& what) {
    if (!ok) fail(NGI_ERROR_INVALID_ARGUMENT, what);
}

// A string result: `s` into `buf` of `size` bytes (truncated with an error when it does not fit), its size in *needed.
inline void copy_string(const std::string& s, char* buf, std::size_t size, std::size_t* needed) {
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

// Bytes of a c x h x w float image, or an error when it does not fit in size_t.
inline std::size_t image_bytes(int c, int h, int w) {
    require(h > 0 && w > 0, "height and width must be positive, got " + std::to_string(h) + "x" + std::to_string(w));
    const std::size_t n = std::size_t(c) * std::size_t(h) * std::size_t(w);
    require(n / std::size_t(h) / std::size_t(w) == std::size_t(c) &&
                n <= std::numeric_limits<std::size_t>::max() / sizeof(float),
            "height x width overflows");
    return n * sizeof(float);
}

// A host size argument `name` of `have` bytes where the call needs `need` for `what`: INVALID_ARGUMENT if smaller.
inline void require_bytes(std::size_t have, std::size_t need, const char* name, const std::string& what) {
    require(have >= need, std::string(name) + " is " + std::to_string(have) + ", " + what + " needs " +
                              std::to_string(need));
}

// A device buffer argument `name` that the call reads or writes `need` bytes of: INVALID_ARGUMENT if smaller.
inline void require_buffer(const ngi_buffer& b, std::size_t need, const char* name, const std::string& what) {
    require(b.buffer.bytes() >= need, std::string("the ") + name + " buffer holds " + std::to_string(b.buffer.bytes()) +
                                          " bytes, " + what + " needs " + std::to_string(need));
}

// Three finite floats (argument `name`).
inline glm::vec3 vec3_arg(const float* v, const char* name) {
    require(v, std::string(name) + " is NULL");
    for (int i = 0; i < 3; ++i)
        require(std::isfinite(v[i]), std::string(name) + "[" + std::to_string(i) + "] is not finite");
    return {v[0], v[1], v[2]};
}

// A camera's look and up: finite, look non-zero and not parallel to up.
inline void require_camera(glm::vec3 l, glm::vec3 u) {
    require(glm::length(l) > 0 && glm::length(glm::cross(l, u)) > 1e-6f * glm::length(l) * glm::length(u),
            "look must be non-zero and not parallel to up");
}

// The face size of a frame the call makes.
inline void require_face_size(int n) {
    require(n >= 2 && n <= 2048, "n must be in 2..2048, got " + std::to_string(n));
}

// "6 faces of 64 x 64": what a frame's planes hold, for size messages.
inline std::string face_string(int n, int faces) {
    return std::to_string(faces) + " face" + (faces == 1 ? "" : "s") + " of " + std::to_string(n) + " x " +
           std::to_string(n);
}

}  // namespace c_abi

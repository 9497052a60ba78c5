// OpenCL context, queue, program cache and small RAII handles. Library-internal.
#pragma once
#include <CL/cl.h>

#include <cstddef>
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "ngi/device.hpp"
#include "ngi/error.hpp"

namespace ngi::detail {

// Throws ClError naming the operation and the OpenCL call when err != CL_SUCCESS.
inline void check(cl_int err, const char* operation, const char* call, const std::string& detail = "") {
    if (err != CL_SUCCESS) throw ClError(operation, call, err, detail);
}

// A device buffer (RAII). Size in bytes.
class Buffer {
public:
    Buffer() = default;
    Buffer(cl_mem m, std::size_t bytes) : mem_(m), bytes_(bytes) {}
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    Buffer(Buffer&& o) noexcept : mem_(std::exchange(o.mem_, nullptr)), bytes_(std::exchange(o.bytes_, 0)) {}
    Buffer& operator=(Buffer&& o) noexcept {
        if (this != &o) { reset(); mem_ = std::exchange(o.mem_, nullptr); bytes_ = std::exchange(o.bytes_, 0); }
        return *this;
    }
    ~Buffer() { reset(); }
    void reset() { if (mem_) clReleaseMemObject(mem_); mem_ = nullptr; bytes_ = 0; }
    cl_mem get() const { return mem_; }
    std::size_t bytes() const { return bytes_; }
    explicit operator bool() const { return mem_ != nullptr; }

private:
    cl_mem mem_ = nullptr;
    std::size_t bytes_ = 0;
};

// A kernel with typed argument setting: k.args(a, b, c) then ctx.launch(k, ...).
class Kernel {
public:
    Kernel() = default;
    // max_work_group: CL_KERNEL_WORK_GROUP_SIZE of the compiled kernel on its device; fixed_local: the kernel's
    // work-group shape is part of its algorithm (reqd_work_group_size or local memory sized for it).
    Kernel(cl_kernel k, std::string name, std::size_t max_work_group = SIZE_MAX, bool fixed_local = false)
        : k_(k), name_(std::move(name)), max_wg_(max_work_group), fixed_local_(fixed_local) {}
    Kernel(const Kernel&) = delete;
    Kernel& operator=(const Kernel&) = delete;
    Kernel(Kernel&& o) noexcept
        : k_(std::exchange(o.k_, nullptr)), name_(std::move(o.name_)), max_wg_(o.max_wg_), fixed_local_(o.fixed_local_) {}
    Kernel& operator=(Kernel&& o) noexcept {
        if (this != &o) {
            if (k_) clReleaseKernel(k_);
            k_ = std::exchange(o.k_, nullptr);
            name_ = std::move(o.name_);
            max_wg_ = o.max_wg_;
            fixed_local_ = o.fixed_local_;
        }
        return *this;
    }
    ~Kernel() { if (k_) clReleaseKernel(k_); }
    cl_kernel get() const { return k_; }
    const std::string& name() const { return name_; }
    std::size_t max_work_group() const { return max_wg_; }
    bool fixed_local() const { return fixed_local_; }
    // Lowers the work-group limit, as a device with fewer resources would report (tests of the launch fallback).
    void limit_work_group(std::size_t n) { max_wg_ = std::min(max_wg_, n); }

    template <class... Args>
    Kernel& args(const Args&... a) {
        cl_uint i = 0;
        (set(i++, a), ...);
        return *this;
    }

private:
    void set(cl_uint i, const Buffer& b) { cl_mem m = b.get(); set_raw(i, sizeof(cl_mem), &m); }
    void set(cl_uint i, cl_mem m) { set_raw(i, sizeof(cl_mem), &m); }
    template <class T>
    void set(cl_uint i, const T& v) {
        static_assert(std::is_arithmetic_v<T>, "kernel arguments are buffers or scalars");
        set_raw(i, sizeof(T), &v);
    }
    void set_raw(cl_uint i, std::size_t size, const void* p) {
        check(clSetKernelArg(k_, i, size, p), ("set argument " + std::to_string(i) + " of kernel " + name_).c_str(),
              "clSetKernelArg");
    }
    cl_kernel k_ = nullptr;
    std::string name_;
    std::size_t max_wg_ = SIZE_MAX;
    bool fixed_local_ = false;
};

class Context {
public:
    Context(cl_platform_id platform, cl_device_id device, DeviceInfo info, DeviceOptions options);
    // Interop: runs on the application's context, device and in-order queue. All three are retained here and
    // released by the destructor; what the application created stays the application's.
    Context(cl_context context, cl_device_id device, cl_command_queue queue);
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    const DeviceInfo& info() const { return info_; }
    const DeviceOptions& options() const { return options_; }
    cl_context context() const { return context_; }
    cl_command_queue queue() const { return queue_; }
    cl_device_id device() const { return device_; }

    // Builds (once per process, and once per device+driver+source+options on disk) the program `program` (its
    // kernels/*.cl files: runtime/programs.cpp) with `defines` as build options ("-DMWG=64 ..."), and returns a
    // new kernel object for `kernel`. Kernel objects are cheap; keep them in the op that uses them.
    Kernel kernel(const std::string& program, const std::string& kernel, const std::string& defines = "");

    // Hex key of (platform, device, driver, options, source of every file) of `program` built with `defines`: the
    // key of the program cache, reused by anything cached per compiled variant (e.g. the GEMM self-check verdicts).
    std::string variant_key(const std::string& program, const std::string& defines) const;

    // Per-device state computed once and shared by every user of this context (e.g. the GEMM self-check): the
    // first call for `key` runs make(), later calls return the same object.
    template <class T>
    T& attached(const std::string& key, const std::function<T()>& make) {
        std::lock_guard<std::mutex> lock(attached_mutex_);
        auto it = attached_.find(key);
        if (it == attached_.end()) it = attached_.emplace(key, std::make_shared<T>(make())).first;
        return *static_cast<T*>(it->second.get());
    }

    // Loop iterations one work-item may run before the driver silently ends every loop of the kernel, measured
    // once per context by a probe kernel: 0 = no limit seen (PoCL, GPUs); 65535 on Mesa llvmpipe (gallivm's
    // LP_MAX_TGSI_LOOP_ITERATIONS). Ops whose loops grow with the problem split work to stay below it.
    long loop_limit();

    Buffer alloc(std::size_t bytes, const char* what);
    // A new buffer of `bytes` whose whole contents fill(dst) writes, through a host mapping
    // (CL_MAP_WRITE_INVALIDATE_REGION): where device memory is host memory (CPU drivers) fill writes the buffer
    // itself, so there is no staging copy and each page is touched once. Packed weights take this way: a host
    // vector, then clEnqueueWriteBuffer, touched 80 MB of fresh pages for the ngf 32 rung's 40 MB (page faults
    // were a third of `ngi lightmap`'s samples). Counted as one upload. fill must write every byte it needs.
    Buffer upload_in_place(std::size_t bytes, const char* what, const std::function<void(void* dst)>& fill);
    // The same into the first `bytes` of an existing buffer (its old contents there are lost): no host copy, e.g.
    // for host images packed into a staging buffer each frame.
    void write_in_place(const Buffer& b, std::size_t bytes, const char* what, const std::function<void(void* dst)>& fill);
    // Host <-> device transfers (blocking, counted in transfers()); copy() stays on the device (not counted).
    void write(const Buffer& b, std::size_t offset_bytes, std::size_t bytes, const void* src, const char* what);
    void read(const Buffer& b, std::size_t offset_bytes, std::size_t bytes, void* dst, const char* what);
    void fill_zero(const Buffer& b, std::size_t offset_bytes, std::size_t bytes, const char* what);
    void copy(cl_mem src, std::size_t src_offset, cl_mem dst, std::size_t dst_offset, std::size_t bytes,
              const char* what);
    // Every host <-> device transfer of this context since it was created (write/read and their wrappers).
    HostTransfers transfers() const;
    // Programs this context compiled from source (and offered to the disk cache) and loaded from the disk cache since
    // it was created (ngi::warm_up reports them: a warmed cache builds none).
    struct ProgramCounts {
        int built = 0, from_cache = 0;
    };
    ProgramCounts program_counts() const { return {programs_built_.load(), programs_from_cache_.load()}; }

    // Enqueues an NDRange. global is rounded up to a multiple of local (kernels guard their bounds). A local size
    // beyond the compiled kernel's CL_KERNEL_WORK_GROUP_SIZE (registers, driver limits) is halved until it fits,
    // for kernels whose work-group shape is free; fixed-shape kernels launch as they are (see context.cpp).
    // Returns the event when `want_event` (profiling), else nullptr.
    cl_event launch(const Kernel& k, int dims, const std::size_t* global, const std::size_t* local,
                    bool want_event = false);
    void finish();

private:
    cl_program program(const std::string& program, const std::string& defines);
    // True when a host store of [off, off + bytes) must be done by a kernel (kernels/transfer.cl): on Oclgrind,
    // whose uninitialized-value checker loses track of host stores that do not cover a whole buffer.
    bool host_stores_via_kernels(std::size_t off, std::size_t bytes) const;
    // "-cl-std=CL1.2 <defines>", plus -cl-opt-disable on Oclgrind (see context.cpp).
    std::string build_options(const std::string& defines) const;

    cl_platform_id platform_ = nullptr;
    cl_device_id device_ = nullptr;
    DeviceInfo info_;
    DeviceOptions options_;
    cl_context context_ = nullptr;
    cl_command_queue queue_ = nullptr;
    std::mutex programs_mutex_;                   // guards programs_ (builds run under it: see program())
    std::map<std::string, cl_program> programs_;  // key: program + '\n' + defines
    std::mutex attached_mutex_;
    std::map<std::string, std::shared_ptr<void>> attached_;
    long loop_limit_ = -1;  // -1 = not probed yet
    bool retained_device_ = false;  // interop: the application's device was retained here
    std::atomic<long long> uploads_{0}, downloads_{0}, upload_bytes_{0}, download_bytes_{0};
    std::atomic<int> programs_built_{0}, programs_from_cache_{0};
};

// The context behind a Device (library internals only: the public header keeps it opaque).
Context& context_of(const Device& device);
std::shared_ptr<Context> shared_context_of(const Device& device);

// Where compiled programs and per-device verdicts are cached: $NGI_CACHE_DIR, else $XDG_CACHE_HOME/ngi, else
// ~/.cache/ngi, else a temporary folder.
std::filesystem::path cache_dir();

// Writes `bytes` to `path` through a unique temporary and a rename; a cache that cannot be written is not an error.
void write_cache_file(const std::filesystem::path& path, const std::string& bytes);

// Makes `b` at least `bytes` large; returns true when it had to (re)allocate (contents not kept). The old buffer is
// released first, so growing never holds both.
inline bool ensure_buffer(Context& ctx, Buffer& b, std::size_t bytes, const char* what) {
    if (b.bytes() >= bytes) return false;
    b.reset();
    b = ctx.alloc(bytes, what);
    return true;
}

// A new buffer holding `v` (at least one float, so an empty vector still gives a valid cl_mem).
Buffer upload_floats(Context& ctx, const std::vector<float>& v, const char* what);

inline std::size_t round_up(std::size_t x, std::size_t m) { return (x + m - 1) / m * m; }

}  // namespace ngi::detail

#include "runtime/context.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "base/file_util.hpp"
#include "ngi/host_memory.hpp"
#include "runtime/programs.hpp"

namespace ngi {
namespace detail {
namespace {

std::string device_string(cl_device_id d, cl_device_info what) {
    std::size_t n = 0;
    check(clGetDeviceInfo(d, what, 0, nullptr, &n), "query device", "clGetDeviceInfo");
    std::string s(n, '\0');
    check(clGetDeviceInfo(d, what, n, s.data(), nullptr), "query device", "clGetDeviceInfo");
    while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
    return s;
}

template <class T>
T device_value(cl_device_id d, cl_device_info what) {
    T v{};
    check(clGetDeviceInfo(d, what, sizeof(T), &v, nullptr), "query device", "clGetDeviceInfo");
    return v;
}

std::string platform_string(cl_platform_id p, cl_platform_info what) {
    std::size_t n = 0;
    check(clGetPlatformInfo(p, what, 0, nullptr, &n), "query platform", "clGetPlatformInfo");
    std::string s(n, '\0');
    check(clGetPlatformInfo(p, what, n, s.data(), nullptr), "query platform", "clGetPlatformInfo");
    while (!s.empty() && s.back() == '\0') s.pop_back();
    return s;
}

std::vector<cl_platform_id> platforms() {
    cl_uint n = 0;
    cl_int err = clGetPlatformIDs(0, nullptr, &n);
    if (err == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || n == 0) return {};
    check(err, "list OpenCL platforms", "clGetPlatformIDs");
    std::vector<cl_platform_id> p(n);
    check(clGetPlatformIDs(n, p.data(), nullptr), "list OpenCL platforms", "clGetPlatformIDs");
    return p;
}

std::vector<cl_device_id> devices_of(cl_platform_id p) {
    cl_uint n = 0;
    cl_int err = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &n);
    if (err == CL_DEVICE_NOT_FOUND || n == 0) return {};
    check(err, "list OpenCL devices", "clGetDeviceIDs");
    std::vector<cl_device_id> d(n);
    check(clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, n, d.data(), nullptr), "list OpenCL devices", "clGetDeviceIDs");
    return d;
}

DeviceInfo describe(cl_platform_id p, cl_device_id d, int pi, int di) {
    DeviceInfo info;
    info.platform_index = pi;
    info.device_index = di;
    info.platform_name = platform_string(p, CL_PLATFORM_NAME);
    info.name = device_string(d, CL_DEVICE_NAME);
    info.vendor = device_string(d, CL_DEVICE_VENDOR);
    info.driver_version = device_string(d, CL_DRIVER_VERSION);
    info.device_version = device_string(d, CL_DEVICE_VERSION);
    info.opencl_c_version = device_string(d, CL_DEVICE_OPENCL_C_VERSION);
    info.extensions = device_string(d, CL_DEVICE_EXTENSIONS);
    auto type = device_value<cl_device_type>(d, CL_DEVICE_TYPE);
    info.is_gpu = (type & CL_DEVICE_TYPE_GPU) != 0;
    info.is_cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    info.fp16 = info.extensions.find("cl_khr_fp16") != std::string::npos;
    info.local_mem_bytes = device_value<cl_ulong>(d, CL_DEVICE_LOCAL_MEM_SIZE);
    info.local_mem_is_dedicated = device_value<cl_device_local_mem_type>(d, CL_DEVICE_LOCAL_MEM_TYPE) == CL_LOCAL;
    info.global_mem_bytes = device_value<cl_ulong>(d, CL_DEVICE_GLOBAL_MEM_SIZE);
    info.max_alloc_bytes = device_value<cl_ulong>(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
    info.max_work_group_size = device_value<std::size_t>(d, CL_DEVICE_MAX_WORK_GROUP_SIZE);
    info.compute_units = device_value<cl_uint>(d, CL_DEVICE_MAX_COMPUTE_UNITS);
    info.native_float_vector_width = device_value<cl_uint>(d, CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT);
    return info;
}

// FNV-1a 64: stable across runs and platforms (std::hash is not), good enough to key a cache.
std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : s) { h ^= c; h *= 1099511628211ull; }
    return h;
}

std::string build_log(cl_program prog, cl_device_id dev) {
    std::size_t n = 0;
    if (clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n) != CL_SUCCESS) return "";
    std::string log(n, '\0');
    clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
    while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
    return log;
}

}  // namespace

std::filesystem::path cache_dir() {
    if (const char* d = std::getenv("NGI_CACHE_DIR"); d && *d) return d;
    // The XDG base directory spec: a relative XDG_CACHE_HOME is invalid and ignored (it would name a folder under
    // whatever the current directory is); a relative HOME likewise (ngi_train.ngi_paths.user_cache_dir agrees).
    const auto absolute = [](const char* d) { return d && *d && std::filesystem::path(d).is_absolute(); };
    if (const char* d = std::getenv("XDG_CACHE_HOME"); absolute(d)) return std::filesystem::path(d) / "ngi";
    if (const char* d = std::getenv("HOME"); absolute(d)) return std::filesystem::path(d) / ".cache" / "ngi";
    return std::filesystem::temp_directory_path() / "ngi-cache";
}

void write_cache_file(const std::filesystem::path& path, const std::string& bytes) {
    static std::atomic<unsigned> counter{0};
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    const auto tmp = path.string() + ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    if (std::ofstream out{tmp, std::ios::binary}; out.write(bytes.data(), std::streamsize(bytes.size()))) {
        out.close();
        if (out) std::filesystem::rename(tmp, path, ec);
    }
    std::filesystem::remove(tmp, ec);
}

Context::Context(cl_platform_id platform, cl_device_id device, DeviceInfo info, DeviceOptions options)
    : platform_(platform), device_(device), info_(std::move(info)), options_(options) {
    cl_int err = CL_SUCCESS;
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(platform_), 0};
    context_ = clCreateContext(props, 1, &device_, nullptr, nullptr, &err);
    check(err, ("create context on " + info_.name).c_str(), "clCreateContext");
    cl_command_queue_properties qp = options_.profiling ? CL_QUEUE_PROFILING_ENABLE : 0;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    queue_ = clCreateCommandQueue(context_, device_, qp, &err);  // OpenCL 1.2 entry point: works everywhere
#pragma GCC diagnostic pop
    if (err != CL_SUCCESS) {
        clReleaseContext(context_);
        check(err, ("create queue on " + info_.name).c_str(), "clCreateCommandQueue");
    }
}

namespace {

// Indices of `device` in the platform/device enumeration ("P:D"), or -1 when it is not enumerated (a device
// handed in by an application that found it some other way).
std::pair<int, int> enumeration_index(cl_platform_id p, cl_device_id d) {
    const auto ps = platforms();
    for (std::size_t pi = 0; pi < ps.size(); ++pi) {
        if (ps[pi] != p) continue;
        const auto ds = devices_of(ps[pi]);
        for (std::size_t di = 0; di < ds.size(); ++di)
            if (ds[di] == d) return {int(pi), int(di)};
    }
    return {-1, -1};
}

}  // namespace

Context::Context(cl_context context, cl_device_id device, cl_command_queue queue) {
    const char* op = "create a device from the application's OpenCL objects";
    if (!context || !device || !queue) throw InputError(std::string(op) + ": context, device and queue must not be NULL");
    // The context must hold the device; the queue must belong to both and run in order (ngi relies on the order of
    // its own commands, and an application's commands before and after ngi's stay ordered with them).
    cl_uint ndev = 0;
    check(clGetContextInfo(context, CL_CONTEXT_NUM_DEVICES, sizeof ndev, &ndev, nullptr), op, "clGetContextInfo");
    std::vector<cl_device_id> devs(ndev);
    check(clGetContextInfo(context, CL_CONTEXT_DEVICES, ndev * sizeof(cl_device_id), devs.data(), nullptr), op,
          "clGetContextInfo");
    if (std::find(devs.begin(), devs.end(), device) == devs.end())
        throw InputError(std::string(op) + ": the device is not one of the context's devices");
    cl_context qctx = nullptr;
    cl_device_id qdev = nullptr;
    cl_command_queue_properties qprops = 0;
    check(clGetCommandQueueInfo(queue, CL_QUEUE_CONTEXT, sizeof qctx, &qctx, nullptr), op, "clGetCommandQueueInfo");
    check(clGetCommandQueueInfo(queue, CL_QUEUE_DEVICE, sizeof qdev, &qdev, nullptr), op, "clGetCommandQueueInfo");
    check(clGetCommandQueueInfo(queue, CL_QUEUE_PROPERTIES, sizeof qprops, &qprops, nullptr), op,
          "clGetCommandQueueInfo");
    if (qctx != context) throw InputError(std::string(op) + ": the queue belongs to another context");
    if (qdev != device) throw InputError(std::string(op) + ": the queue belongs to another device of the context");
    if (qprops & CL_QUEUE_OUT_OF_ORDER_EXEC_MODE_ENABLE)
        throw InputError(std::string(op) + ": the queue executes out of order; ngi needs an in-order queue");
    check(clGetDeviceInfo(device, CL_DEVICE_PLATFORM, sizeof platform_, &platform_, nullptr), op, "clGetDeviceInfo");
    const auto [pi, di] = enumeration_index(platform_, device);
    info_ = describe(platform_, device, pi, di);
    options_.profiling = (qprops & CL_QUEUE_PROFILING_ENABLE) != 0;
    device_ = device;
    // Retained last: nothing above can throw after a retain (a throwing constructor runs no destructor).
    check(clRetainContext(context), op, "clRetainContext");
    context_ = context;
    if (cl_int err = clRetainCommandQueue(queue); err != CL_SUCCESS) {
        clReleaseContext(context_);
        check(err, op, "clRetainCommandQueue");
    }
    queue_ = queue;
    // Devices of OpenCL 1.2+ are retained like other objects; root devices ignore it (retain/release are no-ops).
    clRetainDevice(device_);
    retained_device_ = true;
}

Context::~Context() {
    for (auto& [k, p] : programs_) clReleaseProgram(p);
    if (queue_) { clFinish(queue_); clReleaseCommandQueue(queue_); }
    if (context_) clReleaseContext(context_);
    if (retained_device_) clReleaseDevice(device_);
}

cl_program Context::program(const std::string& name, const std::string& defines) {
    // One lock for the cache and the build: two threads asking for the same program build it once (and never race
    // on its cache file); different programs of one device build one after the other (a Device is shared by
    // threads, and a build is a one-time cost per process, usually served from the disk cache).
    std::lock_guard<std::mutex> lock(programs_mutex_);
    const std::string key = name + '\n' + defines;
    if (auto it = programs_.find(key); it != programs_.end()) return it->second;

    const std::string source = program_source(name);
    const std::string options = build_options(defines);
    const std::string op = "build program " + name + " [" + defines + "] for " + info_.name;
    const std::filesystem::path cached = cache_dir() / (name + "-" + variant_key(name, defines) + ".bin");

    cl_int err = CL_SUCCESS;
    cl_program prog = nullptr;
    // 1. A binary cached on disk by an earlier process (same device, driver, source and options).
    // Read by ngi's file rule (read_file): a FIFO or device in the cache folder must not block or exhaust memory.
    // Anything unreadable is a cache miss.
    std::string bin;
    try {
        bin = read_file(cached.string(), "read kernel cache");
    } catch (const InputError&) {
        bin.clear();
    }
    if (!bin.empty()) {
        const unsigned char* ptr = reinterpret_cast<const unsigned char*>(bin.data());
        std::size_t len = bin.size();
        cl_int status = CL_SUCCESS;
        prog = clCreateProgramWithBinary(context_, 1, &device_, &len, &ptr, &status, &err);
        if (err != CL_SUCCESS || status != CL_SUCCESS ||
            clBuildProgram(prog, 1, &device_, options.c_str(), nullptr, nullptr) != CL_SUCCESS) {
            if (prog) clReleaseProgram(prog);
            prog = nullptr;  // stale or foreign binary: rebuild from source below
        }
        if (prog) ++programs_from_cache_;
    }
    // 2. From the embedded source.
    if (!prog) {
        const char* s = source.c_str();
        std::size_t len = source.size();
        prog = clCreateProgramWithSource(context_, 1, &s, &len, &err);
        check(err, op.c_str(), "clCreateProgramWithSource");
        err = clBuildProgram(prog, 1, &device_, options.c_str(), nullptr, nullptr);
        if (err != CL_SUCCESS) {
            std::string log = build_log(prog, device_);
            clReleaseProgram(prog);
            throw ClError(op, "clBuildProgram", err, "build log:\n" + log);
        }
        ++programs_built_;
        // Store the binary for the next process; a cache we cannot write is not an error.
        std::size_t bin_size = 0;
        if (clGetProgramInfo(prog, CL_PROGRAM_BINARY_SIZES, sizeof bin_size, &bin_size, nullptr) == CL_SUCCESS &&
            bin_size > 0) {
            std::string bin(bin_size, '\0');
            unsigned char* ptr = reinterpret_cast<unsigned char*>(bin.data());
            if (clGetProgramInfo(prog, CL_PROGRAM_BINARIES, sizeof ptr, &ptr, nullptr) == CL_SUCCESS)
                write_cache_file(cached, bin);
        }
    }
    programs_.emplace(key, prog);
    return prog;
}

std::string Context::variant_key(const std::string& program, const std::string& defines) const {
    const std::string source = program_source(program);
    const std::uint64_t h = fnv1a(source, fnv1a(info_.platform_name + '\n' + info_.name + '\n' + info_.driver_version +
                                                 '\n' + info_.device_version + '\n' + build_options(defines)));
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
    return hex;
}

long Context::loop_limit() {
    std::lock_guard<std::mutex> lock(attached_mutex_);
    if (loop_limit_ >= 0) return loop_limit_;
    // 2^20 iterations, each reading memory so no compiler can fold the loop into a closed form.
    const int n = 1 << 20;
    Kernel k = kernel("probe", "count_loop_iterations");
    const int ones[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    Buffer in = alloc(sizeof ones, "loop probe input"), out = alloc(sizeof(int), "loop probe output");
    write(in, 0, sizeof ones, ones, "loop probe input");
    k.args(n, in, out);
    const std::size_t one = 1;
    launch(k, 1, &one, &one);
    int count = 0;
    read(out, 0, sizeof count, &count, "loop probe output");
    loop_limit_ = count >= n ? 0 : count;
    return loop_limit_;
}

Kernel Context::kernel(const std::string& program_name, const std::string& name, const std::string& defines) {
    cl_program prog = program(program_name, defines);
    cl_int err = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, name.c_str(), &err);
    check(err, ("create kernel " + name + " from program " + program_name).c_str(), "clCreateKernel");
    std::size_t max_wg = 0, reqd[3] = {0, 0, 0};
    cl_ulong local_mem = 0;
    const cl_int errs[3] = {
        clGetKernelWorkGroupInfo(k, device_, CL_KERNEL_WORK_GROUP_SIZE, sizeof max_wg, &max_wg, nullptr),
        clGetKernelWorkGroupInfo(k, device_, CL_KERNEL_COMPILE_WORK_GROUP_SIZE, sizeof reqd, reqd, nullptr),
        clGetKernelWorkGroupInfo(k, device_, CL_KERNEL_LOCAL_MEM_SIZE, sizeof local_mem, &local_mem, nullptr)};
    Kernel kernel(k, name, max_wg, reqd[0] != 0 || local_mem > 0);  // owns k: released if a check below throws
    for (cl_int e : errs) check(e, ("query work-group limits of kernel " + name).c_str(), "clGetKernelWorkGroupInfo");
    return kernel;
}

namespace {
// ngi's buffers on CPU devices, whose memory is host memory, are held in the host-memory ledger (ngi/host_memory.hpp;
// issue 51: the viewer at --n 2048 reached 15 GB, its network's tensor arena on PoCL, past NGI_HOST_MEMORY_LIMIT):
// held in Context::alloc, released by the runtime's destructor callback when the cl_mem is freed (after its last
// release, kernels done), so views and retained handles keep it held.
void CL_CALLBACK release_cpu_buffer(cl_mem, void* bytes) {
    detail::release_host_memory(reinterpret_cast<std::uintptr_t>(bytes));
}
}  // namespace

Buffer Context::alloc(std::size_t bytes, const char* what) {
    cl_int err = CL_SUCCESS;
    if (bytes == 0) bytes = 4;  // OpenCL forbids empty buffers; a 0-element tensor still needs a handle
    if (bytes > info_.max_alloc_bytes)
        throw OutOfMemoryError(std::string("allocate ") + what + ": " + std::to_string(bytes) + " bytes exceeds the device's " +
                    "CL_DEVICE_MAX_MEM_ALLOC_SIZE of " + std::to_string(info_.max_alloc_bytes));
    if (info_.is_cpu)
        detail::check_and_hold_host_memory(std::string("allocate ") + what + " on a CPU device (its memory is host memory)",
                                           bytes);
    cl_mem m = clCreateBuffer(context_, CL_MEM_READ_WRITE, bytes, nullptr, &err);
    if (err != CL_SUCCESS && info_.is_cpu) detail::release_host_memory(bytes);
    check(err, (std::string("allocate ") + what + " (" + std::to_string(bytes) + " bytes)").c_str(),
          "clCreateBuffer");
    Buffer b(m, bytes);
    if (info_.is_cpu &&
        clSetMemObjectDestructorCallback(m, release_cpu_buffer, reinterpret_cast<void*>(std::uintptr_t(bytes))) !=
            CL_SUCCESS)
        detail::release_host_memory(bytes);  // not held rather than never released
    if (info_.platform_name == "Oclgrind") {
        // Oclgrind 21.10's uninitialized-value checker gives a buffer shadow memory only at its first host store
        // or first kernel use, and keeps a released buffer's stale shadow for the next buffer with the same
        // index (false "uninitialized" reports, or kernel stores silently not tracked). One whole-buffer store
        // at creation gives every buffer a fresh shadow of its full size. The price: memory no one wrote reads
        // as initialized (zeros) on Oclgrind; private and local memory are still checked exactly.
        const std::vector<unsigned char> zeros(bytes, 0);
        check(clEnqueueWriteBuffer(queue_, m, CL_TRUE, 0, bytes, zeros.data(), 0, nullptr, nullptr),
              (std::string("clear ") + what).c_str(), "clEnqueueWriteBuffer");
    }
    return b;
}

Buffer upload_floats(Context& ctx, const std::vector<float>& v, const char* what) {
    Buffer b = ctx.alloc(std::max<std::size_t>(v.size(), 1) * sizeof(float), what);
    if (!v.empty()) ctx.write(b, 0, v.size() * sizeof(float), v.data(), what);
    return b;
}

Buffer Context::upload_in_place(std::size_t bytes, const char* what, const std::function<void(void* dst)>& fill) {
    Buffer b = alloc(bytes, what);
    write_in_place(b, bytes, what, fill);
    return b;
}

void Context::write_in_place(const Buffer& b, std::size_t bytes, const char* what,
                             const std::function<void(void* dst)>& fill) {
    if (bytes == 0) return;
    if (bytes > b.bytes())
        throw Error(std::string("write ") + what + ": " + std::to_string(bytes) + " bytes into a buffer of " +
                    std::to_string(b.bytes()));
    if (info_.platform_name == "Oclgrind") {  // its checker tracks host stores by write (see alloc): one whole store
        std::vector<unsigned char> host(bytes);
        fill(host.data());
        write(b, 0, bytes, host.data(), what);
        return;
    }
    cl_int err = CL_SUCCESS;
    void* dst = clEnqueueMapBuffer(queue_, b.get(), CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, bytes, 0, nullptr,
                                   nullptr, &err);
    check(err, (std::string("map ") + what + " for upload").c_str(), "clEnqueueMapBuffer");
    try {
        fill(dst);
    } catch (...) {
        clEnqueueUnmapMemObject(queue_, b.get(), dst, 0, nullptr, nullptr);
        clFinish(queue_);
        throw;
    }
    // The queue is in order: kernels enqueued later see the unmapped contents.
    check(clEnqueueUnmapMemObject(queue_, b.get(), dst, 0, nullptr, nullptr),
          (std::string("unmap ") + what + " after upload").c_str(), "clEnqueueUnmapMemObject");
    uploads_.fetch_add(1, std::memory_order_relaxed);
    upload_bytes_.fetch_add((long long)bytes, std::memory_order_relaxed);
}

std::string Context::build_options(const std::string& defines) const {
    // Oclgrind 21.10's uninitialized-value checker aborts the kernel ("Unsupported instruction: freeze") on the
    // `freeze` that LLVM's optimizer inserts when it splits a paired x / d and x % d (im2col, col2im, SSIM):
    // on Oclgrind, kernels are built unoptimized, which keeps the source's own operations.
    return "-cl-std=CL1.2 " + defines + (info_.platform_name == "Oclgrind" ? " -cl-opt-disable" : "");
}

bool Context::host_stores_via_kernels(std::size_t off, std::size_t bytes) const {
    // Oclgrind 21.10's uninitialized-value plugin forgets earlier uploads into a buffer at every host store
    // (see kernels/transfer.cl); its stores from kernels are exact. Word-aligned ranges only (every caller's).
    return info_.platform_name == "Oclgrind" && off % 4 == 0 && bytes % 4 == 0;
}

void Context::write(const Buffer& b, std::size_t off, std::size_t bytes, const void* src, const char* what) {
    if (bytes == 0) return;
    if ((off != 0 || bytes != b.bytes()) && host_stores_via_kernels(off, bytes)) {
        Buffer staging = alloc(bytes, what);
        write(staging, 0, bytes, src, what);  // a whole-buffer upload: its shadow is exact
        copy(staging.get(), 0, b.get(), off, bytes, what);  // by copy_words on Oclgrind, as every copy there
        finish();  // staging is released on return
        return;
    }
    check(clEnqueueWriteBuffer(queue_, b.get(), CL_TRUE, off, bytes, src, 0, nullptr, nullptr),
          (std::string("upload ") + what).c_str(), "clEnqueueWriteBuffer");
    uploads_.fetch_add(1, std::memory_order_relaxed);
    upload_bytes_.fetch_add((long long)bytes, std::memory_order_relaxed);
}

void Context::read(const Buffer& b, std::size_t off, std::size_t bytes, void* dst, const char* what) {
    if (bytes == 0) return;
    check(clEnqueueReadBuffer(queue_, b.get(), CL_TRUE, off, bytes, dst, 0, nullptr, nullptr),
          (std::string("download ") + what).c_str(), "clEnqueueReadBuffer");
    downloads_.fetch_add(1, std::memory_order_relaxed);
    download_bytes_.fetch_add((long long)bytes, std::memory_order_relaxed);
}

void Context::copy(cl_mem src, std::size_t src_off, cl_mem dst, std::size_t dst_off, std::size_t bytes,
                   const char* what) {
    if (bytes == 0) return;
    if (src_off % 4 == 0 && host_stores_via_kernels(dst_off, bytes)) {  // Oclgrind: see kernels/transfer.cl
        Kernel k = kernel("transfer", "copy_words");
        k.args(src, cl_ulong(src_off / 4), dst, cl_ulong(dst_off / 4), cl_ulong(bytes / 4));
        const std::size_t global = bytes / 4, local = 64;
        launch(k, 1, &global, &local);
        return;
    }
    check(clEnqueueCopyBuffer(queue_, src, dst, src_off, dst_off, bytes, 0, nullptr, nullptr),
          (std::string("copy ") + what).c_str(), "clEnqueueCopyBuffer");
}

HostTransfers Context::transfers() const {
    HostTransfers t;
    t.uploads = uploads_.load(std::memory_order_relaxed);
    t.downloads = downloads_.load(std::memory_order_relaxed);
    t.upload_bytes = upload_bytes_.load(std::memory_order_relaxed);
    t.download_bytes = download_bytes_.load(std::memory_order_relaxed);
    return t;
}

void Context::fill_zero(const Buffer& b, std::size_t off, std::size_t bytes, const char* what) {
    if (bytes == 0) return;
    if (host_stores_via_kernels(off, bytes)) {
        Kernel k = kernel("transfer", "zero_words");
        k.args(b, cl_ulong(off / 4), cl_ulong(bytes / 4));
        const std::size_t global = bytes / 4, local = 64;
        launch(k, 1, &global, &local);
        return;
    }
    const float zero = 0.0f;
    check(clEnqueueFillBuffer(queue_, b.get(), &zero, sizeof zero, off, bytes, 0, nullptr, nullptr),
          (std::string("clear ") + what).c_str(), "clEnqueueFillBuffer");
}

cl_event Context::launch(const Kernel& k, int dims, const std::size_t* global, const std::size_t* local,
                         bool want_event) {
    std::size_t g[3], l[3] = {1, 1, 1};
    std::size_t items = 1;
    for (int i = 0; i < dims; ++i) {
        if (global[i] == 0) return nullptr;  // empty NDRange: nothing to do
        if (local) items *= (l[i] = local[i]);
    }
    // Free-shape kernels shrink to the compiled kernel's limit. Fixed-shape kernels keep their shape: their
    // algorithm needs it, and the limit a driver reports for them can be wrong (rusticl 22.3 reports 32 for a
    // kernel compiled with reqd_work_group_size(256), then runs it at 256); a shape the device really cannot run
    // fails in clEnqueueNDRangeKernel with a ClError naming the kernel.
    if (local && items > k.max_work_group() && !k.fixed_local()) {
        while (items > k.max_work_group()) {  // halve the largest dimension: fewer, smaller groups
            int big = 0;
            for (int i = 1; i < dims; ++i) if (l[i] > l[big]) big = i;
            items = items / l[big] * ((l[big] + 1) / 2);
            l[big] = (l[big] + 1) / 2;
        }
    }
    for (int i = 0; i < dims; ++i) g[i] = local ? round_up(global[i], l[i]) : global[i];
    cl_event ev = nullptr;
    check(clEnqueueNDRangeKernel(queue_, k.get(), static_cast<cl_uint>(dims), nullptr, g, local ? l : nullptr, 0, nullptr,
                                 want_event ? &ev : nullptr),
          ("run kernel " + k.name()).c_str(), "clEnqueueNDRangeKernel");
    return ev;
}

void Context::finish() { check(clFinish(queue_), "wait for the device queue", "clFinish"); }

}  // namespace detail

std::vector<DeviceInfo> list_devices() {
    std::vector<DeviceInfo> out;
    auto ps = detail::platforms();
    for (std::size_t pi = 0; pi < ps.size(); ++pi) {
        auto ds = detail::devices_of(ps[pi]);
        for (std::size_t di = 0; di < ds.size(); ++di)
            out.push_back(detail::describe(ps[pi], ds[di], static_cast<int>(pi), static_cast<int>(di)));
    }
    return out;
}

Device Device::open(const std::string& spec_in, DeviceOptions options) {
    std::string spec = spec_in;
    if (spec.empty())
        if (const char* e = std::getenv("NGI_DEVICE")) spec = e;
    auto ps = detail::platforms();
    if (ps.empty())
        throw DeviceNotFoundError("open device: no OpenCL platform found (is an ICD such as pocl-opencl-icd installed, and "
                    "/etc/OpenCL/vendors populated?)");
    struct Candidate { cl_platform_id p; cl_device_id d; DeviceInfo info; };
    std::vector<Candidate> all;
    for (std::size_t pi = 0; pi < ps.size(); ++pi) {
        auto ds = detail::devices_of(ps[pi]);
        for (std::size_t di = 0; di < ds.size(); ++di)
            all.push_back({ps[pi], ds[di], detail::describe(ps[pi], ds[di], int(pi), int(di))});
    }
    const Candidate* pick = nullptr;
    if (spec.empty()) {
        for (auto& c : all) if (c.info.is_gpu) { pick = &c; break; }
        if (!pick) for (auto& c : all) if (c.info.is_cpu) { pick = &c; break; }
        if (!pick && !all.empty()) pick = &all.front();
    } else if (spec == "gpu" || spec == "cpu") {
        for (auto& c : all) if ((spec == "gpu" && c.info.is_gpu) || (spec == "cpu" && c.info.is_cpu)) { pick = &c; break; }
    } else {
        int p = -1, d = -1;
        char tail = 0;
        if (std::sscanf(spec.c_str(), "%d:%d%c", &p, &d, &tail) == 2) {
            for (auto& c : all) if (c.info.platform_index == p && c.info.device_index == d) pick = &c;
        } else {
            // A platform name, or part of it, case-insensitive ("pocl", "rusticl", "nvidia"): its first device.
            // Indices depend on the ICD enumeration order of each machine; names do not.
            auto lower = [](std::string x) {
                for (auto& ch : x) ch = char(std::tolower(static_cast<unsigned char>(ch)));
                return x;
            };
            for (auto& c : all)
                if (lower(c.info.platform_name).find(lower(spec)) != std::string::npos ||
                    (lower(spec) == "pocl" && c.info.platform_name == "Portable Computing Language")) {
                    pick = &c;
                    break;
                }
        }
    }
    if (!pick) {
        std::string have;
        for (auto& c : all)
            have += "\n  " + std::to_string(c.info.platform_index) + ":" + std::to_string(c.info.device_index) + " " +
                    c.info.name + (c.info.is_gpu ? " (gpu)" : c.info.is_cpu ? " (cpu)" : "");
        throw DeviceNotFoundError("open device: no device matches '" + spec + "'; available:" + (have.empty() ? " none" : have));
    }
    return Device(std::make_shared<detail::Context>(pick->p, pick->d, pick->info, options));
}

Device Device::from_opencl(_cl_context* context, _cl_device_id* device, _cl_command_queue* queue) {
    return Device(std::make_shared<detail::Context>(context, device, queue));
}

namespace detail {
Context& context_of(const Device& device) { return *device.context_; }
std::shared_ptr<Context> shared_context_of(const Device& device) { return device.context_; }
}  // namespace detail

_cl_event* Device::marker() const {
    cl_event ev = nullptr;
    detail::check(clEnqueueMarkerWithWaitList(context_->queue(), 0, nullptr, &ev), "enqueue a marker",
                  "clEnqueueMarkerWithWaitList");
    return ev;
}
_cl_context* Device::opencl_context() const { return context_->context(); }
_cl_command_queue* Device::opencl_queue() const { return context_->queue(); }
_cl_device_id* Device::opencl_device() const { return context_->device(); }
HostTransfers Device::host_transfers() const { return context_->transfers(); }

const DeviceInfo& Device::info() const { return context_->info(); }
bool Device::profiling() const { return context_->options().profiling; }
void Device::finish() const { context_->finish(); }

}  // namespace ngi

// Device discovery and selection. A Device owns (or, created from the application's OpenCL objects, shares) an
// OpenCL context and one in-order queue, and holds the compiled-program cache. Copies of a Device are handles to
// the same device state. Threads: a Device may be used by any number of threads at once (docs/ARCHITECTURE.md
// "Threading"); the objects made from it (Model, SurroundPipeline, Renderer, DeviceBuffer) by one thread at a time.
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

// The application's OpenCL objects, named without including <CL/cl.h> here: cl_context is `struct _cl_context*`
// etc. in every OpenCL header, so these are the same types.
struct _cl_context;
struct _cl_device_id;
struct _cl_command_queue;
struct _cl_event;

namespace ngi {

class Device;
namespace detail {
class Context;
Context& context_of(const Device& device);
std::shared_ptr<Context> shared_context_of(const Device& device);
}  // namespace detail

struct DeviceInfo {
    int platform_index = 0;
    int device_index = 0;
    std::string platform_name;
    std::string name;
    std::string vendor;
    std::string driver_version;
    std::string device_version;      // "OpenCL 3.0 PoCL ..."
    std::string opencl_c_version;    // "OpenCL C 1.2 ..."
    bool is_gpu = false;
    bool is_cpu = false;
    bool fp16 = false;               // cl_khr_fp16 reported
    std::size_t local_mem_bytes = 0;
    bool local_mem_is_dedicated = false;  // CL_LOCAL vs CL_GLOBAL local memory type
    std::size_t global_mem_bytes = 0;
    std::size_t max_alloc_bytes = 0;
    std::size_t max_work_group_size = 0;
    unsigned compute_units = 0;
    // CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT: floats per native SIMD register (PoCL on a CPU: 8 with AVX2, 16 with
    // AVX-512). The GEMM tuning database's "vector_width" field: a CPU's register tiles depend on it.
    unsigned native_float_vector_width = 0;
    std::string extensions;
    // "gpu", "cpu" or "other": the one spelling (the GEMM tuning database's "type" field, ngi.Device.info()).
    const char* type_name() const { return is_gpu ? "gpu" : is_cpu ? "cpu" : "other"; }
};

// Every OpenCL device of every platform, in platform/device order (the "P:D" indices).
std::vector<DeviceInfo> list_devices();

struct DeviceOptions {
    bool profiling = false;  // create the queue with CL_QUEUE_PROFILING_ENABLE (per-op timings)
};

// Host <-> device transfers a device's queue has done since the Device was created (uploads: host to device).
// Device-to-device copies are not counted. Used to show that a device-resident frame never touches the host.
struct HostTransfers {
    long long uploads = 0, downloads = 0;
    long long upload_bytes = 0, download_bytes = 0;
};

class Device {
public:
    // spec: "cpu", "gpu", "P:D" (platform and device index), a platform name or part of it ("pocl", "rusticl"),
    // or "" = $NGI_DEVICE, else first GPU, else first CPU.
    static Device open(const std::string& spec = "", DeviceOptions options = {});

    // A device on the application's own OpenCL objects: ngi compiles its programs in `context` and enqueues every
    // kernel and transfer on `queue` (which must be in-order and belong to `context` and `device`), so ngi's work
    // is ordered with the application's own commands on that queue. The three objects are retained while any
    // copy of this Device (or an object made from it) lives, and released afterwards; ngi never destroys them.
    // Profiling follows the queue's CL_QUEUE_PROFILING_ENABLE. Throws InputError for objects that do not match.
    static Device from_opencl(_cl_context* context, _cl_device_id* device, _cl_command_queue* queue);

    const DeviceInfo& info() const;
    bool profiling() const;
    void finish() const;  // wait for all queued work (clFinish on the queue)
    // An event that completes when everything enqueued so far has (clEnqueueMarkerWithWaitList): for applications
    // that wait on ngi's work from another queue. The caller releases it (clReleaseEvent).
    _cl_event* marker() const;

    // The OpenCL objects ngi runs on (not retained for the caller): to create buffers in the same context.
    _cl_context* opencl_context() const;
    _cl_command_queue* opencl_queue() const;
    _cl_device_id* opencl_device() const;

    HostTransfers host_transfers() const;

private:
    friend detail::Context& detail::context_of(const Device&);
    friend std::shared_ptr<detail::Context> detail::shared_context_of(const Device&);
    explicit Device(std::shared_ptr<detail::Context> c) : context_(std::move(c)) {}
    std::shared_ptr<detail::Context> context_;
};

}  // namespace ngi

// Device discovery and selection. A Device owns an OpenCL context, one in-order queue and a program cache.
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace ngi {

namespace detail { class Context; }

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
    std::string extensions;
};

// Every OpenCL device of every platform, in platform/device order (the "P:D" indices).
std::vector<DeviceInfo> list_devices();

struct DeviceOptions {
    bool profiling = false;  // create the queue with CL_QUEUE_PROFILING_ENABLE (per-op timings)
};

class Device {
public:
    // spec: "cpu", "gpu", "P:D" (platform and device index), a platform name or part of it ("pocl", "rusticl"),
    // or "" = $NGI_DEVICE, else first GPU, else first CPU.
    static Device open(const std::string& spec = "", DeviceOptions options = {});

    const DeviceInfo& info() const;
    bool profiling() const;
    void finish() const;  // wait for all queued work

    // For library internals (ops, graph). Not part of the stable API.
    detail::Context& context() const { return *context_; }
    std::shared_ptr<detail::Context> shared_context() const { return context_; }

private:
    explicit Device(std::shared_ptr<detail::Context> c) : context_(std::move(c)) {}
    std::shared_ptr<detail::Context> context_;
};

}  // namespace ngi

// Devices and device memory: listing and opening devices (or adopting an application's OpenCL context and queue),
// their properties, synchronization and program warm-up; buffers allocated by ngi or wrapping an application's cl_mem.
#include <CL/cl.h>

#include "c_handles.hpp"
#include "ngi/warmup.hpp"

using namespace c_abi;

namespace {

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

// The byte range [offset, offset + bytes) of a buffer of `size` bytes: INVALID_ARGUMENT when it reaches outside.
void require_range(std::size_t offset, std::size_t bytes, std::size_t size) {
    require(offset <= size && bytes <= size - offset,
            "bytes [" + std::to_string(offset) + ", " + std::to_string(offset) + " + " + std::to_string(bytes) +
                ") reach outside the buffer's " + std::to_string(size) + " bytes");
}

}  // namespace

extern "C" {

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
        *out = track(std::make_unique<ngi_device>(ngi::Device::open(spec ? spec : "")));
    });
}

ngi_status ngi_device_from_opencl(struct _cl_context* context, struct _cl_device_id* device,
                                  struct _cl_command_queue* queue, ngi_device** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        require(context && device && queue, "context, device and queue must not be NULL");
        *out = track(std::make_unique<ngi_device>(ngi::Device::from_opencl(context, device, queue)));
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

ngi_status ngi_device_retain(ngi_device* device) { return guarded(__func__, [&] { retain_handle(device, "device"); }); }
ngi_status ngi_device_release(ngi_device* device) { return guarded(__func__, [&] { release_handle(device, "device"); }); }

// --- buffers ---------------------------------------------------------------------------------------------------

ngi_status ngi_buffer_new(ngi_device* device, size_t bytes, ngi_buffer** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(bytes > 0, "bytes is 0");
        *out = track(std::make_unique<ngi_buffer>(ngi::DeviceBuffer::allocate(d.device, bytes)));
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
        *out = track(std::make_unique<ngi_buffer>(ngi::DeviceBuffer::wrap(d.device, mem, offset, bytes)));
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

}  // extern "C"

// Device-resident data: a byte range of an OpenCL buffer that ngi either allocated or borrows from the
// application. What the device-in/device-out calls (Model::enqueue, SurroundPipeline::enqueue) read and write.
#pragma once
#include <cstddef>
#include <memory>

#include "ngi/device.hpp"

struct _cl_mem;  // cl_mem is `struct _cl_mem*` in every OpenCL header

namespace ngi {

// A handle: copies refer to the same memory (like Device). An empty DeviceBuffer() holds nothing.
class DeviceBuffer {
public:
    DeviceBuffer();

    // A new buffer of `bytes` (> 0) on `device`, owned by ngi (released with the last handle). Contents undefined.
    static DeviceBuffer allocate(const Device& device, std::size_t bytes);

    // Borrows bytes [offset, offset + bytes) of the application's `mem`, which must belong to the device's
    // OpenCL context and be at least offset + bytes large. The memory object is retained while a handle lives and
    // released afterwards; ngi never frees it. A non-zero offset becomes an OpenCL sub-buffer, so it must be a
    // multiple of the device's CL_DEVICE_MEM_BASE_ADDR_ALIGN (in bytes: usually 64 or 128). Throws InputError
    // naming what does not fit.
    static DeviceBuffer wrap(const Device& device, _cl_mem* mem, std::size_t offset, std::size_t bytes);

    std::size_t bytes() const;
    bool owned() const;      // allocated by ngi (false: wrapped)
    bool writable() const;   // not created CL_MEM_READ_ONLY
    explicit operator bool() const { return impl_ != nullptr; }
    const Device& device() const;
    // The memory kernels address from byte 0 (the sub-buffer when wrapped at an offset). Not retained for the caller.
    _cl_mem* opencl_mem() const;

    // Blocking host transfers of `bytes` at byte `offset` of this buffer (counted in Device::host_transfers()).
    void upload(const void* src, std::size_t bytes, std::size_t offset = 0);
    void download(void* dst, std::size_t bytes, std::size_t offset = 0) const;

    struct Impl;

private:
    std::shared_ptr<Impl> impl_;
};

}  // namespace ngi

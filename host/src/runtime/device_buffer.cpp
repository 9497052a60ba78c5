// DeviceBuffer: ngi-owned or application-owned device memory behind one handle.
#include "ngi/device_buffer.hpp"

#include <algorithm>
#include <string>

#include "ngi/error.hpp"
#include "runtime/context.hpp"

namespace ngi {

struct DeviceBuffer::Impl {
    Device device;
    detail::Buffer mem;  // owns one reference: ngi's allocation, or the app's object (retained) or a sub-buffer of it
    bool owned = false;
    bool writable = true;
};

DeviceBuffer::DeviceBuffer() = default;

DeviceBuffer DeviceBuffer::allocate(const Device& device, std::size_t bytes) {
    if (bytes == 0) throw InputError("allocate device buffer: size is 0 bytes");
    DeviceBuffer b;
    b.impl_ = std::make_shared<Impl>(Impl{device, detail::context_of(device).alloc(bytes, "device buffer"), true, true});
    return b;
}

DeviceBuffer DeviceBuffer::wrap(const Device& device, _cl_mem* mem, std::size_t offset, std::size_t bytes) {
    const std::string op = "wrap application buffer";
    if (!mem) throw InputError(op + ": the cl_mem is NULL");
    if (bytes == 0) throw InputError(op + ": size is 0 bytes");
    detail::Context& ctx = detail::context_of(device);
    cl_context owner = nullptr;
    cl_mem_object_type type = 0;
    std::size_t size = 0;
    cl_mem_flags flags = 0;
    detail::check(clGetMemObjectInfo(mem, CL_MEM_TYPE, sizeof type, &type, nullptr), op.c_str(), "clGetMemObjectInfo");
    if (type != CL_MEM_OBJECT_BUFFER) throw InputError(op + ": the cl_mem is an image, not a buffer");
    detail::check(clGetMemObjectInfo(mem, CL_MEM_CONTEXT, sizeof owner, &owner, nullptr), op.c_str(), "clGetMemObjectInfo");
    if (owner != ctx.context())
        throw InputError(op + ": the cl_mem belongs to another OpenCL context than the device's (create the device "
                              "with Device::from_opencl on the application's context)");
    detail::check(clGetMemObjectInfo(mem, CL_MEM_SIZE, sizeof size, &size, nullptr), op.c_str(), "clGetMemObjectInfo");
    detail::check(clGetMemObjectInfo(mem, CL_MEM_FLAGS, sizeof flags, &flags, nullptr), op.c_str(), "clGetMemObjectInfo");
    if (offset > size || bytes > size - offset)
        throw InputError(op + ": bytes [" + std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                         ") lie outside the cl_mem's " + std::to_string(size) + " bytes");
    cl_mem view = nullptr;
    if (offset == 0) {
        detail::check(clRetainMemObject(mem), op.c_str(), "clRetainMemObject");
        view = mem;
    } else {
        cl_uint align_bits = 0;
        detail::check(clGetDeviceInfo(ctx.device(), CL_DEVICE_MEM_BASE_ADDR_ALIGN, sizeof align_bits, &align_bits,
                                      nullptr), op.c_str(), "clGetDeviceInfo");
        const std::size_t align = std::max<std::size_t>(1, align_bits / 8);
        if (offset % align != 0)
            throw InputError(op + ": offset " + std::to_string(offset) + " is not a multiple of the device's "
                             "CL_DEVICE_MEM_BASE_ADDR_ALIGN (" + std::to_string(align) + " bytes)");
        cl_buffer_region region{offset, bytes};
        cl_int err = CL_SUCCESS;
        view = clCreateSubBuffer(mem, 0, CL_BUFFER_CREATE_TYPE_REGION, &region, &err);
        detail::check(err, op.c_str(), "clCreateSubBuffer");  // a sub-buffer keeps its parent alive
    }
    DeviceBuffer b;
    b.impl_ = std::make_shared<Impl>(Impl{device, detail::Buffer(view, bytes), false, (flags & CL_MEM_READ_ONLY) == 0});
    return b;
}

namespace {
const DeviceBuffer::Impl& require(const std::shared_ptr<DeviceBuffer::Impl>& impl, const char* op) {
    if (!impl) throw InputError(std::string(op) + ": the DeviceBuffer is empty");
    return *impl;
}
void check_range(std::size_t offset, std::size_t bytes, std::size_t size, const char* op) {
    if (offset > size || bytes > size - offset)
        throw InputError(std::string(op) + ": bytes [" + std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                         ") lie outside the buffer's " + std::to_string(size) + " bytes");
}
}  // namespace

std::size_t DeviceBuffer::bytes() const { return impl_ ? impl_->mem.bytes() : 0; }
bool DeviceBuffer::owned() const { return impl_ && impl_->owned; }
bool DeviceBuffer::writable() const { return impl_ && impl_->writable; }
const Device& DeviceBuffer::device() const { return require(impl_, "device buffer").device; }
_cl_mem* DeviceBuffer::opencl_mem() const { return impl_ ? impl_->mem.get() : nullptr; }

void DeviceBuffer::upload(const void* src, std::size_t bytes, std::size_t offset) {
    const Impl& im = require(impl_, "upload to device buffer");
    check_range(offset, bytes, im.mem.bytes(), "upload to device buffer");
    if (!src && bytes) throw InputError("upload to device buffer: the source pointer is NULL");
    detail::context_of(im.device).write(im.mem, offset, bytes, src, "device buffer");
}

void DeviceBuffer::download(void* dst, std::size_t bytes, std::size_t offset) const {
    const Impl& im = require(impl_, "download from device buffer");
    check_range(offset, bytes, im.mem.bytes(), "download from device buffer");
    if (!dst && bytes) throw InputError("download from device buffer: the destination pointer is NULL");
    detail::context_of(im.device).read(im.mem, offset, bytes, dst, "device buffer");
}

}  // namespace ngi

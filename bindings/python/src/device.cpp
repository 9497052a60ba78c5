// ngi.devices(), ngi.Device, ngi.DeviceBuffer, and interop with pyopencl (its Context / CommandQueue / Buffer
// objects are used through their `int_ptr`, the raw cl_* handle, so this module does not depend on pyopencl).
#include <cstdint>
#include <cstring>

#include "common.hpp"

namespace ngi_py {

namespace {

template <typename T>
T* cl_handle(const py::handle& obj, const char* what) {
    if (!py::hasattr(obj, "int_ptr"))
        throw py::type_error(std::string(what) + ": expected a pyopencl object (with an int_ptr), got " +
                             std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
    const auto ptr = obj.attr("int_ptr").cast<std::uintptr_t>();
    if (ptr == 0) throw py::value_error(std::string(what) + ": the OpenCL handle is NULL (released?)");
    return reinterpret_cast<T*>(ptr);
}

py::dict info_dict(const ngi::DeviceInfo& i) {
    py::dict d;
    d["index"] = std::to_string(i.platform_index) + ":" + std::to_string(i.device_index);
    d["platform"] = i.platform_name;
    d["name"] = i.name;
    d["vendor"] = i.vendor;
    d["driver_version"] = i.driver_version;
    d["device_version"] = i.device_version;
    d["opencl_c_version"] = i.opencl_c_version;
    d["type"] = i.type_name();
    d["fp16"] = i.fp16;
    d["compute_units"] = i.compute_units;
    d["native_float_vector_width"] = i.native_float_vector_width;
    d["global_mem_bytes"] = i.global_mem_bytes;
    d["max_alloc_bytes"] = i.max_alloc_bytes;
    d["local_mem_bytes"] = i.local_mem_bytes;
    d["max_work_group_size"] = i.max_work_group_size;
    return d;
}

// An ngi.DeviceBuffer: the DeviceBuffer plus the device state it was made on (to refuse use after close()).
struct PyBuffer {
    DeviceRef device;
    ngi::DeviceBuffer buffer;
};

}  // namespace

ngi::DeviceBuffer device_buffer(const DeviceRef& device, const py::handle& obj, const char* what) {
    if (py::isinstance<PyBuffer>(obj)) {
        const auto& b = obj.cast<const PyBuffer&>();
        b.device->get(what);
        return b.buffer;
    }
    auto* mem = cl_handle<_cl_mem>(obj, what);
    if (!py::hasattr(obj, "size")) throw py::type_error(std::string(what) + ": a pyopencl Buffer has a size; this has none");
    return ngi::DeviceBuffer::wrap(device->get(what), mem, 0, obj.attr("size").cast<std::size_t>());
}

void register_device(py::module_& m) {
    m.def("devices", [] {
        py::list out;
        for (const auto& i : ngi::list_devices()) out.append(info_dict(i));
        return out;
    }, "Every OpenCL device of every platform, as dicts (index 'P:D', platform, name, type, ...), in the order of "
       "the 'P:D' indices that ngi.Device() accepts.");

    py::class_<DeviceState, DeviceRef>(m, "Device", R"doc(
An OpenCL device with ngi's context, in-order queue and compiled-program cache.

Device(spec="") opens: "cpu", "gpu", "P:D" (platform and device index, see ngi.devices()), a platform name or part
of it ("pocl", "rusticl"), or "" = $NGI_DEVICE, else the first GPU, else the first CPU. Device.from_pyopencl(queue)
runs ngi on a pyopencl queue's context and queue instead. A device may be shared by threads; the objects made from
it (Model, Pipeline, Renderer, DeviceBuffer) are used by one thread at a time. close() (or leaving a `with` block)
makes every object made from the device refuse further calls.)doc")
        .def(py::init([](const std::string& spec, bool profiling) {
                 auto s = std::make_shared<DeviceState>();
                 ngi::Device d = [&] {
                     py::gil_scoped_release release;
                     return ngi::Device::open(spec, ngi::DeviceOptions{profiling});
                 }();
                 s->label = "'" + d.info().name + "' (" + d.info().platform_name + ")";
                 s->device = std::move(d);
                 return s;
             }),
             py::arg("spec") = "", py::arg("profiling") = false)
        .def_static("from_pyopencl", [](const py::object& queue) {
            py::object ctx = queue.attr("context"), dev = queue.attr("device");
            auto s = std::make_shared<DeviceState>();
            ngi::Device d = ngi::Device::from_opencl(cl_handle<_cl_context>(ctx, "from_pyopencl: queue.context"),
                                                     cl_handle<_cl_device_id>(dev, "from_pyopencl: queue.device"),
                                                     cl_handle<_cl_command_queue>(queue, "from_pyopencl: queue"));
            s->label = "'" + d.info().name + "' (pyopencl)";
            s->device = std::move(d);
            return s;
        }, py::arg("queue"),
           "A device on a pyopencl CommandQueue (in-order) and its context: ngi compiles in that context and enqueues "
           "on that queue, so its work is ordered with the application's; pyopencl Buffers of that context can be "
           "passed wherever a DeviceBuffer is taken. The pyopencl objects are retained while ngi uses them.")
        .def_property_readonly("info", [](const DeviceState& s) { return info_dict(s.get("Device.info").info()); },
                               "The device's properties as a dict (see ngi.devices()).")
        .def_property_readonly("name", [](const DeviceState& s) { return s.get("Device.name").info().name; })
        .def_property_readonly("closed", [](const DeviceState& s) { return !s.device.has_value(); })
        .def("finish", [](const DeviceState& s) {
            const ngi::Device& d = s.get("Device.finish");
            py::gil_scoped_release release;
            d.finish();
        }, "Wait until everything enqueued on the device's queue has finished.")
        .def("host_transfers", [](const DeviceState& s) {
            const ngi::HostTransfers t = s.get("Device.host_transfers").host_transfers();
            py::dict d;
            d["uploads"] = t.uploads;
            d["downloads"] = t.downloads;
            d["upload_bytes"] = t.upload_bytes;
            d["download_bytes"] = t.download_bytes;
            return d;
        }, "Host <-> device transfers done on this device's queue so far (device-to-device copies not counted).")
        .def("close", [](DeviceState& s) { s.device.reset(); },
             "Release this device handle: every object made from it refuses further calls.")
        .def("__enter__", [](const DeviceRef& s) { return s; })
        .def("__exit__", [](DeviceState& s, py::args) { s.device.reset(); })
        .def("__repr__", [](const DeviceState& s) {
            return "<ngi.Device " + s.label + (s.device ? "" : " closed") + ">";
        });

    py::class_<PyBuffer>(m, "DeviceBuffer", R"doc(
Device memory: allocated by ngi (DeviceBuffer(device, nbytes)) or a pyopencl Buffer borrowed without a copy
(DeviceBuffer.wrap(device, buffer, offset=0, nbytes=None)). What Model.enqueue and Pipeline.enqueue read and write.)doc")
        .def(py::init([](const DeviceRef& device, std::size_t nbytes) {
                 if (nbytes == 0) throw py::value_error("DeviceBuffer: nbytes must be > 0");
                 return PyBuffer{device, ngi::DeviceBuffer::allocate(device->get("DeviceBuffer"), nbytes)};
             }),
             py::arg("device"), py::arg("nbytes"))
        .def_static("wrap", [](const DeviceRef& device, const py::object& buffer, std::size_t offset,
                               std::optional<std::size_t> nbytes) {
            auto* mem = cl_handle<_cl_mem>(buffer, "DeviceBuffer.wrap: buffer");
            std::size_t bytes = 0;
            if (nbytes) bytes = *nbytes;
            else {
                const auto size = buffer.attr("size").cast<std::size_t>();
                if (offset >= size) throw py::value_error("DeviceBuffer.wrap: offset " + std::to_string(offset) +
                                                          " is not inside the buffer's " + std::to_string(size) + " bytes");
                bytes = size - offset;
            }
            return PyBuffer{device, ngi::DeviceBuffer::wrap(device->get("DeviceBuffer.wrap"), mem, offset, bytes)};
        }, py::arg("device"), py::arg("buffer"), py::arg("offset") = 0, py::arg("nbytes") = py::none(),
           "Borrow bytes [offset, offset + nbytes) of a pyopencl Buffer of the device's context (no copy; a non-zero "
           "offset must be a multiple of the device's base address alignment).")
        .def_property_readonly("nbytes", [](const PyBuffer& b) { return b.buffer.bytes(); })
        .def_property_readonly("owned", [](const PyBuffer& b) { return b.buffer.owned(); },
                               "True if ngi allocated the memory, False if it is borrowed.")
        .def("upload", [](PyBuffer& b, const py::object& array, std::size_t offset) {
            b.device->get("DeviceBuffer.upload");
            FloatArray a = float_array(array, "DeviceBuffer.upload: array");
            const std::size_t bytes = std::size_t(a.size()) * sizeof(float);
            py::gil_scoped_release release;
            b.buffer.upload(a.data(), bytes, offset);
        }, py::arg("array"), py::arg("offset") = 0,
           "Copy a float array (C order) into the buffer at byte `offset` (blocking).")
        .def("download", [](const PyBuffer& b, std::vector<py::ssize_t> shape, std::size_t offset) {
            b.device->get("DeviceBuffer.download");
            FloatArray out(shape);
            const std::size_t bytes = std::size_t(out.size()) * sizeof(float);
            float* dst = out.mutable_data();
            {
                py::gil_scoped_release release;
                b.buffer.download(dst, bytes, offset);
            }
            return out;
        }, py::arg("shape"), py::arg("offset") = 0,
           "A new float32 array of `shape` read from byte `offset` of the buffer (blocking).")
        .def("__repr__", [](const PyBuffer& b) {
            return "<ngi.DeviceBuffer " + std::to_string(b.buffer.bytes()) + " bytes" +
                   (b.buffer.owned() ? "" : ", borrowed") + ">";
        });
}

}  // namespace ngi_py

// Shared pieces of the Python module ngi._ngi: NumPy <-> ngi conversions, the checked device handle, argument
// checks. The module is a thin layer over the public C++ API (host/include/ngi); each file registers one area.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/image.hpp"
#include "ngi/tensor.hpp"

namespace py = pybind11;

namespace ngi_py {

// A C-contiguous float32 array (what the library reads and writes); forcecast: float16/64 convert.
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// The state behind an ngi.Device: closing it makes every object made from it refuse further calls (their OpenCL
// resources are freed when they are garbage-collected). Shared by the Device object and everything made from it.
struct DeviceState {
    std::optional<ngi::Device> device;
    std::string label;  // for messages after close()
    const ngi::Device& get(const char* operation) const {
        if (!device) throw ngi::InputError(std::string(operation) + ": the device " + label + " was closed");
        return *device;
    }
};
using DeviceRef = std::shared_ptr<DeviceState>;

// A float array from any array-like of a floating dtype (float16/32/64; converted to a C-contiguous float32 copy
// only when it is not one already). Integer, bool, complex and object arrays are refused with a TypeError naming
// `what`: silently reading integer pixel values as light would be wrong by a factor of 255 or 65535.
FloatArray float_array(const py::handle& obj, const char* what);

// Shape checks that raise ValueError naming `what` and the expected shape.
void expect_ndim(const FloatArray& a, std::initializer_list<int> allowed, const char* what, const char* expected);

// [C, H, W] (or [H, W] as one channel) -> Image (a copy: Image owns its data).
ngi::Image to_image(const py::handle& obj, const char* what);
// Image -> [C, H, W] float32 array that takes over the Image's memory (no copy).
py::array_t<float> from_image(ngi::Image&& image);
// Tensor -> array of its shape that takes over the Tensor's memory (no copy).
py::array_t<float> from_tensor(ngi::Tensor&& tensor);
// A vector that moves into a new array of `shape` (no copy).
py::array_t<float> from_vector(std::vector<float>&& data, std::vector<py::ssize_t> shape);

// str or os.PathLike -> path string.
std::string path_string(const py::handle& obj, const char* what);

// A 3-vector from any sequence of three numbers.
glm::vec3 vec3(const py::handle& obj, const char* what);
py::tuple tuple3(glm::vec3 v);

// A DeviceBuffer from an ngi.DeviceBuffer or anything with an OpenCL `int_ptr` (a pyopencl Buffer: wrapped,
// whole, without a copy; it must belong to the device's context).
ngi::DeviceBuffer device_buffer(const DeviceRef& device, const py::handle& obj, const char* what);

void register_errors(py::module_& m);
void register_device(py::module_& m);
void register_io(py::module_& m);
void register_model(py::module_& m);
void register_pipeline(py::module_& m);
void register_render(py::module_& m);

}  // namespace ngi_py

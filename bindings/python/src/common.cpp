// NumPy <-> ngi conversions and the exception classes of ngi._ngi.
#include "common.hpp"

#include <cstring>

namespace ngi_py {

FloatArray float_array(const py::handle& obj, const char* what) {
    py::array any = py::array::ensure(obj);
    if (!any) throw py::type_error(std::string(what) + ": expected a NumPy array (or array-like), got " +
                                   std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
    const char kind = any.dtype().kind();
    if (kind != 'f')
        throw py::type_error(std::string(what) + ": expected a floating-point array (float16/32/64), got dtype " +
                             std::string(py::str(any.dtype())) + "; convert it explicitly (e.g. x.astype(np.float32) "
                             "/ 255 for 8-bit pixels)");
    FloatArray a = FloatArray::ensure(any);  // no copy when already C-contiguous float32
    if (!a) throw py::error_already_set();
    return a;
}

void expect_ndim(const FloatArray& a, std::initializer_list<int> allowed, const char* what, const char* expected) {
    for (int n : allowed)
        if (a.ndim() == n) return;
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    shape += a.ndim() == 1 ? ",)" : ")";
    throw py::value_error(std::string(what) + ": expected shape " + expected + ", got " + shape);
}

ngi::Image to_image(const py::handle& obj, const char* what) {
    FloatArray a = float_array(obj, what);
    expect_ndim(a, {2, 3}, what, "[C, H, W] or [H, W]");
    const int c = a.ndim() == 3 ? int(a.shape(0)) : 1;
    const int h = int(a.shape(a.ndim() - 2)), w = int(a.shape(a.ndim() - 1));
    if (c < 1 || h < 1 || w < 1) throw py::value_error(std::string(what) + ": the image is empty");
    ngi::Image img(w, h, c);
    std::memcpy(img.data.data(), a.data(), img.data.size() * sizeof(float));
    return img;
}

py::array_t<float> from_vector(std::vector<float>&& data, std::vector<py::ssize_t> shape) {
    auto* owner = new std::vector<float>(std::move(data));
    py::capsule free_owner(owner, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>(shape, owner->data(), free_owner);
}

py::array_t<float> from_image(ngi::Image&& image) {
    const std::vector<py::ssize_t> shape{image.channels, image.height, image.width};
    return from_vector(std::move(image.data), shape);
}

py::array_t<float> from_tensor(ngi::Tensor&& tensor) {
    std::vector<py::ssize_t> shape(tensor.shape.begin(), tensor.shape.end());
    return from_vector(std::move(tensor.data), shape);
}

std::string path_string(const py::handle& obj, const char* what) {
    if (py::isinstance<py::str>(obj)) return obj.cast<std::string>();
    if (py::hasattr(obj, "__fspath__")) {
        py::object p = obj.attr("__fspath__")();
        if (py::isinstance<py::str>(p)) return p.cast<std::string>();
    }
    throw py::type_error(std::string(what) + ": expected a path (str or os.PathLike)");
}

glm::vec3 vec3(const py::handle& obj, const char* what) {
    std::vector<float> v;
    try {
        v = obj.cast<std::vector<float>>();
    } catch (const py::cast_error&) {
        throw py::type_error(std::string(what) + ": expected three numbers");
    }
    if (v.size() != 3) throw py::value_error(std::string(what) + ": expected three numbers, got " + std::to_string(v.size()));
    for (float x : v)
        if (!std::isfinite(x)) throw py::value_error(std::string(what) + ": the components must be finite");
    return {v[0], v[1], v[2]};
}

py::tuple tuple3(glm::vec3 v) { return py::make_tuple(v.x, v.y, v.z); }

// ---- exceptions ------------------------------------------------------------------------------------------------
namespace {
// Created once at import and kept for the interpreter's lifetime (never destroyed: translators may run late).
PyObject* g_error = nullptr;
PyObject* g_input_error = nullptr;
PyObject* g_opencl_error = nullptr;
PyObject* g_oom_error = nullptr;

PyObject* make_class(py::module_& m, const char* name, py::tuple bases, const char* doc) {
    py::dict ns;
    ns["__module__"] = "ngi";
    ns["__doc__"] = doc;
    py::object cls = py::module_::import("builtins").attr("type")(name, bases, ns);
    m.attr(name) = cls;
    return cls.release().ptr();
}
}  // namespace

void register_errors(py::module_& m) {
    g_error = make_class(m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
                         "Base class of every error the ngi library reports; the message names the operation and the "
                         "file, tensor or buffer involved.");
    g_input_error = make_class(m, "InputError", py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError)),
                               "Bad input: a file, array, buffer or argument ngi cannot use (the message names it).");
    g_opencl_error = make_class(m, "OpenCLError", py::make_tuple(py::handle(g_error)),
                                "An OpenCL call failed; `code` is the OpenCL error code, the message names the call "
                                "and the CL_ error name (and carries the build log for a failed kernel build).");
    g_oom_error = make_class(m, "OutOfMemoryError", py::make_tuple(py::handle(g_error), py::handle(PyExc_MemoryError)),
                             "A request beyond the device's memory limits.");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ngi::ClError& e) {
            py::object exc = py::reinterpret_borrow<py::object>(g_opencl_error)(e.what());
            exc.attr("code") = e.code();
            PyErr_SetObject(g_opencl_error, exc.ptr());
        } catch (const ngi::InputError& e) {
            PyErr_SetString(g_input_error, e.what());
        } catch (const ngi::OutOfMemoryError& e) {
            PyErr_SetString(g_oom_error, e.what());
        } catch (const ngi::Error& e) {
            PyErr_SetString(g_error, e.what());
        }
    });
}

}  // namespace ngi_py

// The native module ngi._ngi: Python bindings over ngi's public C++ API (bindings/python/ngi/__init__.py
// re-exports it as `ngi`). Errors become ngi.Error subclasses carrying the library's message; long calls release
// the GIL; arrays are float32 [C, H, W] / NCHW, C order.
#include "common.hpp"

PYBIND11_MODULE(_ngi, m) {
    m.doc() = "ngi: neural global illumination on OpenCL (native part; see help(ngi))";
    m.attr("__version__") = NGI_VERSION_STRING;
    ngi_py::register_errors(m);
    ngi_py::register_device(m);
    ngi_py::register_io(m);
    ngi_py::register_model(m);
    ngi_py::register_pipeline(m);
    ngi_py::register_render(m);
    py::list names;
    for (auto item : m.attr("__dict__").cast<py::dict>()) {
        const std::string name = item.first.cast<std::string>();
        if (!name.empty() && name[0] != '_') names.append(name);
    }
    m.attr("__all__") = names;
}

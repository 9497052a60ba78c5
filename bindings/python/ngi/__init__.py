"""ngi: neural global illumination on OpenCL, from Python.

The native part (``ngi._ngi``, pybind11 over ngi's C++ API) runs models, the surround-aware pipeline, metrics,
image I/O and the path tracer on any OpenCL device, with NumPy arrays in and out::

    import ngi
    dev = ngi.Device("cpu")                                  # or "gpu", "pocl", "rusticl", "P:D"
    model = ngi.Model(dev, "models/surround.safetensors")
    pipe = ngi.Pipeline(dev, 64)                             # face size N
    out = pipe.run(model, ngi.read_frame("frame"))           # {"lightmap": [3, N, N], "final": ..., ...}

The pure-Python modules (importable without the native part, e.g. in sanitizer builds) hold what the training
code, the converter and the parity tests share: ``ngi.model_file`` (the .safetensors model-file writer and
reader), ``ngi.dropout`` (the seeded dropout hash), ``ngi.reference_models`` (the PyTorch generators ngi is
tested against) and ``ngi.convert`` (PyTorch checkpoint -> ngi model file).

Errors raised by the native part: ``ngi.InputError`` (bad file, tensor or argument; a ``ValueError``),
``ngi.OpenCLError`` (an OpenCL call failed; carries ``.code``), ``ngi.OutOfMemoryError`` (a ``MemoryError``), all
subclasses of ``ngi.Error``. Conventions (channel order, value ranges, face orientation) are in docs/CONVENTIONS.md.
"""

try:
    from ._ngi import *  # noqa: F401,F403  (the native API; __all__ of _ngi lists it)
    from ._ngi import __version__  # noqa: F401
    from ._ngi import __all__ as _native_all
    _native_error = None
except ImportError as _e:  # not built (sanitizer build) or not loadable: the pure-Python modules still work
    _native_all = []
    _native_error = _e

__all__ = list(_native_all)


def __getattr__(name):
    # Only reached for names the native import did not define. An AttributeError (not ImportError), so that
    # `from ngi import model_file` still imports the submodule when the native part is missing.
    if _native_error is not None and not name.startswith("__"):
        raise AttributeError(f"module 'ngi' has no attribute '{name}': the native module ngi._ngi could not be "
                             f"imported ({_native_error}); build it with tools/build.sh (CMake option "
                             f"NGI_BUILD_PYTHON, not with sanitizers)")
    raise AttributeError(f"module 'ngi' has no attribute '{name}'")

// ngi errors: every failure is an ngi::Error whose message names the operation and the object involved.
#pragma once
#include <stdexcept>
#include <string>

namespace ngi {

// Base class of every exception ngi throws.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

// An OpenCL call failed. what() = "<operation>: <clCall> failed with CL_<NAME> (<code>)[: detail]".
class ClError : public Error {
public:
    ClError(const std::string& operation, const std::string& call, int code, const std::string& detail = "");
    int code() const { return code_; }

private:
    int code_;
};

// Bad user input: a file, tensor or argument that cannot be used. The message names it.
class InputError : public Error {
public:
    using Error::Error;
};

// No OpenCL platform, or no device matching the spec given to Device::open ("9:9", "nvidia" on a machine without
// one). An InputError (the spec is the caller's input: the C ABI and Python report it as one), typed apart so that
// the CLI can exit with its device-failure code (3) as documented, not 1 as for a bad file.
class DeviceNotFoundError : public InputError {
public:
    using InputError::InputError;
};

// Memory exhausted: a request beyond the device's limits (CL_DEVICE_MAX_MEM_ALLOC_SIZE). OpenCL's own allocation
// failures are ClErrors with CL_MEM_OBJECT_ALLOCATION_FAILURE / CL_OUT_OF_RESOURCES / CL_OUT_OF_HOST_MEMORY.
class OutOfMemoryError : public Error {
public:
    using Error::Error;
};

// "CL_OUT_OF_RESOURCES" for -5 etc.; "CL_UNKNOWN_ERROR" for codes OpenCL 1.2/3.0 does not define.
const char* cl_error_name(int code);

}  // namespace ngi

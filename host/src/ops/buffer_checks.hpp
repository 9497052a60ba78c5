// Checks an op makes of the raw cl_mem buffers a caller hands it: present, and large enough for the shapes given.
// One place for the wording, so every op's error names the op, the buffer, the bytes it holds and what needs more.
#pragma once
#include <string>

#include "ngi/error.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// The size of a buffer in bytes (CL_MEM_SIZE); `what` names the query in an OpenCL error.
inline std::size_t buffer_bytes(cl_mem m, const char* what) {
    std::size_t bytes = 0;
    check(clGetMemObjectInfo(m, CL_MEM_SIZE, sizeof bytes, &bytes, nullptr), what, "clGetMemObjectInfo");
    return bytes;
}

// Throws InputError "<op>: the <name> buffer is null" or "... holds H bytes, <for_what> needs N".
inline void require_buffer(cl_mem m, std::size_t need, const std::string& op, const std::string& name,
                           const std::string& for_what) {
    if (!m) throw InputError(op + ": the " + name + " buffer is null");
    const std::size_t have = buffer_bytes(m, (op + ": size of the " + name + " buffer").c_str());
    if (have < need)
        throw InputError(op + ": the " + name + " buffer holds " + std::to_string(have) + " bytes, " + for_what +
                         " needs " + std::to_string(need));
}

}  // namespace ngi::detail

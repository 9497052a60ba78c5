// Checks an op makes of the raw cl_mem buffers a caller hands it: present, and large enough for the shapes given.
// One place for the wording, so every op's error names the op, the buffer, the bytes it holds and what needs more.
#pragma once
#include <climits>
#include <string>

#include "ngi/error.hpp"
#include "ops/view.hpp"
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

// Throws InputError "<op>: the <name> tensor ... lies beyond 2^31 - 1 floats of its buffer" when a kernel that
// indexes with 32-bit ints could not reach all of `v` (its offset plus its size).
inline void require_int_indexable(const View& v, const std::string& op, const char* name) {
    if ((unsigned long long)v.offset + v.shape.size() > (unsigned long long)INT_MAX)
        throw InputError(op + ": the " + name + " tensor " + to_string(v.shape) + " at offset " +
                         std::to_string(v.offset) + " lies beyond 2^31 - 1 floats of its buffer");
}

}  // namespace ngi::detail

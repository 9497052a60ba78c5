// The library-wide entry points: the version, status names, the thread-local last error every call resets and the
// process-wide error callback (the state behind guarded() in c_handles.hpp).
#include <CL/cl.h>

#include <mutex>

#include "c_handles.hpp"

namespace c_abi {
namespace {

thread_local std::string g_last_error;
thread_local int g_last_cl_error = 0;
std::mutex g_callback_mutex;
ngi_error_callback g_callback = nullptr;
void* g_callback_user = nullptr;

}  // namespace

void reset_last_error() noexcept {
    g_last_error.clear();
    g_last_cl_error = 0;
}

void set_last_cl_error(int code) noexcept { g_last_cl_error = code; }

void report(const char* call, ngi_status status, const std::string& message) {
    g_last_error = std::string(call) + ": " + message;
    ngi_error_callback cb;
    void* user;
    {
        std::lock_guard<std::mutex> lock(g_callback_mutex);
        cb = g_callback;
        user = g_callback_user;
    }
    if (cb) cb(user, status, g_last_error.c_str());
}

bool is_out_of_memory(int cl) {
    return cl == CL_MEM_OBJECT_ALLOCATION_FAILURE || cl == CL_OUT_OF_RESOURCES || cl == CL_OUT_OF_HOST_MEMORY;
}

}  // namespace c_abi

using namespace c_abi;

extern "C" {

int ngi_version(void) { return NGI_VERSION; }

const char* ngi_status_name(ngi_status s) {
    switch (s) {
        case NGI_OK: return "NGI_OK";
        case NGI_ERROR_INVALID_ARGUMENT: return "NGI_ERROR_INVALID_ARGUMENT";
        case NGI_ERROR_INPUT: return "NGI_ERROR_INPUT";
        case NGI_ERROR_OPENCL: return "NGI_ERROR_OPENCL";
        case NGI_ERROR_OUT_OF_MEMORY: return "NGI_ERROR_OUT_OF_MEMORY";
        case NGI_ERROR_INVALID_HANDLE: return "NGI_ERROR_INVALID_HANDLE";
        case NGI_ERROR_INTERNAL: return "NGI_ERROR_INTERNAL";
        case NGI_STATUS_MAX_ENUM: break;
    }
    return "NGI_UNKNOWN_STATUS";
}

const char* ngi_last_error(void) { return g_last_error.c_str(); }
int ngi_last_cl_error(void) { return g_last_cl_error; }

void ngi_set_error_callback(ngi_error_callback callback, void* user) {
    std::lock_guard<std::mutex> lock(g_callback_mutex);
    g_callback = callback;
    g_callback_user = user;
}

}  // extern "C"

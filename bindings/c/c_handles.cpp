// The registry of live handles (c_handles.hpp): one for the whole library, shared by every area's entry points. Its
// table, lock and counter are reached only through the functions below.
#include "c_handles.hpp"

#include <mutex>
#include <unordered_map>

// The first handle value (a build for the registry's own test starts near the end of the range to reach it).
#ifndef NGI_C_FIRST_HANDLE
#define NGI_C_FIRST_HANDLE 0x10000
#endif

namespace c_abi {
namespace {

struct LiveHandle {
    HandleKind kind;
    ngi_handle* object;
};

std::mutex g_live_mutex;
std::unordered_map<const void*, LiveHandle> g_live;
// The next handle value; 0 once every value has been given out (the last is the largest multiple of 16).
std::uintptr_t g_next_handle = NGI_C_FIRST_HANDLE;

// The live handle `h`'s entry, checked to be of `kind`. Called with g_live_mutex held.
LiveHandle& check_locked(const void* h, HandleKind kind, const char* arg) {
    const auto it = g_live.find(h);
    if (it == g_live.end())
        fail(NGI_ERROR_INVALID_HANDLE, std::string(arg) + " is not a live handle (released, or never created)");
    if (it->second.kind != kind)
        fail(NGI_ERROR_INVALID_ARGUMENT,
             std::string(arg) + " is an " + kind_name(it->second.kind) + " handle, not an " + kind_name(kind));
    return it->second;
}

}  // namespace

const void* register_handle(HandleKind kind, ngi_handle* object) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    const std::uintptr_t value = g_next_handle;
    if (value == 0)
        fail(NGI_ERROR_OUT_OF_MEMORY, "no handle left: this process has been given all 2^" +
                                          std::to_string(sizeof(void*) * 8 - 4) +
                                          " handle values, and a value is never given out twice");
    const void* handle = reinterpret_cast<const void*>(value);
    g_live.emplace(handle, LiveHandle{kind, object});  // may throw std::bad_alloc: then nothing changed
    g_next_handle = value + 16;                         // 0 after the last value (unsigned wrap)
    return handle;
}

ngi_handle* find_handle(const void* h, HandleKind kind, const char* arg) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    return check_locked(h, kind, arg).object;
}

void retain_registered(const void* h, HandleKind kind, const char* arg) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    check_locked(h, kind, arg).object->refs.fetch_add(1);
}

ngi_handle* release_registered(const void* h, HandleKind kind, const char* arg) {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    ngi_handle* object = check_locked(h, kind, arg).object;
    if (object->refs.fetch_sub(1) != 1) return nullptr;
    g_live.erase(h);
    return object;
}

}  // namespace c_abi

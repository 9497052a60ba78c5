// The registry of live handles (c_handles.hpp): one for the whole library, shared by every area's entry points.
#include "c_handles.hpp"

namespace c_abi {

std::mutex g_live_mutex;
std::unordered_map<const void*, LiveHandle> g_live;
std::uintptr_t g_next_handle = 0x10000;

}  // namespace c_abi

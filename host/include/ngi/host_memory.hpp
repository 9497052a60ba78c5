// ngi's host-memory limit: the most host memory one operation may plan to hold at once (a file's bytes plus what
// they decode to, an image the command is about to allocate). Every reader and the commands that allocate large
// images check it *before* allocating, so a file or an option too large for the machine ends in an InputError that
// names the operation, the bytes it needs and how to raise the limit, not in the kernel's OOM killer or a
// std::bad_alloc half-way through. It is a per-operation plan, not an accounting of every allocation.
#pragma once
#include <cstdint>
#include <string>

namespace ngi {

// The limit in bytes: set_host_memory_limit's value if called, else $NGI_HOST_MEMORY_LIMIT (bytes, or with a
// K/M/G/T suffix meaning KiB/MiB/GiB/TiB: "8G"), else half of the machine's physical memory (at least 1 GiB).
// A malformed $NGI_HOST_MEMORY_LIMIT throws InputError naming the variable. Thread-safe.
std::uint64_t host_memory_limit();

// Replaces the limit for the whole process (0 = back to the environment / default). Thread-safe.
void set_host_memory_limit(std::uint64_t bytes);

// Throws InputError("<what>: needs N bytes of host memory at once, more than the host-memory limit of L bytes
// (raise it with NGI_HOST_MEMORY_LIMIT, e.g. NGI_HOST_MEMORY_LIMIT=16G)") when bytes > host_memory_limit().
void check_host_memory(const std::string& what, std::uint64_t bytes);

// "805306368 bytes (768 MiB)": how the messages above print a size.
std::string describe_bytes(std::uint64_t bytes);

}  // namespace ngi

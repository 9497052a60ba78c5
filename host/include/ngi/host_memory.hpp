// ngi's host-memory limit: the most host memory one operation may plan to hold at once (a file's bytes plus what
// they decode to, an image the command is about to allocate). Every reader and the commands that allocate large
// images check it *before* allocating, so a file or an option too large for the machine ends in an InputError that
// names the operation, the bytes it needs and how to raise the limit, not in the kernel's OOM killer or a
// std::bad_alloc half-way through. check_host_memory judges one operation's plan. What stays allocated for a while
// and grows with the input -- ngi's buffers on a CPU device (whose memory is host memory), the pipeline's tables,
// an application's large buffers such as a software GL renderer's G-buffer -- is *held*: one process-wide ledger
// (HostMemoryHold), so that each new holding is judged with everything already held.
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

// Bytes held now: every live HostMemoryHold plus ngi's buffers on CPU devices. Thread-safe.
std::uint64_t host_memory_held();

// Holds `bytes` of host memory in the ledger for its lifetime (move-only). The constructor throws InputError
// ("<what>: needs N bytes of host memory while M are already held ..., more than the host-memory limit of L")
// when host_memory_held() + bytes > host_memory_limit(), holding nothing then; construct it *before* allocating.
class HostMemoryHold {
public:
    HostMemoryHold() = default;
    HostMemoryHold(const std::string& what, std::uint64_t bytes);
    ~HostMemoryHold();
    HostMemoryHold(HostMemoryHold&& other) noexcept : bytes_(other.bytes_) { other.bytes_ = 0; }
    HostMemoryHold& operator=(HostMemoryHold&& other) noexcept;
    HostMemoryHold(const HostMemoryHold&) = delete;
    HostMemoryHold& operator=(const HostMemoryHold&) = delete;
    std::uint64_t bytes() const noexcept { return bytes_; }

private:
    std::uint64_t bytes_ = 0;
};

namespace detail {
// The ledger itself, for holdings whose end is not a C++ scope (a cl_mem freed by the runtime's destructor
// callback): check_and_hold throws as HostMemoryHold's constructor does; release undoes a hold.
void check_and_hold_host_memory(const std::string& what, std::uint64_t bytes);
void release_host_memory(std::uint64_t bytes) noexcept;
}  // namespace detail

}  // namespace ngi

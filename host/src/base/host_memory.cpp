#include "ngi/host_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "ngi/error.hpp"

namespace ngi {
namespace {

std::atomic<std::uint64_t> g_limit{0};  // 0 = not set by the application
std::atomic<std::uint64_t> g_held{0};   // the ledger: HostMemoryHold and ngi's buffers on CPU devices

// "8G", "512M", "123456": bytes with an optional binary suffix. Returns 0 for anything else (0 itself included:
// a limit of nothing is a typo, not a request).
std::uint64_t parse_size(const std::string& s) {
    std::size_t i = 0;
    std::uint64_t v = 0;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) {
        const std::uint64_t d = std::uint64_t(s[i] - '0');
        if (v > (std::numeric_limits<std::uint64_t>::max() - d) / 10) return 0;
        v = v * 10 + d;
        ++i;
    }
    if (i == 0) return 0;
    int shift = 0;
    if (i + 1 == s.size()) {
        switch (std::toupper(static_cast<unsigned char>(s[i]))) {
            case 'K': shift = 10; break;
            case 'M': shift = 20; break;
            case 'G': shift = 30; break;
            case 'T': shift = 40; break;
            default: return 0;
        }
    } else if (i != s.size()) {
        return 0;
    }
    if (shift && v > (std::numeric_limits<std::uint64_t>::max() >> shift)) return 0;
    return v << shift;
}

std::uint64_t default_limit() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    const std::uint64_t physical = pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page) : 0;
    return std::max<std::uint64_t>(physical / 2, std::uint64_t(1) << 30);
}

}  // namespace

std::uint64_t host_memory_limit() {
    if (const std::uint64_t set = g_limit.load(std::memory_order_relaxed)) return set;
    if (const char* env = std::getenv("NGI_HOST_MEMORY_LIMIT"); env && *env) {
        const std::uint64_t v = parse_size(env);
        if (!v)
            throw InputError(std::string("NGI_HOST_MEMORY_LIMIT='") + env +
                             "': expected a positive number of bytes, optionally with K, M, G or T (e.g. 8G)");
        return v;
    }
    return default_limit();
}

void set_host_memory_limit(std::uint64_t bytes) { g_limit.store(bytes, std::memory_order_relaxed); }

std::string describe_bytes(std::uint64_t bytes) {
    char buf[64];
    if (bytes >= (std::uint64_t(1) << 30)) std::snprintf(buf, sizeof buf, " (%.1f GiB)", double(bytes) / double(1 << 30));
    else if (bytes >= (std::uint64_t(1) << 20)) std::snprintf(buf, sizeof buf, " (%.0f MiB)", double(bytes) / double(1 << 20));
    else buf[0] = '\0';
    return std::to_string(bytes) + " bytes" + buf;
}

void check_host_memory(const std::string& what, std::uint64_t bytes) {
    const std::uint64_t limit = host_memory_limit();
    if (bytes > limit)
        throw InputError(what + ": needs " + describe_bytes(bytes) + " of host memory at once, more than the " +
                         "host-memory limit of " + describe_bytes(limit) +
                         " (raise it with NGI_HOST_MEMORY_LIMIT, e.g. NGI_HOST_MEMORY_LIMIT=16G)");
}

std::uint64_t host_memory_held() { return g_held.load(std::memory_order_relaxed); }

namespace detail {

void check_and_hold_host_memory(const std::string& what, std::uint64_t bytes) {
    const std::uint64_t limit = host_memory_limit();
    // Compare-and-swap: two threads holding at once cannot both pass on the same headroom.
    std::uint64_t held = g_held.load(std::memory_order_relaxed);
    do {
        if (bytes > limit || held > limit - bytes)
            throw InputError(what + ": needs " + describe_bytes(bytes) + " of host memory while " +
                             describe_bytes(held) + " are already held (ngi's buffers on a CPU device, tables, " +
                             "an application's frames), more than the host-memory limit of " + describe_bytes(limit) +
                             " (raise it with NGI_HOST_MEMORY_LIMIT, e.g. NGI_HOST_MEMORY_LIMIT=16G)");
    } while (!g_held.compare_exchange_weak(held, held + bytes, std::memory_order_relaxed));
}

void release_host_memory(std::uint64_t bytes) noexcept { g_held.fetch_sub(bytes, std::memory_order_relaxed); }

}  // namespace detail

HostMemoryHold::HostMemoryHold(const std::string& what, std::uint64_t bytes) {
    detail::check_and_hold_host_memory(what, bytes);
    bytes_ = bytes;
}

HostMemoryHold::~HostMemoryHold() { detail::release_host_memory(bytes_); }

HostMemoryHold& HostMemoryHold::operator=(HostMemoryHold&& other) noexcept {
    if (this != &other) {
        detail::release_host_memory(bytes_);
        bytes_ = other.bytes_;
        other.bytes_ = 0;
    }
    return *this;
}

}  // namespace ngi

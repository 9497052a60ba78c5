// Shared by the fuzz targets: the input as a std::string, and the one expected failure for bad input.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "ngi/error.hpp"

namespace ngi::fuzz {

inline std::string bytes(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// With NGI_FUZZ_RING=DIR, every input is also written to DIR/input-<k mod 256> (DIR must exist) before it runs: the
// last 256 inputs survive a report that names the wrong one. Why: code built without ASan (OpenEXR, libpng) can
// write into freed memory unseen; ASan finds the damage only when that chunk leaves its quarantine, inputs later,
// and libFuzzer saves the input running then. Replaying the ring under valgrind finds the one that did it.
inline void remember_input(const std::uint8_t* data, std::size_t size) {
    static const char* dir = std::getenv("NGI_FUZZ_RING");
    static unsigned long count = 0;
    if (!dir) return;
    const std::string path = std::string(dir) + "/input-" + std::to_string(count++ % 256);
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
}

// Runs `f`; an ngi::Error (InputError for bad input) is the expected outcome of a malformed file. Anything else —
// std::bad_alloc, std::out_of_range, a nlohmann exception, a sanitizer report — escapes and is a finding.
template <class F>
int expect_ngi_errors_only(F&& f) {
    try {
        f();
    } catch (const ngi::Error&) {
    }
    return 0;
}

}  // namespace ngi::fuzz

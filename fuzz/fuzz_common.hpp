// Shared by the fuzz targets: the input as a std::string, and the one expected failure for bad input.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "ngi/error.hpp"

namespace ngi::fuzz {

inline std::string bytes(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
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

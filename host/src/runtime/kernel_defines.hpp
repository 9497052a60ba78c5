// Build options from host constants (CLBlast's GetDefines() pattern). Every value a kernel shares with the host is
// defined once, in the C++ of the op or module that owns it, and reaches the kernel as "-DNAME=value"; the kernel
// file guards each one with `#ifndef NAME` / `#error`, so a program built without them fails to build, naming the
// missing value, instead of running with a stale copy. Context::kernel() takes the string (the program cache key
// includes it). Library-internal.
#pragma once
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <string>
#include <string_view>

#include "ngi/error.hpp"

namespace ngi::detail {

// "-DNAME=v".
inline std::string define(std::string_view name, long long v) {
    return "-D" + std::string(name) + "=" + std::to_string(v);
}
inline std::string define(std::string_view name, int v) { return define(name, static_cast<long long>(v)); }

// "-DNAME=<v as an OpenCL C float literal>": the shortest decimal that reads back as exactly v, with an 'f' suffix
// (5000 -> 5000.0f, 1e30 -> 1e+30f), so the kernel computes with the host's float bit for bit.
inline std::string define(std::string_view name, float v) {
    if (!std::isfinite(v)) throw Error("kernel build option " + std::string(name) + ": the value is not finite");
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    std::string s(buf, r.ptr);
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return "-D" + std::string(name) + "=" + s + "f";
}

// "-DNAME=a,b,c": an initializer list for a kernel's table (`__constant T t[] = {NAME};`).
template <class Range>
std::string define_list(std::string_view name, const Range& values) {
    std::string s = "-D" + std::string(name) + "=";
    bool first = true;
    for (const auto& v : values) {
        if (!first) s += ',';
        s += std::to_string(v);
        first = false;
    }
    return s;
}

// The options joined with single spaces (empty parts skipped).
inline std::string join_defines(std::initializer_list<std::string> parts) {
    std::string s;
    for (const std::string& p : parts) {
        if (p.empty()) continue;
        if (!s.empty()) s += ' ';
        s += p;
    }
    return s;
}

}  // namespace ngi::detail

// Shared helpers for the Catch2 suite: the device under test, random data, comparisons, naive references.
#pragma once
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <source_location>
#include <span>
#include <string>
#include <vector>

#include "compare.hpp"
#include "ngi/device.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "runtime/context.hpp"

namespace ngi::test {

// Holder of the test device; tests/main.cpp empties it before main returns (see there).
inline std::optional<Device>& device_slot() {
    static std::optional<Device> d;
    return d;
}

// The device every test runs on: $NGI_TEST_DEVICE, else PoCL's CPU device ("cpu").
inline Device& device() {
    std::optional<Device>& d = device_slot();
    if (!d) {
        const char* e = std::getenv("NGI_TEST_DEVICE");
        d.emplace(Device::open(e && *e ? e : "cpu"));
    }
    return *d;
}
inline void release_device() { device_slot().reset(); }

// The GEMM knob sets the table picks for a GPU and for a CPU, each with its fallback chain, without duplicates.
// Chosen by describing a GPU and a CPU to gemm_params_for, not by the device under test: oclgrind presents only
// a GPU, yet the CPU sets must run under it too.
inline std::vector<detail::GemmParams> gpu_and_cpu_gemm_variants() {
    DeviceInfo gpu, cpu;
    gpu.is_gpu = true;
    cpu.is_cpu = true;
    std::vector<detail::GemmParams> sets;
    for (const DeviceInfo* info : {&gpu, &cpu})
        for (const detail::GemmParams& p : detail::gemm_fallback_chain(detail::gemm_params_for(*info)))
            if (std::find(sets.begin(), sets.end(), p) == sets.end()) sets.push_back(p);
    return sets;
}
inline detail::Context& ctx() { return ngi::detail::context_of(device()); }

inline std::vector<float> random_vector(std::size_t n, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
    std::uniform_real_distribution<float> u(lo, hi);
    std::vector<float> v(n);
    for (auto& x : v) x = u(rng);
    return v;
}

inline detail::Buffer upload(const std::vector<float>& v) {
    auto b = ctx().alloc(v.size() * sizeof(float), "test input");
    ctx().write(b, 0, v.size() * sizeof(float), v.data(), "test input");
    return b;
}

inline std::vector<float> download(const detail::Buffer& b, std::size_t n, std::size_t offset = 0) {
    std::vector<float> v(n);
    ctx().read(b, offset * sizeof(float), n * sizeof(float), v.data(), "test output");
    return v;
}

// Checks got against want under tol (tests/compare.hpp: the one comparison of the suite, its tolerance kinds and
// their NaN / Inf rules). On failure Catch prints the caller's file and line, the worst element (index, both values,
// the bound) and the tolerance's name and reason. Returns the comparison (ratio, max_abs: for WARNs and reports).
template <class Got, class Want>
Comparison check_close(const Got& got, const Want& want, const Tol& tol, std::span<const char> skip = {},
                       std::source_location at = std::source_location::current()) {
    const Comparison r = compare(got, want, tol, skip);
    INFO(at.file_name() << ":" << at.line() << ": " << r.report());
    CHECK(r.ok);
    return r;
}
// The same, ending the test case on failure.
template <class Got, class Want>
Comparison require_close(const Got& got, const Want& want, const Tol& tol, std::span<const char> skip = {},
                         std::source_location at = std::source_location::current()) {
    const Comparison r = compare(got, want, tol, skip);
    INFO(at.file_name() << ":" << at.line() << ": " << r.report());
    REQUIRE(r.ok);
    return r;
}
// A comparison made elsewhere (a helper that also ran the op), checked here.
inline void check_comparison(const Comparison& r, std::source_location at = std::source_location::current()) {
    INFO(at.file_name() << ":" << at.line() << ": " << r.report());
    CHECK(r.ok);
}
// One value against its reference.
inline Comparison check_value(double got, double want, const Tol& tol,
                              std::source_location at = std::source_location::current()) {
    const Comparison r = compare_value(got, want, tol);
    INFO(at.file_name() << ":" << at.line() << ": " << r.report());
    CHECK(r.ok);
    return r;
}
inline Comparison require_value(double got, double want, const Tol& tol,
                                std::source_location at = std::source_location::current()) {
    const Comparison r = compare_value(got, want, tol);
    INFO(at.file_name() << ":" << at.line() << ": " << r.report());
    REQUIRE(r.ok);
    return r;
}

// The older forms, still used by the model, pipeline and renderer tests (the op tests use check_close):
// largest |a-b| / (atol + rtol*|b|) (<= 1 means every element is within tolerance), and the largest |a-b|.
inline double worst_ratio(const std::vector<float>& a, const std::vector<float>& b, double atol, double rtol) {
    double worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!std::isfinite(a[i])) return INFINITY;
        worst = std::max(worst, std::abs(double(a[i]) - b[i]) / (atol + rtol * std::abs(double(b[i]))));
    }
    return worst;
}

inline double max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    double m = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!std::isfinite(a[i])) return INFINITY;
        m = std::max(m, std::abs(double(a[i]) - double(b[i])));
    }
    return m;
}

inline bool all_finite(const std::vector<float>& v) {
    for (float x : v) if (!std::isfinite(x)) return false;
    return true;
}

// Runs tests/parity/<script> --out <build>/<name> once per build tree (Debian's /usr/bin/python3, which has
// torch / numpy / skimage; PYTHONPATH=<build>/python, where the build assembles the Python package ngi) unless
// <build>/<name>/cases.json exists, and returns that folder. The script's output goes to <build>/<name>.log.
inline std::filesystem::path python_oracle_data(const std::string& script, const std::string& name) {
    const std::filesystem::path dir = std::filesystem::path(NGI_BINARY_DIR) / name;
    if (!std::filesystem::exists(dir / "cases.json")) {
        const std::string cmd = "PYTHONPATH=" + std::string(NGI_BINARY_DIR) + "/python /usr/bin/python3 " +
                                std::string(NGI_SOURCE_DIR) + "/tests/parity/" + script + " --out " + dir.string() +
                                " > " + dir.string() + ".log 2>&1";
        INFO("running: " << cmd);
        REQUIRE(std::system(cmd.c_str()) == 0);
    }
    return dir;
}

}  // namespace ngi::test

// Shared helpers for the Catch2 suite: the device under test, random data, comparisons, naive references.
#pragma once
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

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

// Largest |a-b| / (atol + rtol*|b|); <= 1 means every element is within tolerance.
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

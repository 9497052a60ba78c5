#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "ngi/device.hpp"
#include "ngi/error.hpp"
#include "ngi/self_check.hpp"

namespace ngi_cli {

namespace {

// Lists every OpenCL device, and (unless --no-check) opens each one and runs ngi's self-check on it: which GEMM
// variant passed against the host reference, which were refused and why, and the driver's loop limit.
int run(bool no_check) {
    const auto devices = ngi::list_devices();
    if (devices.empty()) {
        std::printf("no OpenCL devices found (install an ICD, e.g. pocl-opencl-icd)\n");
        return kExitDevice;
    }
    int failed = 0;
    for (const auto& d : devices) {
        std::printf("%d:%d  %s  [%s]\n", d.platform_index, d.device_index, d.name.c_str(),
                    d.is_gpu ? "gpu" : d.is_cpu ? "cpu" : "other");
        std::printf("      platform %s, %s, driver %s, %s\n", d.platform_name.c_str(), d.device_version.c_str(),
                    d.driver_version.c_str(), d.opencl_c_version.c_str());
        std::printf("      %u compute units, max work-group %zu, local memory %zu KiB (%s), global %zu MiB, "
                    "max alloc %zu MiB, fp16 %s, native float vector %u\n",
                    d.compute_units, d.max_work_group_size, d.local_mem_bytes / 1024,
                    d.local_mem_is_dedicated ? "dedicated" : "global", d.global_mem_bytes >> 20,
                    d.max_alloc_bytes >> 20, d.fp16 ? "yes" : "no",
                    d.native_float_vector_width);
        if (no_check) continue;
        try {
            const ngi::Device dev =
                ngi::Device::open(std::to_string(d.platform_index) + ":" + std::to_string(d.device_index));
            const ngi::SelfCheckReport r = ngi::self_check(dev);
            std::printf("      self-check: GEMM %s passed", r.gemm_variant.c_str());
            if (r.rejected.empty()) std::printf(" (the table's choice)\n");
            else std::printf(" after rejecting:\n");
            for (const auto& why : r.rejected) std::printf("        %s\n", why.c_str());
            if (r.loop_limit > 0)
                std::printf("      loop limit: the driver ends every loop after %ld iterations per work-item "
                            "(docs/RELIABILITY.md)\n", r.loop_limit);
        } catch (const ngi::Error& e) {
            std::printf("      self-check FAILED: %s\n", e.what());
            ++failed;
        }
    }
    return failed ? kExitDevice : kExitOk;
}

}  // namespace

Run add_devices(CLI::App& app) {
    auto no_check = std::make_shared<bool>(false);
    CLI::App* cmd = add_command(app, "devices", "list OpenCL devices, their capabilities and ngi's self-check on each",
                                "The self-check: the GEMM variant in use, the variants refused and why, the driver's "
                                "loop limit. Exit code 3 when there is no device or a self-check fails.");
    add_switch(*cmd, "--no-check", *no_check, "only list the devices: no self-check");
    return [no_check] { return run(*no_check); };
}

}  // namespace ngi_cli

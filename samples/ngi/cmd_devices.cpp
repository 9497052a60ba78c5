#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/device.hpp"
#include "ngi/error.hpp"
#include "ngi/self_check.hpp"

namespace ngi_cli {

namespace {

using json = nlohmann::json;

// One device's self-check: which GEMM variant passed against the host reference, which were refused and why,
// the driver's loop limit; "ok": false with the error when no variant computes correct results.
json check_device(const ngi::DeviceInfo& d) {
    try {
        const ngi::Device dev = ngi::Device::open(std::to_string(d.platform_index) + ":" + std::to_string(d.device_index));
        const ngi::SelfCheckReport r = ngi::self_check(dev);
        return {{"ok", true}, {"gemm_variant", r.gemm_variant}, {"table_choice", r.rejected.empty()},
                {"rejected", r.rejected}, {"loop_limit", r.loop_limit}};
    } catch (const ngi::Error& e) {
        return {{"ok", false}, {"error", e.what()}};
    }
}

json device_json(const ngi::DeviceInfo& d) {
    return {{"spec", std::to_string(d.platform_index) + ":" + std::to_string(d.device_index)},
            {"name", d.name}, {"platform", d.platform_name}, {"vendor", d.vendor}, {"driver", d.driver_version},
            {"device_version", d.device_version}, {"opencl_c_version", d.opencl_c_version}, {"type", d.type_name()},
            {"compute_units", d.compute_units}, {"max_work_group_size", d.max_work_group_size},
            {"local_mem_bytes", d.local_mem_bytes}, {"local_mem_dedicated", d.local_mem_is_dedicated},
            {"global_mem_bytes", d.global_mem_bytes}, {"max_alloc_bytes", d.max_alloc_bytes}, {"fp16", d.fp16},
            {"native_float_vector_width", d.native_float_vector_width}};
}

// Lists every OpenCL device, and (unless --no-check) opens each one and runs ngi's self-check on it: which GEMM
// variant passed against the host reference, which were refused and why, and the driver's loop limit. --json: the
// same as one JSON array on stdout (tools/gpu_check.sh reads it).
int run(bool no_check, bool as_json) {
    const auto devices = ngi::list_devices();
    if (devices.empty()) {
        if (as_json) std::printf("[]\n");
        else std::printf("no OpenCL devices found (install an ICD, e.g. pocl-opencl-icd)\n");
        return kExitDevice;
    }
    int failed = 0;
    json all = json::array();
    for (const auto& d : devices) {
        if (as_json) {
            json j = device_json(d);
            if (!no_check) {
                j["self_check"] = check_device(d);
                failed += j["self_check"]["ok"].get<bool>() ? 0 : 1;
            }
            all.push_back(j);
            continue;
        }
        std::printf("%d:%d  %s  [%s]\n", d.platform_index, d.device_index, d.name.c_str(), d.type_name());
        std::printf("      platform %s, %s, driver %s, %s\n", d.platform_name.c_str(), d.device_version.c_str(),
                    d.driver_version.c_str(), d.opencl_c_version.c_str());
        std::printf("      %u compute units, max work-group %zu, local memory %zu KiB (%s), global %zu MiB, "
                    "max alloc %zu MiB, fp16 %s, native float vector %u\n",
                    d.compute_units, d.max_work_group_size, d.local_mem_bytes / 1024,
                    d.local_mem_is_dedicated ? "dedicated" : "global", d.global_mem_bytes >> 20,
                    d.max_alloc_bytes >> 20, d.fp16 ? "yes" : "no",
                    d.native_float_vector_width);
        if (no_check) continue;
        const json c = check_device(d);
        if (!c["ok"].get<bool>()) {
            std::printf("      self-check FAILED: %s\n", c["error"].get<std::string>().c_str());
            ++failed;
            continue;
        }
        std::printf("      self-check: GEMM %s passed", c["gemm_variant"].get<std::string>().c_str());
        if (c["table_choice"].get<bool>()) std::printf(" (the table's choice)\n");
        else std::printf(" after rejecting:\n");
        for (const auto& why : c["rejected"]) std::printf("        %s\n", why.get<std::string>().c_str());
        if (const long limit = c["loop_limit"].get<long>(); limit > 0)
            std::printf("      loop limit: the driver ends every loop after %ld iterations per work-item "
                        "(docs/RELIABILITY.md)\n", limit);
    }
    if (as_json) std::printf("%s\n", all.dump(1).c_str());
    return failed ? kExitDevice : kExitOk;
}

}  // namespace

Run add_devices(CLI::App& app) {
    auto no_check = std::make_shared<bool>(false);
    auto as_json = std::make_shared<bool>(false);
    CLI::App* cmd = add_command(app, "devices", "list OpenCL devices, their capabilities and ngi's self-check on each",
                                "The self-check: the GEMM variant in use, the variants refused and why, the driver's "
                                "loop limit. Exit code 3 when there is no device or a self-check fails.");
    add_switch(*cmd, "--no-check", *no_check, "only list the devices: no self-check");
    add_switch(*cmd, "--json", *as_json, "print one JSON array (spec, capabilities, self_check) instead of text");
    return [no_check, as_json] { return run(*no_check, *as_json); };
}

}  // namespace ngi_cli

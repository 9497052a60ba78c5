#include <cstdio>

#include "commands.hpp"
#include "ngi/device.hpp"

namespace ngi_cli {

int cmd_devices(int argc, char** argv) {
    Args args(argc, argv, 2, {}, {});
    no_positionals(args);
    const auto devices = ngi::list_devices();
    if (devices.empty()) {
        std::printf("no OpenCL devices found (install an ICD, e.g. pocl-opencl-icd)\n");
        return 1;
    }
    for (const auto& d : devices) {
        std::printf("%d:%d  %s  [%s]\n", d.platform_index, d.device_index, d.name.c_str(),
                    d.is_gpu ? "gpu" : d.is_cpu ? "cpu" : "other");
        std::printf("      platform %s, %s, driver %s, %s\n", d.platform_name.c_str(), d.device_version.c_str(),
                    d.driver_version.c_str(), d.opencl_c_version.c_str());
        std::printf("      %u compute units, max work-group %zu, local memory %zu KiB (%s), global %zu MiB, "
                    "max alloc %zu MiB, fp16 %s\n",
                    d.compute_units, d.max_work_group_size, d.local_mem_bytes / 1024,
                    d.local_mem_is_dedicated ? "dedicated" : "global", d.global_mem_bytes >> 20,
                    d.max_alloc_bytes >> 20, d.fp16 ? "yes" : "no");
    }
    return 0;
}

}  // namespace ngi_cli

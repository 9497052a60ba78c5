// What ngi verified about a device before trusting it (docs/RELIABILITY.md).
#pragma once
#include <string>
#include <vector>

#include "ngi/device.hpp"

namespace ngi {

struct SelfCheckReport {
    std::string gemm_variant;           // GEMM knobs in use on this device, "MR,VW,NV,KU,L0,L1,UNROLL"
    std::vector<std::string> rejected;  // variants tried first and refused, each with the reason
    long loop_limit = 0;                // loop iterations per work-item before the driver ends loops; 0 = no limit
};

// Runs (once per device and driver, cached on disk in $NGI_CACHE_DIR) the GEMM variants ngi would use on
// realistic problems against a host reference and picks the first that agrees; Model::load does the same.
// Throws ngi::Error if no variant computes correct results on this device.
SelfCheckReport self_check(const Device& device);

}  // namespace ngi

// The GEMM self-check: before a GEMM variant (a knob set of kernels/gemm.cl) is used on a device, it must
// reproduce a host double-precision reference on small and realistic problems. A variant that disagrees — a
// driver miscompile, a loop limiter, a build or launch failure — is skipped for the next in a fallback chain
// of ever safer variants, and the reason is reported (ngi devices, stderr once per process).
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ngi/self_check.hpp"
#include "ops/gemm.hpp"

namespace ngi::detail {

struct GemmVerdict {
    bool ok = false;
    double worst = 0;    // largest |got - ref| / (1e-4 + 1e-4 |ref|) over the check problems; <= 1 passes
    std::string reason;  // why it failed ("" when ok)
};

// One check problem: C (M x N) = A (M x K) B (K x N), random operands with outputs of order 1.
struct GemmProblem {
    int m, n, k;
};

// The problems every variant must pass: tile-remainder sizes, the deepest K of the shipped generator families
// (ngf 64: 512 x 4 x 4 = 8192) and an up-convolution's tall M.
const std::vector<GemmProblem>& gemm_check_problems();

// $NGI_SELFCHECK: unset or "full" (the default) checks every problem above; "small" only the first one. For
// instruction-level simulators only (oclgrind runs the K = 8192 problem for minutes): the small set cannot see
// a loop limiter or a miscompile that only deep K shows, so never use it for real runs. Other values throw
// InputError. Small-set verdicts are cached apart from full ones.
bool gemm_selfcheck_is_small();
std::vector<GemmProblem> gemm_selfcheck_problems();

// Runs `p` on the device for each problem and compares with the host reference. Never throws for a variant
// that fails to build or launch: that is a failed verdict with the OpenCL error as the reason.
GemmVerdict check_gemm_variant(Context& ctx, const GemmParams& p, const std::vector<GemmProblem>& problems);

// preferred, then the same tile with preprocessor unrolling, narrower vectors (VW halved, NV doubled: the same
// NR), for a gemm_local preferred (KWG > 0) the same tile on gemm_packed (no local memory, no barriers), a 4x4
// tile, and the scalar 1x1 kernel last.
std::vector<GemmParams> gemm_fallback_chain(const GemmParams& preferred);

// Every knob set the tuner tries on this kind of device (perf/ngi_bench tune), the table's choice first; gemm_local
// sets (KWG > 0) on GPUs and devices with dedicated local memory, where they fit it.
std::vector<GemmParams> gemm_tuning_space(const DeviceInfo& info);

struct GemmSelection {
    GemmParams params;
    std::vector<std::pair<GemmParams, GemmVerdict>> rejected;
    // The implicit convolution's knob set (conv_params_for), checked like the GEMM's; params if it was rejected;
    // nullopt where the tuning database turns the implicit path off (convolutions take the im2col path).
    std::optional<GemmParams> conv_params;
};

using GemmChecker = std::function<GemmVerdict(Context&, const GemmParams&)>;

// The first variant of `chain` that `checker` accepts. Throws Error naming every rejection if none is.
GemmSelection select_gemm(Context& ctx, const std::vector<GemmParams>& chain, const GemmChecker& checker);

// Verdicts cached on disk per (device, driver, kernel source, knobs): a second process does not re-run them.
GemmVerdict cached_check(Context& ctx, const GemmParams& p);

// The selection for this context: computed once (select_gemm over gemm_fallback_chain(gemm_params_for(info))
// with cached_check), logged to stderr once if anything was rejected. What models and ngi devices use.
const GemmSelection& gemm_selection(Context& ctx);

}  // namespace ngi::detail

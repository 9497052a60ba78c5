#include "ops/sh.hpp"

namespace ngi::detail {

ShEvaluate::ShEvaluate(Context& ctx) : kernel_(ctx.kernel("sh", "sh_evaluate")) {}

cl_event ShEvaluate::enqueue(Context& ctx, cl_mem coef, cl_mem dir, int n, int channels, bool irradiance, cl_mem out,
                             bool want_event) {
    if (n <= 0) return nullptr;
    if (channels < 1) throw InputError("SH evaluate: " + std::to_string(channels) + " channels");
    static const std::size_t local[1] = {64};
    kernel_.args(coef, dir, n, channels, int(irradiance), out);
    const std::size_t g[1] = {std::size_t(n)};
    return ctx.launch(kernel_, 1, g, local, want_event);
}

}  // namespace ngi::detail

// Per-image batch normalization (statistics of the image itself over H x W), in place, with a fused activation.
// Eval-mode batch norm (running statistics) has no op of its own: it is folded into the conv epilogue.
#pragma once
#include <optional>
#include <vector>

#include "ops/view.hpp"
#include "ops/op_types.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

class BatchNormPerImage {
public:
    // chunked: each work-item reduces a contiguous range (best on CPUs) rather than an interleaved one (best on
    // GPUs); by default chosen from the device type. Both give the same statistics up to rounding.
    BatchNormPerImage(Context& ctx, int channels, const std::vector<float>& gamma, const std::vector<float>& beta,
                      float eps, Act act, std::optional<bool> chunked = std::nullopt);
    std::size_t scratch_floats(const Shape& s) const { return 3 * std::size_t(s.c); }  // shift, mean, rstd
    void enqueue(Context& ctx, const View& x, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);

private:
    int channels_;
    float eps_;
    Act act_;
    Kernel stats_, apply_;
    Buffer gamma_, beta_;
};

}  // namespace ngi::detail

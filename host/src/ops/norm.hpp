// Per-image batch normalization (statistics of the image itself over H x W), in place, with a fused activation.
// Eval-mode batch norm (running statistics) has no op of its own: it is folded into the conv epilogue.
#pragma once
#include <vector>

#include "ops/view.hpp"
#include "ngi/ops.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

class BatchNormPerImage {
public:
    BatchNormPerImage(Context& ctx, int channels, const std::vector<float>& gamma, const std::vector<float>& beta,
                      float eps, Act act);
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

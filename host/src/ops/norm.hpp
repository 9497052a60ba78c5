// Per-image batch normalization (statistics of the image itself over H x W), in place, with a fused activation.
// Eval-mode batch norm (running statistics) has no op of its own: it is folded into the conv epilogue.
#pragma once
#include <optional>
#include <vector>

#include "ops/view.hpp"
#include "ops/op_types.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// On a GPU, planes of at most this many values are normalized in one launch (channel_norm: statistics and
// normalization by one work-group per channel, the second read from cache); larger ones in two (channel_stats, then
// channel_affine_act over every value, which fills a GPU where one work-group per channel would not). 16,384 floats
// is 64 KiB per channel. CPUs take the one-launch form at every size: on PoCL it measured faster everywhere, from
// the launch-bound planes of the N = 64 generators (11 batch norms, 2.2 -> 0.4 ms) to the thesis generator's 32K-value
// planes (its batch norms 82-97 ms in two launches, 12-13 ms in one; docs/PERFORMANCE.md, "small shapes").
constexpr int kFusedNormPlaneMax = 16384;
// Planes of at most this many values: one work-item per channel (channel_norm_serial), no work-group per channel.
constexpr int kSerialNormPlaneMax = 256;

class BatchNormPerImage {
public:
    // chunked: each work-item reduces a contiguous range (best on CPUs) rather than an interleaved one (best on
    // GPUs); by default chosen from the device type. Both give the same statistics up to rounding.
    // form: automatic picks serial up to kSerialNormPlaneMax values per plane, then work_group (on a GPU up to
    // kFusedNormPlaneMax, two_pass above). two_pass and work_group compute the same values (the same arithmetic in
    // the same order); serial the same statistics up to rounding.
    enum class Form { automatic, two_pass, work_group, serial };
    BatchNormPerImage(Context& ctx, int channels, const std::vector<float>& gamma, const std::vector<float>& beta,
                      float eps, Act act, std::optional<bool> chunked = std::nullopt, Form form = Form::automatic);
    std::size_t scratch_floats(const Shape& s) const { return 3 * std::size_t(s.c); }  // shift, mean, rstd
    void enqueue(Context& ctx, const View& x, cl_mem scratch, std::size_t scratch_off,
                 std::vector<cl_event>* events = nullptr);

private:
    int channels_;
    float eps_;
    Act act_;
    Form form_;
    bool cpu_;
    Kernel stats_, apply_, fused_kernel_, serial_kernel_;
    Buffer gamma_, beta_;
};

}  // namespace ngi::detail

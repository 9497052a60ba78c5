#include "ops/norm.hpp"

namespace ngi::detail {

namespace {
constexpr int kStatsLocal = 64;  // work-group of the reduction (norm.cl LOCAL)
constexpr std::size_t kSerialLocal = 16;  // channels per work-group of channel_norm_serial (fixed: PoCL compiles one
                                          // work-group function per local size)
const std::size_t kApplyLocal[2] = {64, 1};

std::string norm_defines(bool chunked) {
    return "-DLOCAL=" + std::to_string(kStatsLocal) + " -DCHUNKED=" + (chunked ? "1" : "0") + " " +
           activation_defines();
}
}  // namespace

BatchNormPerImage::BatchNormPerImage(Context& ctx, int channels, const std::vector<float>& gamma,
                                     const std::vector<float>& beta, float eps, Act act,
                                     std::optional<bool> chunked, Form form)
    : channels_(channels),
      eps_(eps),
      act_(act),
      form_(form),
      cpu_(ctx.info().is_cpu),
      stats_(ctx.kernel("norm", "channel_stats", norm_defines(chunked.value_or(ctx.info().is_cpu)))),
      apply_(ctx.kernel("norm", "channel_affine_act", norm_defines(chunked.value_or(ctx.info().is_cpu)))),
      fused_kernel_(ctx.kernel("norm", "channel_norm", norm_defines(chunked.value_or(ctx.info().is_cpu)))),
      serial_kernel_(ctx.kernel("norm", "channel_norm_serial", norm_defines(chunked.value_or(ctx.info().is_cpu)))) {
    if (int(gamma.size()) != channels || int(beta.size()) != channels)
        throw InputError("batch norm: expected " + std::to_string(channels) + " gamma and beta values, got " +
                         std::to_string(gamma.size()) + " and " + std::to_string(beta.size()));
    gamma_ = ctx.alloc(gamma.size() * sizeof(float), "batch norm gamma");
    beta_ = ctx.alloc(beta.size() * sizeof(float), "batch norm beta");
    ctx.write(gamma_, 0, gamma.size() * sizeof(float), gamma.data(), "batch norm gamma");
    ctx.write(beta_, 0, beta.size() * sizeof(float), beta.data(), "batch norm beta");
}

void BatchNormPerImage::enqueue(Context& ctx, const View& x, cl_mem scratch, std::size_t scratch_off,
                                std::vector<cl_event>* events) {
    if (x.shape.c != channels_)
        throw InputError("batch norm: input has " + std::to_string(x.shape.c) + " channels, expected " +
                         std::to_string(channels_));
    const int hw = x.shape.h * x.shape.w;
    const std::size_t gs[1] = {std::size_t(channels_) * kStatsLocal};
    const std::size_t ls[1] = {std::size_t(kStatsLocal)};
    const Form form = form_ != Form::automatic ? form_
                      : hw <= kSerialNormPlaneMax                 ? Form::serial
                      : cpu_ || hw <= kFusedNormPlaneMax          ? Form::work_group
                                                                  : Form::two_pass;
    if (form == Form::serial) {
        serial_kernel_.args(x.mem, int(x.offset), channels_, hw, eps_, gamma_.get(), beta_.get(), int(act_.kind),
                            act_.alpha);
        const std::size_t g[1] = {std::size_t(channels_)}, l[1] = {kSerialLocal};
        cl_event e = ctx.launch(serial_kernel_, 1, g, l, events != nullptr);
        if (events && e) events->push_back(e);
        return;
    }
    if (form == Form::work_group) {
        fused_kernel_.args(x.mem, int(x.offset), hw, eps_, gamma_.get(), beta_.get(), int(act_.kind), act_.alpha);
        cl_event e = ctx.launch(fused_kernel_, 1, gs, ls, events != nullptr);
        if (events && e) events->push_back(e);
        return;
    }
    stats_.args(x.mem, int(x.offset), hw, eps_, scratch, int(scratch_off));
    cl_event e = ctx.launch(stats_, 1, gs, ls, events != nullptr);
    if (events && e) events->push_back(e);
    apply_.args(x.mem, int(x.offset), channels_, hw, scratch, int(scratch_off), gamma_.get(), beta_.get(), int(act_.kind), act_.alpha);
    const std::size_t ga[2] = {std::size_t(hw), std::size_t(channels_)};
    e = ctx.launch(apply_, 2, ga, kApplyLocal, events != nullptr);
    if (events && e) events->push_back(e);
}

}  // namespace ngi::detail

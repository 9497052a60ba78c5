#include "ops/jbu.hpp"

#include <cmath>
#include <cstdint>
#include <string>

#include "ops/buffer_checks.hpp"

namespace ngi::detail {

namespace {

constexpr const char* kOp = "joint bilateral upsampling";

void require_side(int v, const char* name) {
    if (v < 1 || v > kJbuMaxSide)
        throw InputError(std::string(kOp) + ": " + name + " " + std::to_string(v) + " (1 to " +
                         std::to_string(kJbuMaxSide) + " supported)");
}

void require_param(bool ok, const char* name, float v, const char* range) {
    if (!ok) throw InputError(std::string(kOp) + ": " + name + " " + std::to_string(v) + " is not " + range);
}

}  // namespace

JointBilateralUpsample::JointBilateralUpsample(Context& ctx)
    : kernel_(ctx.kernel("jbu", "jbu_upsample", jbu_defines())),
      vector_device_(jbu_vector_device(ctx.info())),
      fallbacks_(ctx.alloc(sizeof(std::uint32_t), "joint bilateral upsampling: fallback counter")) {}

int JointBilateralUpsample::enqueue(Context& ctx, const JbuInputs& in, const JbuParams& p, cl_mem out,
                                    bool read_count) {
    require_side(in.low_width, "low-resolution width");
    require_side(in.low_height, "low-resolution height");
    require_side(in.width, "output width");
    require_side(in.height, "output height");
    if (in.channels < 1 || in.channels > kJbuMaxChannels)
        throw InputError(std::string(kOp) + ": " + std::to_string(in.channels) + " channels (1 to " +
                         std::to_string(kJbuMaxChannels) + " supported)");
    require_param(std::isfinite(p.sigma_spatial) && p.sigma_spatial > 0.0f, "sigma_spatial", p.sigma_spatial,
                  "finite and > 0");
    require_param(std::isfinite(p.sigma_plane) && p.sigma_plane > 0.0f, "sigma_plane", p.sigma_plane,
                  "finite and > 0");
    require_param(std::isfinite(p.normal_power) && p.normal_power >= 0.0f && p.normal_power <= 1024.0f,
                  "normal_power", p.normal_power, "in [0, 1024]");
    require_param(std::isfinite(p.fallback_ratio) && p.fallback_ratio >= 0.0f && p.fallback_ratio < 1.0f,
                  "fallback_ratio", p.fallback_ratio, "in [0, 1)");
    if (p.radius < 1 || p.radius > kJbuMaxRadius)
        throw InputError(std::string(kOp) + ": radius " + std::to_string(p.radius) + " (1 to " +
                         std::to_string(kJbuMaxRadius) + " supported)");
    // exp(-d^2 / (2 sigma^2)) with the reciprocal folded on the host; a sigma so small that it overflows is refused.
    const double s2 = 1.0 / (2.0 * double(p.sigma_spatial) * p.sigma_spatial);
    const double p2 = 1.0 / (2.0 * double(p.sigma_plane) * p.sigma_plane);
    require_param(s2 < 3.0e38, "sigma_spatial", p.sigma_spatial, "large enough (1/(2 sigma^2) overflows a float)");
    require_param(p2 < 3.0e38, "sigma_plane", p.sigma_plane, "large enough (1/(2 sigma^2) overflows a float)");

    const std::size_t lo = std::size_t(in.low_width) * in.low_height, hi = std::size_t(in.width) * in.height;
    const std::string low_size = "a " + std::to_string(in.low_width) + "x" + std::to_string(in.low_height) + " image";
    const std::string hi_size = "a " + std::to_string(in.width) + "x" + std::to_string(in.height) + " image";
    const std::string ch = " of " + std::to_string(in.channels) + " channels";
    require_buffer(in.low, in.channels * lo * sizeof(float), kOp, "low-resolution input", low_size + ch);
    require_buffer(in.low_normal, 3 * lo * sizeof(float), kOp, "low-resolution normal", low_size);
    require_buffer(in.low_position, 3 * lo * sizeof(float), kOp, "low-resolution position", low_size);
    require_buffer(in.normal, 3 * hi * sizeof(float), kOp, "normal", hi_size);
    require_buffer(in.position, 3 * hi * sizeof(float), kOp, "position", hi_size);
    require_buffer(out, in.channels * hi * sizeof(float), kOp, "output", hi_size + ch);
    if (double(in.channels) * double(hi) > 2147483647.0 || double(in.channels) * double(lo) > 2147483647.0)
        throw InputError(std::string(kOp) + ": more than 2^31 - 1 values in one image");
    for (cl_mem m : {in.low, in.low_normal, in.low_position, in.normal, in.position})
        if (m == out) throw InputError(std::string(kOp) + ": the output buffer is also an input");

    ctx.fill_zero(fallbacks_, 0, fallbacks_.bytes(), "joint bilateral upsampling: fallback counter");
    using K = JbuParams::Kernel;
    if (p.kernel == K::Rows8 && in.channels > kJbuVecMaxChannels)
        throw InputError(std::string(kOp) + ": the Rows8 kernel takes 1 to " + std::to_string(kJbuVecMaxChannels) +
                         " channels, not " + std::to_string(in.channels));
    const bool vec = p.kernel == K::Rows8 ||
                     (p.kernel == K::Auto && vector_device_ && in.channels <= kJbuVecMaxChannels);
    // The vector kernel's program is built only where it runs (llvmpipe took ~65 s to build it).
    if (vec && !kernel_vec_.get()) {
        kernel_vec_ = ctx.kernel("jbu_vec", "jbu_upsample8", jbu_defines());
        pack_taps_ = ctx.kernel("jbu_vec", "jbu_pack_taps", jbu_defines());
    }
    Kernel& k = vec ? kernel_vec_ : kernel_;
    if (vec) {
        // The taps' records for the shared-columns path (kernels/jbu_vec.cl jbu_pack_taps, one work-item per texel;
        // not made when the knob turns that path off).
        ensure_buffer(ctx, taps_, kJbuTapFloats * lo * sizeof(float), "joint bilateral upsampling: tap records");
        if (p.shared_columns) {
            pack_taps_.args(in.low, in.low_normal, in.low_position, in.low_width, in.low_height, in.channels, taps_);
            const std::size_t items[1] = {round_up(lo, 64)}, group[1] = {64};
            ctx.launch(pack_taps_, 1, items, group);
        }
        k.args(in.low, in.low_normal, in.low_position, in.low_width, in.low_height, in.channels, in.normal, in.position,
               in.width, in.height, float(s2), p.normal_power, float(p2), p.radius, p.fallback_ratio,
               int(p.shared_columns), taps_, out, fallbacks_);
    } else {
        k.args(in.low, in.low_normal, in.low_position, in.low_width, in.low_height, in.channels, in.normal, in.position,
               in.width, in.height, float(s2), p.normal_power, float(p2), p.radius, p.fallback_ratio, out, fallbacks_);
    }
    static const std::size_t local[2] = {8, 8};
    const std::size_t global[2] = {vec ? (std::size_t(in.width) + kJbuVec - 1) / kJbuVec : std::size_t(in.width),
                                   std::size_t(in.height)};
    ctx.launch(k, 2, global, local);
    return read_count ? fallback_count(ctx) : -1;
}

int JointBilateralUpsample::fallback_count(Context& ctx) const {
    std::uint32_t v = 0;
    ctx.read(fallbacks_, 0, sizeof v, &v, "joint bilateral upsampling: fallback counter");
    return int(v);
}

}  // namespace ngi::detail

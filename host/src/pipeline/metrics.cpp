// MSE / PSNR / SSIM: enqueues kernels/metrics.cl and adds the per-work-group partial sums in double.
#include "ngi/metrics.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi {
namespace {

constexpr double kSigma = 1.5, kTruncate = 3.5, kK1 = 0.01, kK2 = 0.03;
constexpr int kRadius = int(kTruncate * kSigma + 0.5);  // scipy.ndimage's radius: 5, i.e. 11 taps (SSIM_R)
constexpr int kTile = 16;                               // ssim_tiles' work-group: TILE x TILE
constexpr int kSeLocal = 256;                           // squared_error_partials' work-group (SE_LOCAL)
constexpr std::size_t kSeMaxGroups = 1024;
// Squares of 1e15 are 1e30; a work-group adds at most a few hundred of them: far below FLT_MAX (3.4e38).
constexpr float kMaxMagnitude = 1e15f;

std::string dims(const Image& i) {
    return std::to_string(i.width) + "x" + std::to_string(i.height) + "x" + std::to_string(i.channels);
}

void check_inputs(const Image& a, const Image& b, const char* op) {
    const std::string what = std::string(op) + ": ";
    for (const Image* i : {&a, &b})
        if (i->width <= 0 || i->height <= 0 || i->channels <= 0 || i->data.size() != i->plane() * i->channels)
            throw InputError(what + "invalid image " + dims(*i) + " with " + std::to_string(i->data.size()) + " values");
    if (a.width != b.width || a.height != b.height || a.channels != b.channels)
        throw InputError(what + "images differ in size: " + dims(a) + " vs " + dims(b) + " (width x height x channels)");
    if (a.data.size() > std::size_t(std::numeric_limits<int>::max()))
        throw InputError(what + "image too large (" + dims(a) + ")");
    const char* names[] = {"first", "second"};
    int k = 0;
    for (const Image* i : {&a, &b}) {
        std::size_t bad = 0, huge = 0;
        for (float v : i->data) {
            bad += !std::isfinite(v);
            huge += std::isfinite(v) && std::abs(v) > kMaxMagnitude;
        }
        if (bad)
            throw InputError(what + "the " + names[k] + " image has " + std::to_string(bad) + " NaN/Inf values");
        if (huge)
            throw InputError(what + "the " + names[k] + " image has " + std::to_string(huge) +
                             " values beyond +-1e15, whose squares would overflow the float32 sums");
        ++k;
    }
}

// allow_zero: compare_images reports the metrics a zero range leaves undefined instead of failing (the range of an
// all-zero reference is 0, and a sky-only frame has an all-zero lightmap reference).
// A positive range lies in [kMinRange, kMaxRange]: the values' own bound above, and below it SSIM's constants
// C1 = (0.01 R)^2, C2 = (0.03 R)^2 stay normal float32 numbers. Outside, the kernel's float(C1) was Inf (R = 1e38:
// SSIM NaN with no note) or 0 (R = 1e-45: 0 / 0 in constant windows), and PSNR said -892 dB of an image whose
// values are 10^45 ranges away from the one it names.
constexpr double kMinRange = 1e-15, kMaxRange = 1e15;  // (1e15 itself: float(1e15) is a little below it)

bool range_usable(double data_range) {
    return data_range == 0.0 || (data_range >= kMinRange && data_range <= kMaxRange);
}

std::string range_text(double data_range) {
    char got[32];
    std::snprintf(got, sizeof got, "%g", data_range);
    return got;
}

// compare_images (allow_zero) reports a range outside [kMinRange, kMaxRange] as undefined metrics with a note;
// ssim() has no room for a note and refuses it.
void check_range(double data_range, const char* op, bool allow_zero) {
    if (!(allow_zero ? data_range >= 0.0 : data_range > 0.0) || !std::isfinite(data_range))
        throw InputError(std::string(op) + ": data_range must be finite and " + (allow_zero ? ">= 0" : "> 0") +
                         ", got " + std::to_string(data_range));
    if (!allow_zero && !range_usable(data_range))
        throw InputError(std::string(op) + ": data_range must be in [1e-15, 1e15] (the values' bound; beyond it "
                         "SSIM's constants are not float32 numbers), got " + range_text(data_range));
}

struct Pair {
    detail::Buffer a, b;
};

Pair upload(detail::Context& ctx, const Image& a, const Image& b) {
    const std::size_t bytes = a.data.size() * sizeof(float);
    Pair p{ctx.alloc(bytes, "metrics image a"), ctx.alloc(bytes, "metrics image b")};
    ctx.write(p.a, 0, bytes, a.data.data(), "metrics image a");
    ctx.write(p.b, 0, bytes, b.data.data(), "metrics image b");
    return p;
}

double run_mse(detail::Context& ctx, const Pair& p, std::size_t n) {
    const std::size_t groups = std::min(kSeMaxGroups, (n + kSeLocal - 1) / std::size_t(kSeLocal));
    detail::Buffer partial = ctx.alloc(groups * sizeof(float), "squared-error partial sums");
    detail::Kernel k = ctx.kernel("metrics", "squared_error_partials", detail::metrics_defines());
    k.args(p.a, p.b, int(n), partial);
    const std::size_t global = groups * kSeLocal, local = kSeLocal;
    ctx.launch(k, 1, &global, &local);
    std::vector<float> sums(groups);
    ctx.read(partial, 0, groups * sizeof(float), sums.data(), "squared-error partial sums");
    double total = 0;
    for (float s : sums) total += s;
    return total / double(n);
}

double run_ssim(detail::Context& ctx, const Pair& p, int width, int height, int channels, double data_range) {
    // scipy.ndimage's 1-D Gaussian: exp(-x^2 / (2 sigma^2)) for x in [-r, r], normalized to sum 1.
    std::vector<double> wd(2 * kRadius + 1);
    double wsum = 0;
    for (int x = -kRadius; x <= kRadius; ++x) wsum += wd[x + kRadius] = std::exp(-0.5 * x * x / (kSigma * kSigma));
    std::vector<float> w(wd.size());
    for (std::size_t i = 0; i < wd.size(); ++i) w[i] = float(wd[i] / wsum);
    detail::Buffer weights = ctx.alloc(w.size() * sizeof(float), "SSIM Gaussian weights");
    ctx.write(weights, 0, w.size() * sizeof(float), w.data(), "SSIM Gaussian weights");

    // Only the map pixels skimage keeps after cropping kRadius from every border: a (W - 2r) x (H - 2r) grid.
    const int crop_w = width - 2 * kRadius, crop_h = height - 2 * kRadius;
    const std::size_t gx = (crop_w + kTile - 1) / kTile, gy = (crop_h + kTile - 1) / kTile;
    const std::size_t count = gx * gy * std::size_t(channels);
    detail::Buffer partial = ctx.alloc(count * sizeof(float), "SSIM partial sums");
    detail::Kernel k = ctx.kernel("metrics", "ssim_tiles", detail::metrics_defines());
    const double c1 = (kK1 * data_range) * (kK1 * data_range), c2 = (kK2 * data_range) * (kK2 * data_range);
    k.args(p.a, p.b, width, height, weights, float(c1), float(c2), partial);
    const std::size_t global[3] = {gx * kTile, gy * kTile, std::size_t(channels)}, local[3] = {kTile, kTile, 1};
    ctx.launch(k, 3, global, local);
    std::vector<float> sums(count);
    ctx.read(partial, 0, count * sizeof(float), sums.data(), "SSIM partial sums");
    // Per channel mean, then the mean over channels (skimage's channel_axis loop).
    double total = 0;
    for (int c = 0; c < channels; ++c) {
        double s = 0;
        for (std::size_t i = 0; i < gx * gy; ++i) s += sums[c * gx * gy + i];
        total += s / (double(crop_w) * crop_h);
    }
    return total / channels;
}

bool ssim_fits(const Image& a) { return a.width >= 2 * kRadius + 1 && a.height >= 2 * kRadius + 1; }

std::string ssim_size_message(const Image& a) {
    return "SSIM needs images of at least " + std::to_string(2 * kRadius + 1) + "x" + std::to_string(2 * kRadius + 1) +
           " pixels (the Gaussian window), got " + std::to_string(a.width) + "x" + std::to_string(a.height);
}

void check_ssim_size(const Image& a, const char* op) {
    if (!ssim_fits(a)) throw InputError(std::string(op) + ": " + ssim_size_message(a));
}

void append_json_string(std::string& out, const std::string& s) {
    out += '"';
    for (const char c : s) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            out += buf;
        } else {
            out += c;
        }
    }
    out += '"';
}

void append_json_number(std::string& out, double v) {
    if (!std::isfinite(v)) {
        out += "null";
        return;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    out += buf;
}

}  // namespace

std::string detail::metrics_defines() {
    return join_defines({define("SSIM_R", kRadius), define("TILE", kTile), define("SE_LOCAL", kSeLocal)});
}

double psnr_from_mse(double mse, double data_range) {
    if (mse == 0.0) return std::numeric_limits<double>::infinity();
    if (data_range == 0.0) return std::numeric_limits<double>::quiet_NaN();
    // As two logarithms: data_range^2 / mse would overflow for data ranges beyond 1e154.
    return 20.0 * std::log10(data_range) - 10.0 * std::log10(mse);
}

double mse(const Device& device, const Image& a, const Image& b) {
    check_inputs(a, b, "mse");
    detail::Context& ctx = ngi::detail::context_of(device);
    return run_mse(ctx, upload(ctx, a, b), a.data.size());
}

double ssim(const Device& device, const Image& a, const Image& b, double data_range) {
    check_inputs(a, b, "ssim");
    check_range(data_range, "ssim", false);
    check_ssim_size(a, "ssim");
    detail::Context& ctx = ngi::detail::context_of(device);
    return run_ssim(ctx, upload(ctx, a, b), a.width, a.height, a.channels, data_range);
}

ImageMetrics compare_images(const Device& device, const Image& a, const Image& b, double data_range) {
    check_inputs(a, b, "compare images");
    check_range(data_range, "compare images", true);
    detail::Context& ctx = ngi::detail::context_of(device);
    const Pair p = upload(ctx, a, b);
    ImageMetrics m;
    m.mse = run_mse(ctx, p, a.data.size());
    m.psnr = psnr_from_mse(m.mse, data_range);
    const bool usable = range_usable(data_range);
    const std::string unusable = "data_range " + range_text(data_range) + " is outside [1e-15, 1e15] (the values' "
                                 "bound; beyond it SSIM's constants are not float32 numbers): ";
    if (m.mse == 0.0) {
        m.psnr_note = "mse is 0 (identical images): PSNR is +infinity";
    } else if (data_range == 0.0) {
        m.psnr_note = "data_range is 0 (e.g. an all-zero reference): PSNR is undefined";
    } else if (!usable) {
        m.psnr = std::numeric_limits<double>::quiet_NaN();
        m.psnr_note = unusable + "PSNR is not reported";
    }
    // Exact equality on the host (the MSE cannot tell: squares of differences below 1e-19 underflow to 0).
    const bool identical = a.data == b.data;
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    if (!ssim_fits(a)) {
        m.ssim = nan;
        m.ssim_note = ssim_size_message(a);
    } else if (identical) {
        m.ssim = 1.0;  // by definition, also where C1 = C2 = 0 would make the formula 0 / 0
    } else if (!usable) {
        m.ssim = nan;
        m.ssim_note = unusable + "SSIM is not reported";
    } else if (data_range == 0.0) {
        m.ssim = nan;
        m.ssim_note = "data_range is 0 (e.g. an all-zero reference): SSIM's constants C1 = C2 = 0 leave it "
                      "undefined (0 / 0 wherever a window is constant)";
    } else {
        m.ssim = run_ssim(ctx, p, a.width, a.height, a.channels, data_range);
    }
    return m;
}

std::string to_json(const ImageMetrics& m) {
    std::string out = "{\"mse\": ";
    append_json_number(out, m.mse);
    out += ", \"psnr\": ";
    append_json_number(out, m.psnr);
    out += ", \"ssim\": ";
    append_json_number(out, m.ssim);
    if (!std::isfinite(m.psnr)) {
        out += ", \"psnr_note\": ";
        append_json_string(out, m.psnr_note);
    }
    if (!std::isfinite(m.ssim)) {
        out += ", \"ssim_note\": ";
        append_json_string(out, m.ssim_note);
    }
    out += "}";
    return out;
}

}  // namespace ngi

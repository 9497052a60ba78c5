// Image quality metrics on the device, matching scikit-image (skimage.metrics):
//   mse   mean over every pixel and channel of (a - b)^2                           (mean_squared_error)
//   psnr  10 log10(data_range^2 / mse) dB                                         (peak_signal_noise_ratio)
//   ssim  Wang et al. 2004: 11x11 Gaussian window (sigma 1.5, truncated at 3.5 sigma), K1 = 0.01, K2 = 0.03,
//         population (co)variances, per channel, averaged over the map with a 5-pixel border cropped (as
//         skimage does), then over channels    (structural_similarity(gaussian_weights=True, sigma=1.5,
//                                               use_sample_covariance=False, data_range=..., channel_axis=0))
// data_range is the distance between the smallest and largest possible value: 1 for [0, 1] images (the default),
// for HDR images the range the comparison is meant over (e.g. the reference's maximum). It sets PSNR's peak and
// SSIM's stabilizing constants C1 = (K1 R)^2, C2 = (K2 R)^2, which keep SSIM defined for constant images.
//
// Edge cases (docs/CONVENTIONS.md, "Metrics"): compare_images never throws for them; a value that is not a
// finite number comes with a note saying why, and JSON (to_json) writes it as null next to that note:
//   identical images (mse 0)          psnr +infinity; ssim exactly 1 (for any data_range, also 0)
//   data_range 0, images differ       psnr NaN, ssim NaN: undefined (skimage: -inf and 0, or NaN if both are 0)
//   smaller than 11x11                ssim NaN: no full window fits (skimage raises); mse and psnr are computed
// A constant (e.g. all-zero) reference with data_range > 0 is no edge case: C1, C2 > 0 keep SSIM defined.
//
// Inputs must have the same width, height and channel count and hold only finite values within +-1e15
// (InputError otherwise: NaN would silently poison every sum, and larger values overflow float32 squares).
// The single-value functions ssim() and psnr_from_mse() have no room for a note: ssim() throws InputError below
// 11x11 or for data_range <= 0, like skimage.
#pragma once
#include "ngi/device.hpp"
#include "ngi/image.hpp"

#include <string>

namespace ngi {

struct ImageMetrics {
    double mse = 0;
    double psnr = 0;        // dB; +infinity when mse == 0, NaN when undefined (psnr_note says which)
    double ssim = 0;        // NaN when undefined (ssim_note says why)
    std::string psnr_note;  // empty when psnr is a finite number
    std::string ssim_note;  // empty when ssim is a number
};

// data_range: finite and >= 0 (0: e.g. the maximum of an all-zero reference; PSNR and SSIM are then undefined
// unless the images are identical).
ImageMetrics compare_images(const Device& device, const Image& a, const Image& b, double data_range = 1.0);
double mse(const Device& device, const Image& a, const Image& b);
double ssim(const Device& device, const Image& a, const Image& b, double data_range = 1.0);
// +infinity when mse == 0 (whatever the range), NaN when data_range == 0 < mse.
double psnr_from_mse(double mse, double data_range);

// One JSON object {"mse": .., "psnr": .., "ssim": ..}; JSON has no infinity or NaN, so a psnr or ssim that is not
// a finite number is written as null and its note is added as "psnr_note" / "ssim_note" (only then).
// Numbers are written with 17 significant digits (they read back to the same double).
std::string to_json(const ImageMetrics& m);

}  // namespace ngi

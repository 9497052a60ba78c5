// Image quality metrics on the device, matching scikit-image (skimage.metrics):
//   mse   mean over every pixel and channel of (a - b)^2                           (mean_squared_error)
//   psnr  10 log10(data_range^2 / mse) dB, +infinity when mse == 0                (peak_signal_noise_ratio)
//   ssim  Wang et al. 2004: 11x11 Gaussian window (sigma 1.5, truncated at 3.5 sigma), K1 = 0.01, K2 = 0.03,
//         population (co)variances, per channel, averaged over the map with a 5-pixel border cropped (as
//         skimage does), then over channels    (structural_similarity(gaussian_weights=True, sigma=1.5,
//                                               use_sample_covariance=False, data_range=..., channel_axis=0))
// data_range is the distance between the smallest and largest possible value: 1 for [0, 1] images (the default),
// for HDR images the range the comparison is meant over (e.g. the reference's maximum). It sets PSNR's peak and
// SSIM's stabilizing constants C1 = (K1 R)^2, C2 = (K2 R)^2.
//
// Inputs must have the same width, height and channel count and hold only finite values within +-1e15
// (InputError otherwise: NaN would silently poison every sum, and larger values overflow float32 squares).
// SSIM needs at least 11x11 pixels, like skimage.
#pragma once
#include "ngi/device.hpp"
#include "ngi/image.hpp"

namespace ngi {

struct ImageMetrics {
    double mse = 0;
    double psnr = 0;  // +infinity for identical images
    double ssim = 0;
};

ImageMetrics compare_images(const Device& device, const Image& a, const Image& b, double data_range = 1.0);
double mse(const Device& device, const Image& a, const Image& b);
double ssim(const Device& device, const Image& a, const Image& b, double data_range = 1.0);
double psnr_from_mse(double mse, double data_range);  // +infinity when mse == 0

}  // namespace ngi

#!/usr/bin/python3
"""Reference values for ngi's image metrics, from scikit-image (Debian's python3-skimage).

Writes random image pairs as float32 .npy files, shape [C, H, W], and cases.json with scikit-image's MSE, PSNR and
SSIM for each pair. The metrics are computed in float64 on the float32 values (skimage keeps float32 inputs in
float32, which would make the reference itself noisier than ngi), with the settings that reproduce Wang et al.
2004: gaussian_weights=True, sigma=1.5, use_sample_covariance=False, an explicit data_range, channel_axis=0.

Usage: ssim_reference.py --out DIR
"""
import argparse
import json
import math
import os

import numpy as np
from skimage.metrics import mean_squared_error, peak_signal_noise_ratio, structural_similarity


def smooth_image(rng, c, h, w):
    # Structured content (gradients, waves, a few edges): SSIM's structure term matters here, unlike on noise.
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    out = np.empty((c, h, w))
    for k in range(c):
        fx, fy = rng.uniform(0.02, 0.3, 2)
        out[k] = 0.5 + 0.3 * np.sin(fx * x + k) * np.cos(fy * y) + 0.1 * (x / w) + 0.1 * (y > h / 2)
    return out


def case_pairs(rng):
    """(name, a, b, data_range) with a, b float32 [C, H, W]."""
    cases = []
    for (c, h, w) in [(1, 11, 11), (3, 16, 16), (1, 37, 23), (3, 64, 48), (3, 129, 97), (1, 200, 131)]:
        a = rng.uniform(0, 1, (c, h, w))
        b = np.clip(a + rng.normal(0, 0.1, a.shape), 0, 1)
        cases.append((f"noise_{c}x{h}x{w}", a, b, 1.0))
        s = smooth_image(rng, c, h, w)
        t = np.clip(s + rng.normal(0, 0.03, s.shape), 0, 1)
        cases.append((f"smooth_{c}x{h}x{w}", s, t, 1.0))
    # HDR radiance (log-normal, up to a few thousand) compared over its own range, and over range 1 (the case
    # where E[x^2] - E[x]^2 cancels badly in float: large means, small constants).
    for (c, h, w) in [(3, 57, 83), (1, 96, 96)]:
        a = np.exp(rng.normal(1.0, 1.5, (c, h, w)))
        b = a * np.exp(rng.normal(0, 0.1, a.shape))
        cases.append((f"hdr_{c}x{h}x{w}_range_max", a, b, float(a.max())))
        cases.append((f"hdr_{c}x{h}x{w}_range_1", a, b, 1.0))
    # Large offset, small detail: flat-looking images far from zero.
    a = 100.0 + rng.normal(0, 0.01, (3, 40, 40))
    b = a + rng.normal(0, 0.01, a.shape)
    cases.append(("offset_3x40x40_range_1", a, b, 1.0))
    # Unrelated and inverted images: SSIM near 0 and negative.
    a = rng.uniform(0, 1, (3, 45, 51))
    cases.append(("independent_3x45x51", a, rng.uniform(0, 1, a.shape), 1.0))
    s = smooth_image(rng, 1, 50, 50)
    cases.append(("inverted_1x50x50", s, 1.0 - s, 1.0))
    a = rng.uniform(0, 1, (3, 33, 35))
    cases.append(("identical_3x33x35", a, a.copy(), 1.0))
    # Edge cases (docs/CONVENTIONS.md, Metrics): empty and constant ("pure sky") references, where Wang's C1, C2
    # keep SSIM defined; HDR values beyond the largest half float (65504) over their own range and over range 1.
    zero, sky = np.zeros((3, 24, 20)), np.full((3, 24, 20), 0.37)
    cases.append(("zero_identical_3x24x20", zero, zero.copy(), 1.0))
    cases.append(("constant_identical_3x24x20", sky, sky.copy(), 1.0))
    cases.append(("zero_reference_3x24x20", rng.uniform(0, 1, zero.shape), zero, 1.0))
    cases.append(("constant_reference_3x24x20", np.clip(sky + rng.normal(0, 0.05, sky.shape), 0, 1), sky, 1.0))
    cases.append(("two_constants_3x24x20", np.full(sky.shape, 0.8), sky, 1.0))
    a = 65504.0 * np.exp(rng.normal(0.0, 1.0, (3, 29, 32)))
    b = a * np.exp(rng.normal(0, 0.05, a.shape))
    cases.append(("hdr_beyond_half_3x29x32_range_max", a, b, float(a.max())))
    cases.append(("hdr_beyond_half_3x29x32_range_1", a, b, 1.0))
    return [(n, a.astype(np.float32), b.astype(np.float32), r) for (n, a, b, r) in cases]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rng = np.random.default_rng(20240607)
    out = []
    for name, a, b, data_range in case_pairs(rng):
        a64, b64 = a.astype(np.float64), b.astype(np.float64)
        if a.shape[0] == 1:
            ssim = structural_similarity(a64[0], b64[0], gaussian_weights=True, sigma=1.5,
                                         use_sample_covariance=False, data_range=data_range)
        else:
            ssim = structural_similarity(a64, b64, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                         data_range=data_range, channel_axis=0)
        mse = mean_squared_error(a64, b64)
        with np.errstate(divide="ignore"):
            psnr = peak_signal_noise_ratio(a64, b64, data_range=data_range)
        np.save(os.path.join(args.out, f"{name}_a.npy"), a)
        np.save(os.path.join(args.out, f"{name}_b.npy"), b)
        out.append({"name": name, "a": f"{name}_a.npy", "b": f"{name}_b.npy", "data_range": data_range,
                    "mse": float(mse), "psnr": None if math.isinf(psnr) else float(psnr),  # JSON has no infinity
                    "ssim": float(ssim)})
        print(f"{name:32s} range {data_range:10.3f}  mse {mse:.6g}  psnr {psnr:.4f}  ssim {ssim:.8f}")
    tmp = os.path.join(args.out, "cases.json.tmp")
    with open(tmp, "w") as f:
        json.dump(out, f, indent=1)
    os.replace(tmp, os.path.join(args.out, "cases.json"))  # cases.json appears last: its presence means complete


if __name__ == "__main__":
    main()

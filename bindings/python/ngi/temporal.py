"""Temporal stability of a sequence of output images: flicker measures that need no optical flow.

Both compare consecutive frames t-1, t of a sequence; a model's value is read against the path-traced
reference's own value on the same frames (the reference changes too: the camera moves, the sun moves, and it has
its own Monte Carlo noise), so "excess" = model - reference is the flicker the model adds (negative: smoother than
the truth, e.g. a lagging light level).

- mabd: mean absolute brightness difference (Neural GI, seed 002, after TecoGAN): the mean over pixels and over
  t of |Y_t - Y_t-1|, Y = Rec. 709 luminance of the tone-mapped image. Pixel-aligned, so it is the natural
  measure for a fixed camera.
- warp_error: the same difference after exact reprojection (Lai et al. 2018, with the renderer's geometry instead
  of optical flow): each pixel of frame t is lifted to its world point with its planar depth and camera, projected
  into frame t-1's camera and compared with frame t-1's nearest pixel there (RGB mean absolute difference).
  Pixels that leave the view, see the sky (depth > 1000 m) or are occluded in t-1 (depths differ by more than
  2% + 5 cm) are left out. Diffuse lighting does not depend on the view, so a perfect, noise-free output would
  score 0 up to resampling; the reference's own value is that floor plus its noise.

Cameras follow docs/CONVENTIONS.md: the front face looks along `look` with a 90-degree field of view, right =
look x up (up re-orthogonalized), pixel (col, row) looks along look + u right + v up with
u = 2 (col + 0.5) / N - 1, v = 1 - 2 (row + 0.5) / N; depth is planar (along look).
"""

import numpy as np

from . import _constants
from .scoring import luminance

SKY_DEPTH = _constants.MAX_SURFACE_DEPTH  # beyond it a texel is no surface (host/src/base/surface_depth.hpp)


def mabd(images):
    """Mean over t >= 1 of the mean |Y_t - Y_t-1| of a list of [3, H, W] tone-mapped images."""
    if len(images) < 2:
        raise ValueError("mabd: a sequence needs at least two frames")
    ys = [luminance(im) for im in images]
    return float(np.mean([np.mean(np.abs(b - a)) for a, b in zip(ys, ys[1:])]))


def _basis(look, up):
    look = np.asarray(look, np.float64)
    look = look / np.linalg.norm(look)
    up = np.asarray(up, np.float64)
    up = up - np.dot(up, look) * look
    up = up / np.linalg.norm(up)
    return look, np.cross(look, up), up


def world_points(depth, camera):
    """The world point [N, N, 3] (float64) each pixel of a front view sees: planar depth [N, N] along the camera's
    look, camera = (position, look, up) with the 90-degree view of docs/CONVENTIONS.md."""
    n = depth.shape[0]
    pos, look, right, up = (np.asarray(camera[0], np.float64), *_basis(camera[1], camera[2]))
    c = 2.0 * (np.arange(n) + 0.5) / n - 1.0
    u, v = np.meshgrid(c, -c)  # v: row 0 is the top
    d = depth.astype(np.float64)
    return pos + d[..., None] * (look + u[..., None] * right + v[..., None] * up)


def reprojection(depth_t, camera_t, camera_prev):
    """For every pixel of frame t (planar depth [N, N]; camera = (position, look, up)): the (row, col) of frame
    t-1's pixel that sees the same world point, and the point's planar depth in t-1's camera. Returns
    (rows, cols, depth_in_prev, inside) with `inside` False where the point is behind or outside t-1's view or
    frame t sees the sky."""
    n = depth_t.shape[0]
    pos_p, look_p, right_p, up_p = (np.asarray(camera_prev[0], np.float64), *_basis(camera_prev[1], camera_prev[2]))
    d = depth_t.astype(np.float64)
    q = world_points(depth_t, camera_t) - pos_p
    z = q @ look_p
    safe = np.where(z > 1e-6, z, 1.0)
    up_ = (q @ right_p) / safe
    vp_ = (q @ up_p) / safe
    cols = np.floor((up_ + 1.0) * n / 2.0).astype(np.int64)
    rows = np.floor((1.0 - vp_) * n / 2.0).astype(np.int64)
    inside = (z > 1e-6) & (cols >= 0) & (cols < n) & (rows >= 0) & (rows < n) & (d < SKY_DEPTH)
    return np.clip(rows, 0, n - 1), np.clip(cols, 0, n - 1), z, inside


def warp_masks(depths, cameras):
    """Per t >= 1: (rows, cols, valid) mapping frame t's pixels into frame t-1 (see reprojection), valid = inside
    and not occluded in t-1."""
    out = []
    for t in range(1, len(depths)):
        rows, cols, z, inside = reprojection(depths[t], cameras[t], cameras[t - 1])
        seen = depths[t - 1][rows, cols]
        valid = inside & (np.abs(seen - z) <= 0.02 * z + 0.05)
        out.append((rows, cols, valid))
    return out


def warp_error(images, masks):
    """Mean over t >= 1 of the mean over valid pixels of |O_t - O_t-1(reprojected)| (RGB mean) for [3, N, N]
    images and warp_masks(...) of the same sequence. Also returns the mean share of valid pixels."""
    if len(images) < 2 or len(masks) != len(images) - 1:
        raise ValueError("warp_error: needs N >= 2 images and the N - 1 masks of the same sequence")
    errs, shares = [], []
    for t, (rows, cols, valid) in enumerate(masks, start=1):
        if not valid.any():
            continue
        prev = images[t - 1][:, rows, cols]
        diff = np.mean(np.abs(images[t] - prev), axis=0)
        errs.append(float(np.mean(diff[valid])))
        shares.append(float(np.mean(valid)))
    if not errs:
        raise ValueError("warp_error: no pixel of any frame pair is visible in both frames")
    return float(np.mean(errs)), float(np.mean(shares))

"""Seed 001's ambient-occlusion MLP: the data conventions shared by training (ao_train.py) and evaluation
(ao_eval.py). The C++ side (ngi::AoNetwork, kernels/ao.cl) implements the same ring gather; docs/RESULTS_AO.md.

An AO frame folder (written by `ngi ao-data`) holds normal.npy [3, N, N] (smooth object-space normals, zero where
no surface), face_normal.npy [3, N, N], depth.npy [1, N, N] (planar, 1e4 = no surface), ao.npy [1, N, N] (the
ray-traced reference in [0, 1], 1 = unoccluded) and view.json (camera position, look, up); scenes with triangles
also surface.npy [6, N, N] (the visible triangle's three vertex indices, -1 where none, and barycentric weights).

The network input of a pixel is 48 floats: the normals at 16 points on a circle of `radius_px` pixels around it,
point k at angle 2 pi k / 16 (k = 0 to the right, counter-clockwise on screen, i.e. towards smaller rows), each
rounded to the nearest pixel, channel 3 k + c = component c of point k's normal. A point outside the image or on
the background takes the centre pixel's normal ("background samples take the centre's normal"). radius 0 = the
seed's inference (all 16 = the pixel's own normal).
"""

import json
import math
from pathlib import Path

import numpy as np

RING = 16
NORMAL_FILE = {"smooth": "normal", "face": "face_normal"}  # model metadata ao.normals -> the frame folder's file


def ring_offsets(radius_px):
    """[(dy, dx)] * 16, rounded to the nearest pixel (half away from zero, like C's lround)."""
    out = []
    for k in range(RING):
        a = 2.0 * math.pi * k / RING
        dx = radius_px * math.cos(a)
        dy = -radius_px * math.sin(a)
        out.append((int(math.copysign(math.floor(abs(dy) + 0.5), dy)), int(math.copysign(math.floor(abs(dx) + 0.5), dx))))
    return out


def load_view(folder):
    folder = Path(folder)
    v = {name: np.load(folder / f"{name}.npy").astype(np.float32)
         for name in ("normal", "face_normal", "depth", "ao")}
    v["view"] = json.loads((folder / "view.json").read_text())
    if (folder / "surface.npy").exists():
        v["surface"] = np.load(folder / "surface.npy").astype(np.float32)
    v["mask"] = np.abs(v["face_normal"]).sum(0) > 0
    return v


def views(data_dir, split):
    return sorted(p for p in (Path(data_dir) / split).glob("v*") if (p / "ao.npy").exists())


def ring_inputs(normal, mask, radius_px, rows, cols):
    """The 48 inputs at pixels (rows, cols): [len(rows), 48] float32."""
    n = normal.shape[1]
    centre = normal[:, rows, cols].T  # [P, 3]
    parts = []
    for dy, dx in ring_offsets(radius_px):
        r, c = rows + dy, cols + dx
        inside = (r >= 0) & (r < n) & (c >= 0) & (c < n)
        rc, cc = np.clip(r, 0, n - 1), np.clip(c, 0, n - 1)
        use = inside & mask[rc, cc]
        parts.append(np.where(use[:, None], normal[:, rc, cc].T, centre))
    return np.concatenate(parts, 1).astype(np.float32)


def image_inputs(v, radius_px):
    """[P, 48] for every foreground pixel of view v, and the (rows, cols) they belong to."""
    rows, cols = np.nonzero(v["mask"])
    return ring_inputs(v["normal"], v["mask"], radius_px, rows, cols), rows, cols


def sample(data_dir, radius_px, per_view=512, seed=1, normals="smooth"):
    """The seed's training set: `per_view` random foreground pixels of every orbit view. Returns X [S, 48],
    y [S] (reference AO) and the view index of each sample. normals: "smooth" (normal.npy) or "face"."""
    rng = np.random.default_rng(seed)
    xs, ys, ids = [], [], []
    for i, folder in enumerate(views(data_dir, "orbit")):
        v = load_view(folder)
        rows, cols = np.nonzero(v["mask"])
        pick = rng.choice(len(rows), size=min(per_view, len(rows)), replace=False)
        r, c = rows[pick], cols[pick]
        xs.append(ring_inputs(v[NORMAL_FILE[normals]], v["mask"], radius_px, r, c))
        ys.append(v["ao"][0, r, c])
        ids.append(np.full(len(r), i))
    return np.concatenate(xs), np.concatenate(ys).astype(np.float32), np.concatenate(ids)


def camera_rays(view, n):
    """Unit ray directions [3, n, n] of the front face (ngi/camera.hpp: right = look x up, square 90 degrees)."""
    look = np.asarray(view["look"], np.float64)
    look /= np.linalg.norm(look)
    up = np.asarray(view["up"], np.float64)
    right = np.cross(look, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, look)
    u = 2.0 * (np.arange(n) + 0.5) / n - 1.0
    vv = 1.0 - 2.0 * (np.arange(n) + 0.5) / n
    d = look[:, None, None] + u[None, None, :] * right[:, None, None] + vv[None, :, None] * up[:, None, None]
    return d / np.linalg.norm(d, axis=0, keepdims=True), look, right, up

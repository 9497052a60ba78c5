"""An irradiance-probe grid: the non-neural preparation of a static scene that issue 46 names as the competitor of a
network fitted to the scene (docs/ADAPT.md, "The probe grid").

Probes sit on a regular 3D grid (spacing s metres, probe (i, j, k) at ((i, j, k) + 0.5) s) wherever the grid point is
in air and a solid block is near enough for the probe to be a corner of some surface point's grid cell. Each probe
stores the SH projection (bands 0-2, RGB) of the *indirect* radiance arriving there (light that has bounced at least
once: Renderer.project_sh(indirect=True), path-traced), so an engine adds it to its own direct light. A surface point
p with normal n is shaded from the 8 probes of its grid cell (offset 1 cm along n), as DDGI does it (Majercik et al.
2019) with its Chebyshev visibility replaced by an exact test in a voxel world:

  weight = trilinear(p) * (((dir . n) + 1) / 2)^2 + 0.2)  * visible
  lighting(p) = max(0, sum_i weight_i E_i(n) / sum_i weight_i) / pi,  E_i(n) = sum_k A_l c_ik Y_k(n)

with `visible` = no solid block at any of `samples_per_block` samples per metre of the segment from p to the probe
(a sampled march: a segment that clips a block's corner by less than 1 / samples_per_block metres may pass), and the
cosine-lobe factors A_l of docs/CONVENTIONS.md section 14. Where every probe of the cell is hidden, the weights
without visibility are used (a probe behind a thin wall beats none); where the cell has no probe at all the indirect
light is 0. Units: lighting = irradiance / pi, as every "lighting" of ngi.
"""

import math

import numpy as np

from .temporal import SKY_DEPTH, world_points

# Cosine-lobe factors A_l per coefficient k = l (l + 1) + m (Ramamoorthi & Hanrahan 2001).
LOBE = np.array([math.pi] + [2.0 * math.pi / 3.0] * 3 + [math.pi / 4.0] * 5)
SURFACE_OFFSET = 0.01  # metres along the normal: the shaded point leaves its own block's surface


def sh9(d):
    """Real SH bands 0-2 with the Condon-Shortley phase (docs/CONVENTIONS.md section 14) of unit directions
    d [..., 3] -> [..., 9]."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([np.full_like(x, 0.28209479177387814), -0.48860251190291992 * y, 0.48860251190291992 * z,
                     -0.48860251190291992 * x, 1.0925484305920792 * x * y, -1.0925484305920792 * y * z,
                     0.31539156525252005 * (3.0 * z * z - 1.0), -1.0925484305920792 * x * z,
                     0.54627421529603959 * (x * x - y * y)], axis=-1)


def _dilate(solid, radius):
    """Blocks within `radius` blocks (Chebyshev distance) of a solid block, by separable running maxima (written
    here: scipy.ndimage's maximum_filter would do it, but the ngi package depends on NumPy only)."""
    out = solid.copy()
    for axis in range(3):
        grown = out.copy()
        for shift in range(1, radius + 1):
            for sign in (1, -1):
                moved = np.roll(out, sign * shift, axis=axis)
                edge = [slice(None)] * 3
                edge[axis] = slice(0, shift) if sign > 0 else slice(-shift, None)
                moved[tuple(edge)] = False  # no wrap-around
                grown |= moved
        out = grown
    return out


class ProbeGrid:
    """Probe positions of a scene (ngi.Scene.blocks [Z, Y, X]) at `spacing` metres; bake() fills `sh` [P, 3, 9]."""

    def __init__(self, blocks, spacing=2.0, samples_per_block=4):
        if not (spacing > 0 and math.isfinite(spacing)):
            raise ValueError(f"ProbeGrid: spacing {spacing} must be a positive number of metres")
        self.solid = np.asarray(blocks) != 0
        if self.solid.ndim != 3:
            raise ValueError(f"ProbeGrid: blocks must be [Z, Y, X], got shape {self.solid.shape}")
        self.size = np.array(self.solid.shape[::-1])  # x, y, z
        self.spacing = float(spacing)
        self.samples_per_block = int(samples_per_block)
        self.dims = np.maximum(1, np.ceil(self.size / self.spacing).astype(np.int64))  # probes along x, y, z
        ijk = np.stack(np.meshgrid(*[np.arange(n) for n in self.dims], indexing="ij"), -1).reshape(-1, 3)
        points = np.minimum((ijk + 0.5) * self.spacing, self.size)  # inside the grid's box
        cell = np.minimum(np.floor(points).astype(np.int64), self.size - 1)
        # A probe serves the surface points whose grid cell it is a corner of: a solid block within spacing * sqrt 3
        # (rounded up to whole blocks) of it.
        near = _dilate(self.solid, int(math.ceil(self.spacing * math.sqrt(3.0))))
        keep = ~self.solid[cell[:, 2], cell[:, 1], cell[:, 0]] & near[cell[:, 2], cell[:, 1], cell[:, 0]]
        self.points = points[keep].astype(np.float32)
        self.index = np.full(int(np.prod(self.dims)), -1, np.int64)
        self.index[np.flatnonzero(keep)] = np.arange(int(keep.sum()))
        self.index = self.index.reshape(tuple(self.dims))  # [i, j, k] along x, y, z
        self.sh = None

    @property
    def count(self):
        return len(self.points)

    def bake(self, renderer, time=None, directions=256, bounces=8, seed=0):
        """Path-traces every probe's indirect SH (Renderer.project_sh); returns {'seconds', 'rays'} of the call."""
        if self.count == 0:
            raise ValueError("ProbeGrid.bake: the grid has no probes (a scene without solid blocks)")
        out = renderer.project_sh(self.points, time=time, directions=directions, bounces=bounces, seed=seed,
                                  indirect=True)
        self.sh = np.asarray(out["sh"], np.float64)
        return {"seconds": out["seconds"], "rays": out["rays"]}

    def shade(self, depth, normal, camera):
        """Indirect lighting [3, N, N] of a front view: planar depth [N, N], unit normals [3, N, N], camera =
        (position, look, up) with ngi's 90-degree view (docs/CONVENTIONS.md; ngi.temporal's convention)."""
        if self.sh is None:
            raise ValueError("ProbeGrid.shade: bake() first")
        n = depth.shape[0]
        surface = depth < SKY_DEPTH
        nrm = np.moveaxis(normal.astype(np.float64), 0, -1)[surface]  # [S, 3]
        nrm /= np.maximum(np.linalg.norm(nrm, axis=-1, keepdims=True), 1e-12)
        p = world_points(depth, camera)[surface] + SURFACE_OFFSET * nrm
        g = p / self.spacing - 0.5
        base = np.floor(g).astype(np.int64)
        frac = g - base
        irr_basis = sh9(nrm) * LOBE  # [S, 9]
        steps = int(math.ceil(self.spacing * math.sqrt(3.0) * self.samples_per_block)) + 1
        t = (np.arange(steps) + 0.5) / steps
        total = np.zeros((len(p), 3))
        weight = np.zeros(len(p))
        total_any = np.zeros((len(p), 3))
        weight_any = np.zeros(len(p))
        for corner in range(8):
            offset = np.array([corner & 1, corner >> 1 & 1, corner >> 2 & 1])
            ijk = base + offset
            inside = np.all((ijk >= 0) & (ijk < self.dims), axis=-1)
            idx = np.where(inside, self.index[tuple(np.clip(ijk, 0, self.dims - 1).T)], -1)
            have = idx >= 0
            tri = np.prod(np.where(offset == 1, frac, 1.0 - frac), axis=-1)
            to = self.points[np.maximum(idx, 0)] - p  # a missing probe's weight is 0 below
            dist = np.maximum(np.linalg.norm(to, axis=-1), 1e-9)
            back = ((np.sum(to * nrm, axis=-1) / dist + 1.0) * 0.5) ** 2 + 0.2
            w = np.where(have, tri * back, 0.0)
            samples = p[:, None, :] + t[None, :, None] * to[:, None, :]  # [S, steps, 3]
            blk = np.floor(samples).astype(np.int64)
            in_grid = np.all((blk >= 0) & (blk < self.size), axis=-1)
            blk = np.clip(blk, 0, self.size - 1)
            hit = in_grid & self.solid[blk[..., 2], blk[..., 1], blk[..., 0]]
            visible = ~np.any(hit, axis=1)
            e = np.einsum("sck,sk->sc", self.sh[np.maximum(idx, 0)], irr_basis)
            total_any += w[:, None] * e
            weight_any += w
            wv = w * visible
            total += wv[:, None] * e
            weight += wv
        use_any = weight <= 1e-12
        total = np.where(use_any[:, None], total_any, total)
        weight = np.where(use_any, weight_any, weight)
        lit = np.where(weight[:, None] > 1e-12, total / np.maximum(weight, 1e-12)[:, None], 0.0)
        out = np.zeros((3, n, n), np.float32)
        out[:, surface] = (np.maximum(lit, 0.0) / math.pi).T
        return out

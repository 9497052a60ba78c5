"""Seed 004's voxel scenes: loading the data generator's scene folders, the standardization statistics (from the
training scenes only), and synthetic scenes of the same format for tests and timing.

A scene folder holds
    attributes.npy  float32 [V, 10]  per occupied voxel: block centre x, y, z (metres), albedo r, g, b,
                                     emission r, g, b, voxel id = x + X (y + Y z) of its cell, as a float
    sh.npy          float32 [V, 27]  the SH coefficients (bands 0-2 x RGB, [3][9], docs/CONVENTIONS.md
                                     section 14) of the light the voxel receives
    normal.npy      float32 [V, 3]   not a network input (seed 004 section 4.1 drops normals); optional here
    scene.json      {"grid": [X, Y, Z], "name": ...}
"""

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

INPUTS = 10
OUTPUTS = 27
ID_CHANNEL = 9
# Coefficients whose training spread is below this are constant in the data: standardized with std 1 (not 0).
MIN_STD = 1e-9


@dataclass
class Scene:
    name: str
    folder: str
    grid: tuple
    attributes: np.ndarray  # float32 [V, 10]
    sh: np.ndarray          # float32 [V, 27]

    @property
    def voxels(self):
        return len(self.attributes)


def _array(folder, name, columns):
    path = Path(folder) / name
    if not path.is_file():
        raise ValueError(f"{folder}: {name} is missing")
    a = np.load(path, allow_pickle=False)
    if a.ndim != 2 or a.shape[1] != columns or a.shape[0] < 1:
        raise ValueError(f"{path}: shape {list(a.shape)}, expected [V, {columns}] with V >= 1")
    a = a.astype(np.float32, copy=False)
    if not np.isfinite(a).all():
        raise ValueError(f"{path}: {int((~np.isfinite(a)).sum())} values are NaN or infinite")
    return a


def load_scene(folder):
    folder = Path(folder)
    meta_path = folder / "scene.json"
    if not meta_path.is_file():
        raise ValueError(f"{folder}: scene.json is missing (not a scene folder)")
    meta = json.loads(meta_path.read_text())
    grid = meta.get("grid")
    if not (isinstance(grid, list) and len(grid) == 3 and all(isinstance(g, int) and g >= 1 for g in grid)):
        raise ValueError(f"{meta_path}: 'grid' must be [X, Y, Z], positive integers, got {grid!r}")
    attributes = _array(folder, "attributes.npy", INPUTS)
    sh = _array(folder, "sh.npy", OUTPUTS)
    if len(sh) != len(attributes):
        raise ValueError(f"{folder}: attributes.npy has {len(attributes)} voxels, sh.npy {len(sh)}")
    ids = attributes[:, ID_CHANNEL].astype(np.float64)
    cells = grid[0] * grid[1] * grid[2]
    if (ids != np.round(ids)).any() or ids.min() < 0 or ids.max() >= cells:
        raise ValueError(f"{folder}: the voxel ids (column {ID_CHANNEL}) must be integers in [0, {cells}) for the "
                         f"grid {grid}; got {ids.min()} .. {ids.max()}")
    return Scene(str(meta.get("name", folder.name)), str(folder), tuple(grid), attributes, sh)


def load_scenes(folders, grid=None):
    """The scenes of `folders`, all of one grid (the inputs hold absolute positions and ids): `grid` if given, else
    the first scene's."""
    scenes = [load_scene(f) for f in folders]
    if not scenes:
        raise ValueError("no scene folders given")
    want = tuple(grid) if grid is not None else scenes[0].grid
    for s in scenes:
        if s.grid != want:
            raise ValueError(f"{s.folder}: grid {'x'.join(map(str, s.grid))}, but the model's grid is "
                             f"{'x'.join(map(str, want))} (positions and voxel ids are absolute: one grid per model)")
    return scenes


def digest(scenes):
    """Hex digest of the scenes' names and contents (a resumed run must see the same data)."""
    h = hashlib.sha1()
    for s in scenes:
        h.update(s.name.encode())
        h.update(np.ascontiguousarray(s.attributes).tobytes())
        h.update(np.ascontiguousarray(s.sh).tobytes())
    return h.hexdigest()


@dataclass
class Stats:
    """Standardization statistics (float64): inputs to [-1, 1] by the training range, outputs by mean and std."""
    input_lo: np.ndarray
    input_hi: np.ndarray
    output_mean: np.ndarray
    output_std: np.ndarray

    @staticmethod
    def from_scenes(scenes):
        x = np.concatenate([s.attributes for s in scenes]).astype(np.float64)
        y = np.concatenate([s.sh for s in scenes]).astype(np.float64)
        std = y.std(axis=0)
        return Stats(x.min(axis=0), x.max(axis=0), y.mean(axis=0), np.where(std > MIN_STD, std, 1.0))

    def to_dict(self):
        return {k: [float(v) for v in getattr(self, k)] for k in ("input_lo", "input_hi", "output_mean", "output_std")}

    @staticmethod
    def from_dict(d):
        return Stats(*(np.asarray(d[k], dtype=np.float64) for k in ("input_lo", "input_hi", "output_mean", "output_std")))


# ---- synthetic scenes --------------------------------------------------------------------------------------

def sh9(d):
    """Real SH bands 0-2 of unit directions d [..., 3] (docs/CONVENTIONS.md section 14) -> [..., 9]."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([np.full_like(x, 0.28209479177387814), -0.48860251190291992 * y, 0.48860251190291992 * z,
                     -0.48860251190291992 * x, 1.0925484305920792 * x * y, -1.0925484305920792 * y * z,
                     0.31539156525252005 * (3 * z * z - 1), -1.0925484305920792 * x * z,
                     0.54627421529603959 * (x * x - y * y)], axis=-1)


def make_synthetic_scene(folder, grid=(32, 32, 32), voxels=10000, seed=0, name=None, emitters=2):
    """Writes a scene folder of the data generator's format with a made-up light field: `voxels` random cells of
    the grid (1 m across), a smooth albedo, `emitters` clusters of emissive voxels, and SH = the emitters'
    radiance seen from each voxel, sum_j E_j Y(dir_ij) / (1 + (d_ij / 0.2)^2), plus a bounce term from the scene's
    mean albedo (global information only the set network can see). Not physics; a learnable target of the right
    shape and spread."""
    rng = np.random.default_rng(seed)
    X, Y, Z = grid
    if voxels > X * Y * Z:
        raise ValueError(f"{voxels} voxels do not fit a {X}x{Y}x{Z} grid")
    h = 1.0 / max(grid)
    cells = np.sort(rng.choice(X * Y * Z, size=voxels, replace=False))
    ix, iy, iz = cells % X, (cells // X) % Y, cells // (X * Y)
    pos = (np.stack([ix, iy, iz], axis=1) + 0.5) * h
    k = rng.normal(size=(3, 3)) * 2 * math.pi
    albedo = np.clip(rng.uniform(0.2, 0.8, size=3) + 0.25 * np.sin(pos @ k + rng.uniform(0, 6.3, size=3)), 0.02, 0.98)
    emission = np.zeros((voxels, 3))
    for _ in range(emitters):
        centre = pos[rng.integers(voxels)]
        near = np.argsort(((pos - centre) ** 2).sum(1))[:max(1, min(24, voxels // 4))]
        emission[near] = rng.uniform(2, 10) * rng.uniform(0.6, 1.0, size=3)
    lit = np.nonzero(emission.sum(1) > 0)[0]
    d = pos[lit][None, :, :] - pos[:, None, :]                      # [V, E, 3] voxel -> emitter
    r = np.linalg.norm(d, axis=2)
    w = np.where(r > 0, 1.0 / (1.0 + (r / 0.2) ** 2), 0.0)          # no self-illumination
    basis = sh9(d / np.maximum(r, 1e-9)[..., None])                 # [V, E, 9]
    sh = np.einsum("ve,ec,vek->vck", w, emission[lit], basis) / max(1, len(lit)) * 4
    bounce = albedo.mean(0) * emission.sum(0) / voxels * 50          # [3]: global, the same for every voxel
    sh[:, :, 0] += bounce[None, :] * 0.28209479177387814 * (0.5 + 0.5 * albedo)
    normals = np.eye(3)[rng.integers(3, size=voxels)] * rng.choice([-1.0, 1.0], size=(voxels, 1))
    attributes = np.concatenate([pos, albedo, emission, cells[:, None].astype(np.float64)], axis=1)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    np.save(folder / "attributes.npy", attributes.astype(np.float32))
    np.save(folder / "sh.npy", sh.reshape(voxels, OUTPUTS).astype(np.float32))
    np.save(folder / "normal.npy", normals.astype(np.float32))
    (folder / "scene.json").write_text(json.dumps({"grid": list(grid), "name": name or folder.name,
                                                   "voxel_size": h, "synthetic_seed": seed}) + "\n")
    return folder

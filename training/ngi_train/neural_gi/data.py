"""Seed 002's training data: frame folders of `ngi dataset` (front face only) -> the tensors ngi.neural_gi trains on.

Per frame (docs/RENDERER.md "Frame metadata", docs/CONVENTIONS.md sections 1-3):

    look, up, centre ("position"), area light: the frame's camera.json (the light and the centre are written there
                        only for a frame lit by an area light; a frame without them is refused)
    right   = normalize(cross(look, up')),  up' = up re-orthogonalized against look (camera.hpp's cluster basis;
              for the front face, alpha = beta x gamma = up' x (-look) = look x up')
    ray     = look + u right + v up',  u = 2 (col + 0.5) / N - 1,  v = 1 - 2 (row + 0.5) / N   (dot(ray, look) = 1)
    p       = centre + depth * ray       (depth = the planar depth along look: front_depth.exr)
    view    = normalize(p - centre)   (= normalize(ray) for depth > 0; camera -> point)
    light   = normalize(light centre - p)                            (point -> the area light's centre)
    normal, albedo, direct = front_normal / front_albedo / front_direct.exr; target = reference.exr

**Scene box**: [0, 0, 0] .. the scene's grid size in blocks (1 block = 1 m, the grid's minimum corner is the world
origin), read from `<split>/<scene>/scene.json` "size" (`ngi dataset` records it there; neither camera.json nor
dataset.json holds it). Every surface a primary ray can hit lies in it (outside the grid is empty).

**Sky** (no surface): pixels whose planar depth is >= SKY_DEPTH_MIN (the renderer writes exactly 1e4 m there). The
mask is 0 there and 1 elsewhere; the loss ignores masked pixels. Their inputs are what the formulas give, exactly as
ngi's kernel (kernels/neural_gi.cl, neural_gi_inputs) assembles them: p = centre + 1e4 x ray (far outside the box, so
the normalized position is clamped to +-1), normal, albedo and direct 0 (the renderer's sky values), view = the
ray, light direction from that far point. They are not zeroed: the U-Net sees them as the C++ side feeds them.
Their reference and albedo are 0, so the final image does not depend on the prediction there; evaluate.py sets
the predicted lighting to 0 there, as the reference is (the kernel does the same: indirect 0 without a surface).

Cache (CACHE/<split>/<scene>/<frame>.npy + .json), so that epochs cost no EXR decoding: one float32 array
[CHANNELS, N, N] per frame (world position, normal, albedo, view direction, direct, light direction, reference,
mask; raw, before the box normalization and the log of assemble_inputs), and a manifest with a stamp of the frame
folder (names, sizes and mtimes of its files). An entry is reused while its stamp matches, and written to a
temporary file and renamed, so an interrupted run leaves none half-written.
"""

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np
import torch

import ngi
from ngi.neural_gi import assemble_inputs

CACHE_FORMAT = 2  # 2: sky positions at depth 1e4, as the kernel
SKY_DEPTH = 1.0e4       # the renderer's planar depth where the primary ray escapes (docs/RENDERER.md)
SKY_DEPTH_MIN = 0.5 * SKY_DEPTH  # threshold: no voxel scene (<= 4096 blocks per axis) has a surface this far
# Channels of a cache entry, in order.
CHANNELS = ["position.x", "position.y", "position.z", "normal.x", "normal.y", "normal.z", "albedo.r", "albedo.g",
            "albedo.b", "view.x", "view.y", "view.z", "direct.r", "direct.g", "direct.b", "light_dir.x",
            "light_dir.y", "light_dir.z", "reference.r", "reference.g", "reference.b", "mask"]
SLICES = {"position": slice(0, 3), "normal": slice(3, 6), "albedo": slice(6, 9), "view": slice(9, 12),
          "direct": slice(12, 15), "light_dir": slice(15, 18), "reference": slice(18, 21), "mask": slice(21, 22)}


# --------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------

def camera_basis(look, up):
    """(look, right, up') unit vectors of the front face (CONVENTIONS section 1: up re-orthogonalized against look
    by Gram-Schmidt, right = look x up'), float64."""
    look = np.asarray(look, np.float64)
    up = np.asarray(up, np.float64)
    if not (np.isfinite(look).all() and np.isfinite(up).all()) or np.linalg.norm(look) == 0:
        raise ValueError(f"bad camera: look {look.tolist()}, up {up.tolist()}")
    f = look / np.linalg.norm(look)
    u = up - np.dot(up, f) * f
    if np.linalg.norm(u) < 1e-9:
        raise ValueError(f"camera up {up.tolist()} is parallel to look {look.tolist()}")
    u = u / np.linalg.norm(u)
    r = np.cross(f, u)
    return f, r / np.linalg.norm(r), u


def pixel_rays(n, look, up):
    """[3, n, n] unnormalized rays look + u right + v up' of the front face's pixel centres (row 0 = top)."""
    f, r, u = camera_basis(look, up)
    c = 2.0 * (np.arange(n, dtype=np.float64) + 0.5) / n - 1.0     # u per column
    v = 1.0 - 2.0 * (np.arange(n, dtype=np.float64) + 0.5) / n     # v per row
    return (f[:, None, None] + r[:, None, None] * c[None, None, :] + u[:, None, None] * v[None, :, None])


def _unit_np(v):
    norm = np.linalg.norm(v, axis=0, keepdims=True)
    return np.where(norm > 0, v / np.maximum(norm, 1e-30), 0.0)


def frame_geometry(depth, look, up, centre, light_centre):
    """World position, view direction and light direction [3, n, n] (float64) and the surface mask [1, n, n] of a
    front face with planar depth [1, n, n]. As kernels/neural_gi.cl: p = centre + depth x ray for every pixel (a NaN
    depth counts as 0), sky pixels included (depth 1e4: a point far outside the box)."""
    depth = np.asarray(depth, np.float64).reshape(1, *np.shape(depth)[-2:])
    n = depth.shape[-1]
    rays = pixel_rays(n, look, up)
    mask = np.isfinite(depth) & (depth < SKY_DEPTH_MIN)
    t = np.where(np.isnan(depth), 0.0, depth)
    position = np.asarray(centre, np.float64)[:, None, None] + t * rays
    view = _unit_np(position - np.asarray(centre, np.float64)[:, None, None])
    light = _unit_np(np.asarray(light_centre, np.float64)[:, None, None] - position)
    return position, view, light, mask


# --------------------------------------------------------------------------
# Frames and scenes
# --------------------------------------------------------------------------

def read_camera(frame_dir):
    """camera.json of a frame lit by an area light: {look, up, position, area_light{centre, half_u, half_v,
    radiance}}. ValueError if it has no area light (seed 002 needs the light's position as an input)."""
    cam = json.loads((Path(frame_dir) / "camera.json").read_text())
    if "area_light" not in cam or "position" not in cam:
        raise ValueError(f"{frame_dir}/camera.json has no area light and camera position: render the dataset with "
                         "an \"area_light\" entry (docs/RENDERER.md)")
    return cam


def scene_box(scene_dir):
    """(bbox_min, bbox_max) of a dataset scene folder: [0, 0, 0] .. scene.json's "size" (the grid, metres)."""
    info = json.loads((Path(scene_dir) / "scene.json").read_text())
    size = [float(s) for s in info["size"]]
    if len(size) != 3 or not all(s > 0 for s in size):
        raise ValueError(f"{scene_dir}/scene.json: bad size {info['size']}")
    return [0.0, 0.0, 0.0], size


def _read(path):
    image, _ = ngi.read_exr(str(path))
    return np.asarray(image, np.float32)


def decode_frame(frame_dir):
    """A frame folder -> float32 [len(CHANNELS), N, N] (the cache entry's content)."""
    d = Path(frame_dir)
    cam = read_camera(d)
    depth = _read(d / "front_depth.exr")
    position, view, light, mask = frame_geometry(depth, cam["look"], cam["up"], cam["position"],
                                                 cam["area_light"]["centre"])
    parts = [position, _read(d / "front_normal.exr"), _read(d / "front_albedo.exr"), view,
             _read(d / "front_direct.exr"), light, _read(d / "reference.exr"), mask]
    out = np.concatenate([np.asarray(p, np.float32) for p in parts], axis=0)
    if out.shape[0] != len(CHANNELS):
        raise ValueError(f"{d}: decoded {out.shape[0]} channels, expected {len(CHANNELS)}")
    return out


def _stamp(frame_dir):
    h = hashlib.sha256()
    for p in sorted(Path(frame_dir).iterdir()):
        if p.is_file():
            st = p.stat()
            h.update(f"{p.name}:{st.st_size}:{st.st_mtime_ns}\n".encode())
    return h.hexdigest()


def _atomic_write(path, write):
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def cached_frame(frame_dir, cache_dir, key):
    """The decoded frame, from CACHE/<key>.npy when its manifest's stamp matches the folder, else decoded and
    stored. Returned memory-mapped (read-only)."""
    cache_dir = Path(cache_dir)
    npy, manifest = cache_dir / f"{key}.npy", cache_dir / f"{key}.json"
    stamp = _stamp(frame_dir)
    if npy.is_file() and manifest.is_file():
        try:
            m = json.loads(manifest.read_text())
            if m.get("format") == CACHE_FORMAT and m.get("stamp") == stamp and m.get("channels") == CHANNELS:
                return np.load(npy, mmap_mode="r")
        except ValueError:
            pass
    arr = decode_frame(frame_dir)
    _atomic_write(npy, lambda f: np.save(f, arr))
    _atomic_write(manifest, lambda f: f.write(json.dumps({"format": CACHE_FORMAT, "frame": str(frame_dir),
                                                          "stamp": stamp, "channels": CHANNELS,
                                                          "shape": list(arr.shape)}).encode()))
    return np.load(npy, mmap_mode="r")


def list_scene_frames(scene_dir):
    """Frame folders (sorted by frame number) of a dataset scene folder: every subfolder with a camera.json and a
    reference.exr."""
    scene_dir = Path(scene_dir)
    frames = sorted(p for p in scene_dir.iterdir()
                    if p.is_dir() and ".tmp-" not in p.name and (p / "camera.json").is_file())
    missing = [p for p in frames if not (p / "reference.exr").is_file()]
    if missing:
        raise FileNotFoundError(f"{len(missing)} frames have no reference.exr, e.g. {missing[0]}")
    if not frames:
        raise FileNotFoundError(f"{scene_dir}: no frame folders (render the dataset with `ngi dataset` first)")
    return frames


def find_scene(dataset, scene=None, split="train"):
    """The scene folder DATASET/<split>/<scene> (scene: the folder name, e.g. bleed_seed1; may be omitted when the
    split holds one scene)."""
    root = Path(dataset) / split
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: no such folder")
    if scene:
        d = root / scene
        if not (d / "scene.json").is_file():
            raise FileNotFoundError(f"{d}/scene.json: no such scene in the dataset")
        return d
    scenes = sorted(p for p in root.iterdir() if (p / "scene.json").is_file())
    if len(scenes) != 1:
        raise ValueError(f"{root} holds {len(scenes)} scenes ({', '.join(p.name for p in scenes)}): pass --scene")
    return scenes[0]


def split_frames(dataset, scene=None, test_frames=100, split="train", test_split=None):
    """(scene folder, train frame folders, test frame folders).

    One static scene is in one split of an `ngi dataset` (the generator refuses a scene in both splits, and a
    second dataset of the same scene would repeat the same camera path and lights): by default the scene's LAST
    `test_frames` frames of the path are held out (new views: keyframe_interval 1 makes every frame a new
    keyframe; new lights: each frame draws its own). With `test_split` (e.g. "test"), the test frames are all
    frames of DATASET/<test_split>/<scene> instead and every frame of `split` trains."""
    scene_dir = find_scene(dataset, scene, split)
    frames = list_scene_frames(scene_dir)
    if test_split:
        test_dir = Path(dataset) / test_split / scene_dir.name
        return scene_dir, frames, list_scene_frames(test_dir)
    if not 0 <= test_frames < len(frames):
        raise ValueError(f"{scene_dir}: {len(frames)} frames, cannot hold out {test_frames} and train on the rest")
    cut = len(frames) - test_frames
    return scene_dir, frames[:cut], frames[cut:]


# --------------------------------------------------------------------------
# Tensors
# --------------------------------------------------------------------------

def to_tensors(arr, bbox_min, bbox_max):
    """A cache entry [C, N, N] -> (inputs [1, 18, N, N], direct [1, 3, N, N], reference [1, 3, N, N],
    mask [1, 1, N, N]) float32 tensors."""
    t = torch.from_numpy(np.array(arr, np.float32, copy=True)).unsqueeze(0)
    g = {k: t[:, s] for k, s in SLICES.items()}
    inputs = assemble_inputs(g["position"], g["normal"], g["albedo"], g["view"], g["direct"], g["light_dir"],
                             bbox_min, bbox_max)
    mask = g["mask"]
    return inputs, g["direct"].contiguous(), g["reference"].contiguous(), mask.contiguous()


class SceneData:
    """The frames of one split of one scene, decoded once into the cache; item i -> to_tensors(...)."""

    def __init__(self, frames, scene_dir, cache_dir, split_name):
        self.frames = [Path(f) for f in frames]
        self.bbox_min, self.bbox_max = scene_box(scene_dir)
        scene = Path(scene_dir)
        self.arrays = [cached_frame(f, Path(cache_dir) / scene.parent.name / scene.name, f.name)
                       for f in self.frames]
        self.name = split_name
        shapes = {a.shape for a in self.arrays}
        if len(shapes) > 1:
            raise ValueError(f"frames of different sizes: {sorted(shapes)}")

    def __len__(self):
        return len(self.arrays)

    def __getitem__(self, i):
        return to_tensors(self.arrays[i], self.bbox_min, self.bbox_max)

    @property
    def n(self):
        return self.arrays[0].shape[-1]


def masked_log_l1(prediction, target, mask):
    """ngi.neural_gi.log_l1_loss over the surface pixels only (mask 1): the loss of the pixels kept (all channels),
    i.e. log_l1_loss of the selected pixels. 0 if no pixel is kept."""
    from ngi.neural_gi import log_l1_loss
    keep = mask.expand_as(prediction) > 0.5
    if not bool(keep.any()):
        return prediction.sum() * 0.0
    return log_l1_loss(prediction[keep], target[keep])

"""Training data: frame folders -> exactly the tensors the C++ pipeline feeds the generator, and the targets.

The C++ pipeline is the only implementation of the preprocessing: every frame goes once through it, in process,
through the Python bindings (bindings/python: ngi.Pipeline.network_input / encode_lightmap, the same calls
`ngi merge --npy-only [--single-view]` makes), giving input.npy (SurroundPipeline::network_input: [1, 12, 2N, 4N]
surround or [1, 10, N, N] front view only, values in [-1, 1]) and target.npy (SurroundPipeline::encode_lightmap of
the frame's reference.exr: [1, 3, N, N], the front view's linear lighting through the Reinhard transfer into
[-1, 1], i.e. the exact inverse of the decoding `ngi lightmap` applies to the generator's output). Nothing here
re-implements the merge or the encoding; the loader only reads those files back. training/tests/test_training.py checks
them against `ngi merge`'s files bit for bit.

Cache layout (reused on rerun, one merge per new or changed frame):

    CACHE/cache.json                      layout, channel names, format version
    CACHE/<split>/<scene>/<frame>/        input.npy, target.npy, front.npy, manifest.json
                                          (manifest: frame folder, a stamp of its files, shapes, channels)

front.npy [1, 15, N, N] holds the front face's linear planes the losses of an indirect-mode generator and of the
final image need (FRONT_PLANES): the reference lighting, direct light, albedo, emission and env, as the frame folder
holds them (read_frame's sanitizing; absent emission/env are zeros). The loss sanitizes them as compose.cl does.

A frame's entry is reused while its manifest's stamp (names, sizes and mtimes of the frame folder's files)
still matches. Each entry is written into a temporary folder and renamed into place, so an interrupted run
leaves no half-written entry. Every prepare() re-merges one cached frame and compares it bit for bit with the
cache; a difference (a changed ngi build) invalidates the whole cache.
"""

import concurrent.futures
import hashlib
import json
import os
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import torch

import ngi as ngi_py  # the Python bindings; `ngi` is the CLI binary's path in this project's scripts
import ngi.model_file as model_file

from ngi_train import checkpoint

CACHE_FORMAT = 2  # 2: front.npy
# Layouts "ssgi_residual*" (issue 45): a network that corrects an SSGI rung (SSGI_BASES: layout -> the rung's model
# name). Its input is the front view's channels and the rung's indirect light encoded like a target
# (ngi.Pipeline.network_input(frame, ssgi=...), [1, 13, N, N]); its output is added to those three channels
# (SSGI_CHANNELS) before decoding (docs/CONVENTIONS.md section 8).
SSGI_BASES = {"ssgi_residual": "ssgi_surround", "ssgi_residual_2bounce": "ssgi_surround_2bounce"}
LAYOUTS = ("surround", "single_view") + tuple(SSGI_BASES)


def is_residual(layout):
    return layout in SSGI_BASES

# docs/CONVENTIONS.md section 7 (surround_input_channels / single_view_input_channels in pipeline.hpp). Checked
# against ngi.surround_input_channels() / single_view_input_channels() for every frame merged.
SURROUND_CHANNELS = ["albedo.r", "albedo.g", "albedo.b", "normal.x", "normal.y", "normal.z", "depth",
                     "lumination.r", "lumination.g", "lumination.b", "coord.phi", "coord.theta"]
SINGLE_VIEW_CHANNELS = SURROUND_CHANNELS[:10]
SSGI_RESIDUAL_CHANNELS = SINGLE_VIEW_CHANNELS + ["ssgi.r", "ssgi.g", "ssgi.b"]
SSGI_CHANNELS = slice(10, 13)
# front.npy's planes, each RGB: the slices below index its channel axis.
FRONT_PLANES = ("reference", "direct", "albedo", "emission", "env")
FRONT = {name: slice(3 * i, 3 * i + 3) for i, name in enumerate(FRONT_PLANES)}


def check_layout(layout):
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")


def channels(layout):
    check_layout(layout)
    if is_residual(layout):
        return list(SSGI_RESIDUAL_CHANNELS)
    return list(SURROUND_CHANNELS if layout == "surround" else SINGLE_VIEW_CHANNELS)


def input_nc(layout):
    return len(channels(layout))


def front_region(n):
    """(rows, cols) of the front face inside the thesis global view (docs/CONVENTIONS.md 4.1): an exact copy."""
    return slice(n // 2, 3 * n // 2), slice(3 * n // 2, 5 * n // 2)


def crop_front(t, n, layout):
    """The front view of an NCHW tensor in `layout`'s spatial layout: a crop for surround, all of it otherwise."""
    if layout != "surround":
        return t
    rows, cols = front_region(n)
    return t[..., rows, cols]


def input_hw(n, layout):
    return (2 * n, 4 * n) if layout == "surround" else (n, n)


# --------------------------------------------------------------------------
# Dataset folders (ngi dataset: DIR/dataset.json, DIR/<split>/<scene>/<frame:04d>/)
# --------------------------------------------------------------------------

def read_dataset_config(dataset_dir):
    """The dataset's dataset.json (what `ngi dataset` rendered), or None for a plain folder of frames."""
    path = Path(dataset_dir) / "dataset.json"
    return json.loads(path.read_text()) if path.is_file() else None


def list_frames(dataset_dir, split):
    """Frame folders (paths relative to dataset_dir, sorted) under dataset_dir/split (or dataset_dir when split
    is empty): every folder holding a camera.json. All must have a reference.exr (the training target)."""
    dataset_dir = Path(dataset_dir)
    root = dataset_dir / split if split else dataset_dir
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: no such folder (render the dataset with `ngi dataset` first)")
    frames = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if ".tmp-" not in d and not d.startswith("."))
        if "camera.json" in filenames:
            frames.append(Path(dirpath).relative_to(dataset_dir).as_posix())
    frames.sort()
    if not frames:
        raise FileNotFoundError(f"{root}: no frame folders (folders with a camera.json)")
    missing = [f for f in frames if not (dataset_dir / f / "reference.exr").is_file()]
    if missing:
        raise FileNotFoundError(f"{len(missing)} frames have no reference.exr (the training target), e.g. "
                                f"{dataset_dir / missing[0]}")
    return frames


def select_frames(frames, count):
    """`count` frames spread evenly over the list (all of them when count is 0 or >= len): a held-out subset
    that covers every scene instead of the first scene's first frames."""
    if not count or count >= len(frames):
        return list(frames)
    if count == 1:
        return [frames[0]]
    return [frames[round(i * (len(frames) - 1) / (count - 1))] for i in range(count)]


def frame_list_digest(frames):
    return hashlib.sha1("\n".join(frames).encode()).hexdigest()


def frame_stamp(frame_dir):
    """Names, sizes and modification times of a frame folder's files: changes when the frame is re-rendered."""
    h = hashlib.sha1()
    for entry in sorted(os.scandir(frame_dir), key=lambda e: e.name):
        if entry.is_file():
            st = entry.stat()
            h.update(f"{entry.name}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    return h.hexdigest()


# --------------------------------------------------------------------------
# The merge cache
# --------------------------------------------------------------------------

_DEVICES = {}
_DEVICES_LOCK = threading.Lock()
_LOCAL = threading.local()


def _pipeline(device, n):
    """This thread's ngi.Pipeline of face size n on `device` (a device is shared by threads, a pipeline is not)."""
    with _DEVICES_LOCK:
        if device not in _DEVICES:
            _DEVICES[device] = ngi_py.Device(device or "")
        dev = _DEVICES[device]
    pipes = _LOCAL.__dict__.setdefault("pipes", {})
    if (device, n) not in pipes:
        pipes[(device, n)] = ngi_py.Pipeline(dev, n)
    return pipes[(device, n)]


def ssgi_gather(name):
    """The gather settings of the SSGI rung `name` (its file's metadata), as a correction of it records them."""
    cfg = model_file.read_config(ngi_py.resolve_model(name))
    return {k: cfg[k] for k in model_file.SSGI_GATHER_FIELDS if k in cfg}


def _ssgi_model(device, name):
    """The SSGI rung `name` loaded on `device` (one per thread: a Model is used by one thread at a time)."""
    models = _LOCAL.__dict__.setdefault("ssgi", {})
    if (device, name) not in models:
        with _DEVICES_LOCK:
            dev = _DEVICES[device]
        models[(device, name)] = ngi_py.Model(dev, name)
    return models[(device, name)]


def _save_atomic(path, array):
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", suffix=".npy", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            np.save(f, array)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def run_merge(frame_dir, out_dir, layout, device=None):
    """input.npy and target.npy of one frame into out_dir (created if needed; target.npy is written last), as
    `ngi merge --npy-only [--single-view]` writes them; returns the input's channel names."""
    single = layout == "single_view"
    names = list(ngi_py.ssgi_residual_input_channels() if is_residual(layout)
                 else ngi_py.single_view_input_channels() if single else ngi_py.surround_input_channels())
    if names != channels(layout):
        raise RuntimeError(f"ngi reports the channels {names}, the training code expects {channels(layout)} "
                           "(docs/CONVENTIONS.md section 7 changed? update training/ngi_train/generator/data.py)")
    frame = ngi_py.read_frame(frame_dir)
    if frame.reference is None:
        raise RuntimeError(f"{frame_dir}: no reference.exr (a training frame needs its reference lighting)")
    pipe = _pipeline(device, frame.n)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if is_residual(layout):
        x = pipe.network_input(frame, ssgi=_ssgi_model(device, SSGI_BASES[layout]))
    else:
        x = pipe.network_input(frame, single_view=single)
    _save_atomic(out_dir / "input.npy", x)
    _save_atomic(out_dir / "front.npy", front_planes(frame))
    _save_atomic(out_dir / "target.npy", pipe.encode_lightmap(frame.reference))
    return names


def front_planes(frame):
    """[1, 15, N, N] float32: FRONT_PLANES of the front face (face 0), linear; a feature the frame lacks is zeros."""
    n = frame.n
    planes = [np.asarray(frame.reference, np.float32).reshape(3, n, n)]
    for name in FRONT_PLANES[1:]:
        f = frame.feature(name)
        planes.append(np.zeros((3, n, n), np.float32) if f is None else np.asarray(f[0], np.float32).reshape(3, n, n))
    return np.concatenate(planes)[None]


class MergeCache:
    """input.npy / target.npy of every frame, made by run_merge, cached under cache_dir."""

    def __init__(self, cache_dir, layout, device=None, jobs=1, log=sys.stderr, read_only=False):
        """read_only: open a cache another process prepared (the other ranks of a distributed run), writing nothing."""
        check_layout(layout)
        self.dir = Path(cache_dir)
        self.layout = layout
        self.device = device
        self.jobs = max(1, int(jobs))
        self.log = log
        info = {"format": CACHE_FORMAT, "layout": layout, "channels": channels(layout)}
        if is_residual(layout):  # the inputs hold that gather's light: a changed rung is another cache
            info["ssgi"] = ssgi_gather(SSGI_BASES[layout])
        info_path = self.dir / "cache.json"
        if read_only:
            if not info_path.is_file() or json.loads(info_path.read_text()) != info:
                raise RuntimeError(f"{info_path}: no prepared {layout} merge cache (rank 0 prepares it)")
            return
        self.dir.mkdir(parents=True, exist_ok=True)
        if info_path.is_file():
            old = json.loads(info_path.read_text())
            if old == dict(info, format=1):  # format 1 lacks front.npy: _fresh() re-merges its entries as needed
                checkpoint.write_text_atomic(info_path, json.dumps(info, indent=1) + "\n")
            elif old != info:
                raise RuntimeError(f"{info_path} describes another cache ({old}); use another cache folder")
        else:
            checkpoint.write_text_atomic(info_path, json.dumps(info, indent=1) + "\n")

    def entry(self, rel):
        return self.dir / rel

    def _fresh(self, frame_dir, rel):
        manifest = self.entry(rel) / "manifest.json"
        if not manifest.is_file():
            return False
        try:
            m = json.loads(manifest.read_text())
        except ValueError:
            return False
        return (m.get("stamp") == frame_stamp(frame_dir) and m.get("layout") == self.layout
                and all((self.entry(rel) / f).is_file() for f in ("input.npy", "target.npy", "front.npy")))

    def _merge(self, frame_dir, rel):
        dest = self.entry(rel)
        dest.parent.mkdir(parents=True, exist_ok=True)
        stamp = frame_stamp(frame_dir)
        tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.tmp-", dir=dest.parent))
        try:
            names = run_merge(frame_dir, tmp, self.layout, self.device)
            x = np.load(tmp / "input.npy", mmap_mode="r")
            y = np.load(tmp / "target.npy", mmap_mode="r")
            manifest = {"frame": str(Path(frame_dir).resolve()), "stamp": stamp, "layout": self.layout,
                        "channels": names, "input_shape": list(x.shape), "target_shape": list(y.shape)}
            (tmp / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
            del x, y
            if dest.exists():
                shutil.rmtree(dest)
            os.rename(tmp, dest)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise

    def _verify_one(self, dataset_dir, rel):
        """Re-merge one cached frame and compare it with the cache bit for bit."""
        with tempfile.TemporaryDirectory(dir=self.dir) as tmp:
            run_merge(Path(dataset_dir) / rel, tmp, self.layout, self.device)
            for name in ("input.npy", "target.npy", "front.npy"):
                if not np.array_equal(np.load(Path(tmp) / name), np.load(self.entry(rel) / name)):
                    return False
        return True

    def prepare(self, dataset_dir, frames):
        """Makes sure every frame (relative to dataset_dir) has a fresh entry. Returns {"merged", "reused"}."""
        dataset_dir = Path(dataset_dir)
        todo = [rel for rel in frames if not self._fresh(dataset_dir / rel, rel)]
        todo_set = set(todo)
        cached = [rel for rel in frames if rel not in todo_set]
        if cached and not self._verify_one(dataset_dir, cached[0]):
            print(f"merge cache {self.dir}: {cached[0]} differs from what this ngi makes now; "
                  "re-merging every frame", file=self.log)
            todo, cached = list(frames), []
        if todo:
            t0 = time.monotonic()
            last = 0.0
            done = 0
            with concurrent.futures.ThreadPoolExecutor(self.jobs) as pool:
                futures = [pool.submit(self._merge, dataset_dir / rel, rel) for rel in todo]
                for f in concurrent.futures.as_completed(futures):
                    f.result()
                    done += 1
                    now = time.monotonic()
                    if now - last > 5 or done == len(todo):
                        last = now
                        rate = (now - t0) / done
                        print(f"merge {done}/{len(todo)} frames ({len(cached)} cached)  {rate:.2f} s/frame  "
                              f"ETA {rate * (len(todo) - done):.0f} s", file=self.log, flush=True)
        return {"merged": len(todo), "reused": len(cached)}


    def check(self, dataset_dir, frames):
        """Read-only: every frame has a fresh entry (what prepare() leaves behind); raises otherwise."""
        stale = [rel for rel in frames if not self._fresh(Path(dataset_dir) / rel, rel)]
        if stale:
            raise RuntimeError(f"merge cache {self.dir}: {len(stale)} frames not prepared, e.g. {stale[0]}")
        return {"merged": 0, "reused": len(frames)}


class FrameDataset(torch.utils.data.Dataset):
    """(input [C, H, W], target [3, N, N], name) per frame, read from the merge cache (float32, as ngi wrote);
    front(i): the frame's front.npy [15, N, N] (FRONT_PLANES)."""

    def __init__(self, cache, frames):
        self.cache = cache
        self.frames = list(frames)

    def __len__(self):
        return len(self.frames)

    def arrays(self, i):
        e = self.cache.entry(self.frames[i])
        return np.load(e / "input.npy")[0], np.load(e / "target.npy")[0]

    def front(self, i):
        return torch.from_numpy(np.load(self.cache.entry(self.frames[i]) / "front.npy")[0])

    def __getitem__(self, i):
        x, y = self.arrays(i)
        return torch.from_numpy(x), torch.from_numpy(y), self.frames[i]


def load_split(dataset_dir, split, layout, cache_dir, device=None, jobs=1, max_frames=0, log=sys.stderr,
               prepare=True):
    """The FrameDataset of one split (max_frames: an evenly spread subset), merged (or reused) through the cache;
    returns (dataset, n, merge stats). prepare=False: only open a cache another process prepared (the ranks other
    than 0 of a distributed run, after rank 0's prepare and a barrier): no merge, no write, no ngi device."""
    frames = select_frames(list_frames(dataset_dir, split), max_frames)
    cache = MergeCache(cache_dir, layout, device=device, jobs=jobs, log=log, read_only=not prepare)
    stats = cache.prepare(dataset_dir, frames) if prepare else cache.check(dataset_dir, frames)
    ds = FrameDataset(cache, frames)
    _, y = ds.arrays(0)
    return ds, int(y.shape[-1]), stats


def default_cache_dir(dataset_dir, layout):
    return Path(dataset_dir) / "merge_cache" / layout


#!/usr/bin/python3
"""What surround screen-space GI (model family "ssgi", docs/CONVENTIONS.md section 19) costs per frame, per setting:
the speed side of its speed/accuracy trade (the accuracy side: training/ngi_train/generator/engine_eval.py).

    PYTHONPATH=build/python /usr/bin/python3 perf/ssgi_cost.py --frames runs/engine/frames [--out perf/ssgi_cost.json]

For every frame folder found under --frames (recursively; e.g. engine_eval's rendered .vox frames) and every
variant (the shipped models/ssgi files, then cluster_level x near_factor settings), the frame runs through
Pipeline.run_images with timings: the "network" stage is the gather (its kernels and nothing else, timed by waiting
for the device after it), "total" the whole frame in process from host images. One warm-up, then --repeats runs per
frame and variant, variants interleaved per frame so that machine noise hits them alike; the per-frame median is
recorded, and the median and maximum over frames. Device: --device (default "cpu", PoCL).
"""

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

import ngi
from ngi import model_file

import bench_record

FACES = ("front", "back", "left", "right", "up", "down")
FEATURES = ("albedo", "normal", "depth", "direct", "emission", "env")
SETTINGS = [(0, 0.0), (2, 0.0), (2, 2.0), (2, 4.0), (3, 2.0), (3, 4.0), (3, 8.0)]  # (cluster_level, near_factor)


def frame_images(d):
    """A frame folder's images as run_images takes them ([N, N, C] float32), and its camera."""
    images = {(face, feat): np.ascontiguousarray(np.moveaxis(ngi.read_exr(d / f"{face}_{feat}.exr")[0], 0, -1))
              for face in FACES for feat in FEATURES}
    cam = json.loads((d / "camera.json").read_text())
    return images, cam["look"], cam["up"]


def variants(tmp, extra=()):
    out = {f"shipped:{p.stem}": p for p in sorted((bench_record.REPO / "models" / "ssgi").glob("*.safetensors"))}
    out.update({f"file:{Path(p).stem}": Path(p) for p in extra})
    for level, near in SETTINGS:
        path = Path(tmp) / f"L{level}_near{near:g}.safetensors"
        model_file.write_model(path, {}, {"format_version": 1, "family": "ssgi", "view": "surround",
                                          "cluster_level": level, "near_factor": near, "min_distance": 0.5})
        out[f"surround L{level} near {near:g}"] = path
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=Path, required=True, help="folder searched for frame folders (camera.json)")
    ap.add_argument("--max-frames", type=int, default=0, help="use at most this many frames, spread evenly (0: all)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--extra", default="", help="more ssgi rung files to time, comma-separated (e.g. ssgi_variants' "
                                                 "output); named file:<stem>")
    args = ap.parse_args()
    frames = sorted(p.parent for p in args.frames.rglob("camera.json") if ".tmp-" not in str(p))
    if args.max_frames and len(frames) > args.max_frames:
        frames = [frames[round(i * (len(frames) - 1) / (args.max_frames - 1))] for i in range(args.max_frames)]
    if not frames:
        raise SystemExit(f"ssgi_cost: no frame folders under {args.frames}")
    dev = ngi.Device(args.device)
    with tempfile.TemporaryDirectory() as tmp:
        paths = variants(tmp, [p for p in args.extra.split(",") if p])
        models = {name: ngi.Model(dev, str(p)) for name, p in paths.items()}
        configs = {name: model_file.read_config(p) for name, p in paths.items()}
        pipes, per = {}, {name: {"gather_ms": [], "total_ms": []} for name in models}
        for i, d in enumerate(frames):
            images, look, up = frame_images(d)
            n = images[("front", "depth")].shape[0]
            pipe = pipes.setdefault(n, ngi.Pipeline(dev, n))
            for name, m in models.items():
                pipe.run_images(m, images, look, up, timings=True)  # warm-up: program builds, buffers
            runs = {name: [] for name in models}
            for _ in range(args.repeats):
                for name, m in models.items():
                    runs[name].append(pipe.run_images(m, images, look, up, timings=True)["timings"])
            for name, ts in runs.items():
                per[name]["gather_ms"].append(float(np.median([t["network_ms"] for t in ts])))
                per[name]["total_ms"].append(float(np.median([sum(t.values()) for t in ts])))
            bench_record.log(f"ssgi_cost: frame {i + 1}/{len(frames)} {bench_record.relative(d)}")
    result = {
        "what": "surround screen-space GI per frame: the gather stage and the whole frame in process (run_images)",
        "device": dev.name,
        "commit": bench_record.git_head(), "load": bench_record.load(), "repeats": args.repeats,
        "frames": [bench_record.relative(d) for d in frames],
        "variants": {name: {"config": {k: configs[name].get(k) for k in model_file.SSGI_GATHER_FIELDS},
                            "gather_ms_median": float(np.median(v["gather_ms"])),
                            "gather_ms_max": float(np.max(v["gather_ms"])),
                            "total_ms_median": float(np.median(v["total_ms"])),
                            "gather_ms_per_frame": [round(x, 3) for x in v["gather_ms"]]}
                     for name, v in per.items()},
    }
    for name, v in result["variants"].items():
        bench_record.log(f"  {name:28s} gather median {v['gather_ms_median']:6.2f} ms, max {v['gather_ms_max']:6.2f}, "
                         f"frame {v['total_ms_median']:6.2f} ms")
    bench_record.emit(result, args.out)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Cost of the display view (issue 47; ngi/display.hpp): the N x N lightmap brought to S x S and accumulated.

    PYTHONPATH=build/python /usr/bin/python3 perf/display_cost.py [--device pocl] [--sizes 512,1024,1440] \\
        [--n 64] [--repeats 20] [--out perf/display_cost_pocl_2core.json]

Per display size S and upsampler (jbu with radius 2, the default, and 1; bilinear): the median over --repeats frames (after 3 untimed ones) of each
stage of DisplayView.run's timings -- guides (both resolutions' normals and positions, and the N x N indirect light),
upsample, temporal (reprojection, clamp, blend), outputs (compose, tone map and the download of the final image) --
and "upsampling + temporal" = guides + upsample + temporal, the figure issue 47 budgets (2 ms at 512^2, 8 ms at
1920 x 1080; 1440^2 has the pixels of 1920 x 1080). Each stage is timed by waiting for the device after it
(FrameTimings' rule). The frames are synthetic: a floor and a wall seen by a camera that moves 1 cm per frame (every
pixel a surface, the history reprojected each frame); the cost depends on the pixel count, not on the light.
"""

import argparse
import json
import os
import platform
import sys
from datetime import date

import numpy as np

import ngi


def scene(size, position, look=(0.0, -0.3, -1.0), up=(0.0, 1.0, 0.0)):
    """A Frame (face `size`; face 0 = front, the other faces a copy: only the front is read) of a floor y = 0 and a
    wall z = -6 around a camera at `position`."""
    look = np.asarray(look, np.float64) / np.linalg.norm(look)
    right = np.cross(look, up)
    right /= np.linalg.norm(right)
    upv = np.cross(right, look)
    c = 2.0 * (np.arange(size) + 0.5) / size - 1.0
    u, v = np.meshgrid(c, -c)
    d = look + u[..., None] * right + v[..., None] * upv
    pos = np.asarray(position, np.float64)
    t_floor = np.where(d[..., 1] < 0, -pos[1] / np.minimum(d[..., 1], -1e-9), np.inf)
    t_wall = np.where(d[..., 2] < 0, (-6.0 - pos[2]) / np.minimum(d[..., 2], -1e-9), np.inf)
    floor = t_floor < t_wall
    depth = np.where(floor, t_floor, t_wall).astype(np.float32)
    normal = np.where(floor[None], np.array([0, 1, 0.0])[:, None, None], np.array([0, 0, 1.0])[:, None, None])
    world = pos + depth[..., None] * d
    direct = (1.0 + 0.5 * np.sin(world[..., 0]))[None].repeat(3, 0)
    albedo = np.full((3, size, size), 0.6)
    f = lambda a: np.ascontiguousarray(np.repeat(np.asarray(a, np.float32)[None], 6, axis=0))
    return ngi.Frame.from_dict({"albedo": f(albedo), "normal": f(normal), "depth": f(depth[None]),
                                "direct": f(direct), "look": tuple(look), "up": tuple(up)})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--device", default=os.environ.get("NGI_DEVICE", "pocl"))
    ap.add_argument("--sizes", default="512,1024,1440")
    ap.add_argument("--n", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    dev = ngi.Device(args.device)
    rows = []
    for s in [int(x) for x in args.sizes.split(",")]:
        for up, radius in (("jbu", 2), ("jbu", 1), ("bilinear", 2)):
            view = ngi.DisplayView(dev, s, upsampler=up, radius=radius)
            times = []
            for k in range(args.repeats + 3):
                p = (0.01 * k, 1.5, 2.0)
                low, hi = scene(args.n, p), scene(s, p)
                lm = low.feature("direct")[0] + 0.3
                t = view.run(low, lm, hi, p, outputs=("final",), timings=True, stats=(k == args.repeats + 2))
                if k >= 3:
                    times.append(t["timings"])
            med = {key: float(np.median([t[key] for t in times])) for key in times[0]}
            med["upsample_temporal_ms"] = float(np.median([t["geometry_ms"] + t["upsample_ms"] + t["temporal_ms"]
                                                           for t in times]))
            row = {"size": s, "n": args.n, "upsampler": up, "radius": radius if up == "jbu" else None,
                   "temporal": True, "median_ms": med,
                   "last_frame_stats": t["stats"]}
            rows.append(row)
            print(f"{s}^2 {up:8s} r{radius} " + ", ".join(f"{k} {v:.2f}" for k, v in med.items()), file=sys.stderr, flush=True)
    record = {"benchmark": "display_cost", "date": date.today().isoformat(), "device": dev.info,
              "host": {"machine": platform.machine(), "cpus": os.cpu_count()}, "repeats": args.repeats, "rows": rows}
    text = json.dumps(record, indent=1)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    else:
        print(text)


if __name__ == "__main__":
    main()

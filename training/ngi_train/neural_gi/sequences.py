#!/usr/bin/python3
"""Seed 002's temporal and equal-time test data: two short sequences per scene, rendered with `ngi render`.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.neural_gi.sequences \\
        --config configs/neural_gi_bleed_n32.json --out data/neural_gi_seq_n32 [--frames 16] [--pt-spp 16]

For the dataset config's (only) scene, at its N, feature and reference spp:

  moving_camera/<scene>/NNNN   frames S..S+F-1 of the scene's smooth camera path (`ngi render --frame K
                               --path-frames P`: keyframes every 25 frames, ~0.1 m per frame; a walk of its own,
                               not the dataset's: checked, frame 0 at (11.5, 6.5, 5.5) and frame 8750 at (6.1, 2.8,
                               13.6) in bleed:seed=1, the dataset's frames 0 and 350 at (7.5, 6.5, 4.5) and (7.0, 5.1,
                               3.6)), one fixed area light
                               (the centre of the config's light box, 2 x 2 m, facing down)
  moving_light/<scene>/NNNN    the camera of moving_camera's first frame, the light's centre swept along x across the
                               config's light box (y, z and size fixed) in F steps
  <sequence>_pt<S>/<scene>/... the same frames path traced at S spp with other seeds: "path tracing at equal time"
                               (evaluate.py --path-traced); S is chosen by the caller from the measured network time
                               and the reference_ms this script records
  noise/<scene>/0000           moving_camera's frame 0 again at the reference spp with another seed (the noise
                               floor of the references: two independent renders compared)

Each frame has its own path-tracer seed (as in a dataset). Every scene folder gets a scene.json with the grid size
(data.py's scene box). OUT/render.json records each render's reference time (ms) and settings, taken from the
render.json `ngi render` writes into the frame folder. Frames already written are skipped: an interrupted run
resumes.
"""

import argparse
import json
import re
import sys
import time
from pathlib import Path

from tqdm import tqdm

from ngi_train import ngi_paths

SEQUENCES = ("moving_camera", "moving_light")
LIGHT_HALF_EDGE = 1.0  # metres: the fixed 2 x 2 m panel of the sequences (the dataset draws edges of 1-3 m)


def folder_name(spec):
    """`ngi dataset`'s scene folder name of a procedural scene: bleed:seed=1 -> bleed_seed1."""
    if not re.fullmatch(r"[a-z_]+:seed=\d+", spec):
        raise SystemExit(f"sequences.py handles procedural scenes (NAME:seed=S), not {spec!r}")
    return spec.replace(":", "_").replace("=", "")


def light_arg(centre, radiance, facing):
    """--area-light cx,cy,cz,ux,uy,uz,vx,vy,vz,r,g,b of a square panel (it emits toward cross(u, v))."""
    if facing != "down":
        raise SystemExit(f"sequences.py handles lights facing down only, the config says {facing!r}")
    h = LIGHT_HALF_EDGE
    u, v = (h, 0.0, 0.0), (0.0, 0.0, h)  # cross(x, z) = -y: facing down
    return ",".join(f"{x:.6g}" for x in (*centre, *u, *v, *radiance))


def plan(config, frames, pt_spp, start):
    """[(sequence folder, index, ngi render arguments, seed)] for one scene."""
    box = config["area_light"]
    lo, hi = box["centre_min"], box["centre_max"]
    mid = [(a + b) / 2 for a, b in zip(lo, hi)]
    jobs = []
    for seq in SEQUENCES:
        for i in range(frames):
            if seq == "moving_camera":
                frame, centre = start + i, mid
            else:
                t = i / max(frames - 1, 1)
                frame, centre = start, [lo[0] + t * (hi[0] - lo[0]), mid[1], mid[2]]
            light = light_arg(centre, box["radiance"], box.get("facing", "down"))
            base = ["--frame", str(frame), "--area-light", light]
            jobs.append((seq, i, base, config["reference_spp"], 1000 + i))
            for s in pt_spp:
                jobs.append((f"{seq}_pt{s}", i, base, s, 5000 + i))
    jobs.append(("noise", 0, ["--frame", str(start), "--area-light", light_arg(mid, box["radiance"], "down")],
                 config["reference_spp"], 9000))
    return jobs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", required=True, type=Path, help="the scene's dataset config (configs/neural_gi_*)")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--frames", type=int, default=16, help="frames per sequence")
    ap.add_argument("--path-frames", type=int, default=10000, help="--path-frames of ngi render (the path's length)")
    ap.add_argument("--start-frame", type=int, default=8750, help="the path frame of the sequences' first frame")
    ap.add_argument("--pt-spp", type=int, nargs="*", default=[], help="equal-time path tracing sample counts")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--ngi", help="the ngi binary (default: found by ngi_paths)")
    a = ap.parse_args(argv)
    config = json.loads(a.config.read_text())
    if len(config["train"]) != 1 or "area_light" not in config:
        raise SystemExit(f"{a.config}: needs one train scene and an area_light")
    spec = config["train"][0]["scene"]
    hours = config["train"][0].get("time")
    if hours is not None and not isinstance(hours, (int, float)):
        raise SystemExit(f"{a.config}: a time range ({hours}) has no single time for a sequence; give one time")
    scene = folder_name(spec)
    ngi_bin = a.ngi or ngi_paths.find_ngi()
    record_path = a.out / "render.json"
    record = json.loads(record_path.read_text()) if record_path.is_file() else {}
    if not 0 <= a.start_frame <= a.path_frames - a.frames:
        raise SystemExit(f"--start-frame {a.start_frame} + --frames {a.frames} exceeds --path-frames {a.path_frames}")
    jobs = plan(config, a.frames, a.pt_spp, a.start_frame)
    bar = tqdm(jobs, desc=f"sequences {scene}", unit="frame", file=sys.stderr)
    for seq, i, base, spp, seed in bar:
        folder = a.out / seq / scene
        out = folder / f"{i:04d}"
        key = f"{seq}/{scene}/{i:04d}"
        if (out / "reference.exr").is_file() and key in record:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        cmd = [ngi_bin, "render", "--scene", spec, *(["--time", str(hours)] if hours is not None else []),
               "--path-frames", str(a.path_frames),
               "--face", str(config["n"]), "--feature-spp", str(config["feature_spp"]), "--spp", str(spp),
               "--bounces", str(config.get("max_bounces", 8)), "--seed", str(seed), "--device", a.device,
               "--out", str(out), *base]
        t0 = time.monotonic()
        try:
            ngi_paths.run(cmd)
        except RuntimeError as e:
            raise SystemExit(str(e)[-2000:]) from None
        rendered = json.loads((out / "render.json").read_text())
        record[key] = {"spp": rendered["settings"]["reference_spp"], "reference_ms": rendered["timing"]["reference_ms"],
                       "feature_ms_six_faces": rendered["timing"]["features_ms"], "seed": seed,
                       "wall_s": round(time.monotonic() - t0, 3), "args": base}
        size = rendered["scene"]["size"]
        (folder / "scene.json").write_text(json.dumps({"spec": spec, "size": size,
                                                       "note": "sequences.py (ngi render frames)"}) + "\n")
        tmp = record_path.with_suffix(".tmp")
        tmp.write_text(json.dumps(record, indent=1) + "\n")
        tmp.replace(record_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

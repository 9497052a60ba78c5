#!/usr/bin/python3
"""Adds (or replaces) networks that correct an SSGI rung (output_mode "ssgi_residual", issue 45) in the zoo manifest,
with their measured cost and accuracy, so that ngi.plan offers them beside the SSGI rungs they correct.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.residual_zoo --zoo models/zoo.json \\
        --models models/ssgi/gi_ssgi_residual_n64_ngf16.safetensors \\
        --vox docs/results/engine_vox/engine.json --validation docs/results/engine_validation/engine.json \\
        --frames runs/engine/frames [--device pocl]

- cost: generator_ms = the whole frame in process (gather + network + outputs: engine_eval's pipeline time, median
  of its timed runs on one .vox frame after a warm-up); lightmap_ms = the whole `ngi lightmap` command, median wall
  time over --lightmap-frames frames found under --frames after one warm-up run (as ssgi_zoo times the SSGI rungs).
- accuracy: engine inputs, from engine_eval's summaries ("vox": the public .vox scenes, evaluation only;
  "validation": this project's own scenes, where the checkpoint and bn_mode were chosen); "heldout" is null.
The rung's name is the file's stem.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

import ngi
import ngi.model_file as model_file
import ngi.zoo as zoo_mod

from ngi_train import ngi_paths
from ngi_train.generator import ladder_eval as le, ssgi_zoo

REPO = le.REPO


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--zoo", type=Path, default=REPO / "models" / "zoo.json")
    ap.add_argument("--models", required=True, help="comma-separated ssgi_residual model files")
    ap.add_argument("--vox", type=Path, required=True, help="engine_eval's summary on the .vox scenes")
    ap.add_argument("--validation", type=Path, required=True, help="engine_eval's summary on this project's scenes")
    ap.add_argument("--frames", type=Path, required=True, help="folder searched for frame folders (camera.json)")
    ap.add_argument("--lightmap-frames", type=int, default=5)
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    zoo = json.loads(args.zoo.read_text())
    vox = json.loads(args.vox.read_text())
    val = json.loads(args.validation.read_text())
    frames = sorted(p.parent for p in args.frames.rglob("camera.json") if ".tmp" not in str(p))
    frames = frames[:: max(1, len(frames) // args.lightmap_frames)][: args.lightmap_frames]
    info = ngi.Device(args.device).info
    key = zoo_mod.device_key(zoo, info) or f"{args.device}:{info['name']}"
    zoo["devices"].setdefault(key, {k: info[k] for k in ("platform", "name", "driver_version", "device_version")})
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    new = []
    for f in (Path(m).resolve() for m in args.models.split(",")):
        cfg = model_file.read_config(str(f))
        if cfg.get("output_mode") != "ssgi_residual":
            raise SystemExit(f"{f}: output_mode {cfg.get('output_mode')!r}, not ssgi_residual")
        if f.stem not in vox["rungs"] or f.stem not in val["rungs"]:
            raise SystemExit(f"{f.stem}: not in both engine_eval summaries (run engine_eval with it first)")
        walls = ssgi_zoo.lightmap_ms(ngi_bin, f, frames, args.device)
        frame_ms = vox["rungs"][f.stem]["pipeline"]["ms"]
        train = cfg.get("training", {})
        new.append({
            "name": f.stem, "kind": "rung", "file": str(f.relative_to(args.zoo.resolve().parent)),
            "sha256": zoo_mod.sha256(f), "layout": "ssgi_residual", "n": train.get("dataset_config", {}).get("n", 64),
            "ngf": cfg["ngf"], "num_downs": cfg["num_downs"], "bn_mode": cfg["bn_mode"], "weights": "f16",
            "training": {k: train.get(k) for k in ("steps", "frames", "epochs", "wall_seconds", "dataset")},
            "input": {"channels": cfg["input_layout"]}, "gflop": None, "memory_mib": None,
            "corrects": cfg["ssgi"],
            "cost": {key: {"generator_ms": float(frame_ms), "generator_ms_what": "whole frame in process",
                           "lightmap_ms": float(np.median(walls)), "lightmap_ms_all": walls,
                           "source": le.rel(args.vox)}},
            "accuracy": {"heldout": None, "vox": ssgi_zoo.accuracy_of(vox, f.stem),
                         "validation": ssgi_zoo.accuracy_of(val, f.stem)},
            "output_mode": "ssgi_residual"})
        le.log(f"residual_zoo: {f.stem}: frame {frame_ms:.1f} ms, ngi lightmap {np.median(walls):.1f} ms")
    names = {r["name"] for r in new}
    zoo["rungs"] = [r for r in zoo["rungs"] if r["name"] not in names] + new
    le.write_json(args.zoo, zoo)
    zoo_mod.load(args.zoo)  # what was written must load
    le.log(f"residual_zoo: {args.zoo}: {', '.join(sorted(names))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

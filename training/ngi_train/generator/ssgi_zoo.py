#!/usr/bin/python3
"""Adds (or replaces) the surround screen-space GI rungs (models/ssgi/*.safetensors, model family "ssgi": no network)
in the zoo manifest, with their measured cost and accuracy, so that ngi.plan offers them.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.ssgi_zoo --zoo models/zoo.json \\
        --cost perf/ssgi_cost_pocl_2core.json --vox docs/results/engine.json \\
        --validation docs/results/engine_validation.json --frames runs/engine/frames [--device pocl]

- cost: generator_ms = the gather stage's median over the frames of perf/ssgi_cost.py's record (its "shipped:<stem>"
  entry); lightmap_ms = the whole `ngi lightmap` command, median wall time over --lightmap-frames frames found under
  --frames after one warm-up run, as ladder_eval's speed stage times the networks.
- accuracy: engine inputs (converged direct light), from training/ngi_train/generator/engine_eval.py's summaries:
  "vox" on the public .vox scenes (evaluation only) and "validation" on this project's own scenes (where settings
  are chosen); "heldout" is null (the dataset's test split was not rendered with engine inputs).
The rung's name is the file's stem + "_n<N>" (N = --n, the face size it was measured at); layout "surround" for view
"surround", "single_view" for "front" (the faces it reads).
"""

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

import ngi
import ngi.model_file as model_file
import ngi.zoo as zoo_mod

from ngi_train import ngi_paths
from ngi_train.generator import ladder_eval as le

REPO = le.REPO


def accuracy_of(summary, stem):
    """The rung's per-group means and per-frame honesty from an engine_eval summary (None if it was not run)."""
    if summary is None or stem not in summary["rungs"]:
        return None
    r = summary["rungs"][stem]
    s = summary["settings"]
    return {"feature_spp": s["feature_spp"], "reference_spp": s["ref_spp"], "frames": summary["frames"]["lit"],
            "groups": r["groups"], "honesty": r.get("honesty")}


def lightmap_ms(ngi_bin, model, frames, device):
    """Median wall time of the whole `ngi lightmap` command over `frames` (after one warm-up run)."""
    env = le.device_env(device)
    tmp = Path(tempfile.mkdtemp(prefix="ssgi_zoo-"))
    try:
        run = lambda f, out: le.run_timed([ngi_bin, "lightmap", "--frame", f, "--model", model, "--out", out,  # noqa: E731
                                           "--device", device], env)[1]
        run(frames[0], tmp / "warmup")
        return [run(f, tmp / str(k)) for k, f in enumerate(frames)]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--zoo", type=Path, default=REPO / "models" / "zoo.json")
    ap.add_argument("--cost", type=Path, required=True, help="perf/ssgi_cost.py's JSON record")
    ap.add_argument("--vox", type=Path, required=True, help="engine_eval's summary on the .vox scenes")
    ap.add_argument("--validation", type=Path, help="engine_eval's summary on this project's own scenes")
    ap.add_argument("--frames", type=Path, required=True, help="folder searched for frame folders (camera.json)")
    ap.add_argument("--lightmap-frames", type=int, default=5)
    ap.add_argument("--n", type=int, default=64)
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    zoo = json.loads(args.zoo.read_text())
    cost = json.loads(args.cost.read_text())
    vox = json.loads(args.vox.read_text())
    val = json.loads(args.validation.read_text()) if args.validation else None
    frames = sorted(p.parent for p in args.frames.rglob("camera.json") if ".tmp" not in str(p))
    frames = frames[:: max(1, len(frames) // args.lightmap_frames)][: args.lightmap_frames]
    info = ngi.Device(args.device).info
    key = zoo_mod.device_key(zoo, info) or f"{args.device}:{info['name']}"
    zoo["devices"].setdefault(key, {k: info[k] for k in ("platform", "name", "driver_version", "device_version")})
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    new = []
    for f in sorted((REPO / "models" / "ssgi").glob("*.safetensors")):
        cfg = model_file.read_config(str(f))
        walls = lightmap_ms(ngi_bin, f, frames, args.device)
        gather = cost["variants"][f"shipped:{f.stem}"]
        new.append({
            "name": f"{f.stem}_n{args.n}", "kind": "ssgi", "file": str(f.relative_to(args.zoo.resolve().parent)),
            "sha256": zoo_mod.sha256(f), "layout": "surround" if cfg.get("view", "surround") == "surround" else
            "single_view", "n": args.n, "weights": None, "input": None, "gflop": None, "memory_mib": None,
            "config": {k: cfg.get(k) for k in model_file.SSGI_GATHER_FIELDS},
            "cost": {key: {"generator_ms": gather["gather_ms_median"], "generator_ms_max": gather["gather_ms_max"],
                           "lightmap_ms": float(np.median(walls)), "lightmap_ms_all": walls,
                           "source": le.rel(args.cost)}},
            "accuracy": {"heldout": None, "vox": accuracy_of(vox, f.stem), "validation": accuracy_of(val, f.stem)},
            "output_mode": "indirect"})
        le.log(f"ssgi_zoo: {new[-1]['name']}: gather {gather['gather_ms_median']:.2f} ms, ngi lightmap "
               f"{np.median(walls):.1f} ms")
    names = {r["name"] for r in new}
    zoo["rungs"] = [r for r in zoo["rungs"] if r["name"] not in names] + new
    le.write_json(args.zoo, zoo)
    zoo_mod.load(args.zoo)  # what was written must load
    le.log(f"ssgi_zoo: {args.zoo}: {', '.join(sorted(names))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The model zoo manifest (models/zoo.json): every shipped generator variant with its measured cost and accuracy.

Written by ngi_train.generator.ladder_eval from its measurements; read by ngi.plan. Format (version 1):

    {"format": "ngi-zoo", "version": 1, "comment": ..., "protocol": {how cost and accuracy were measured},
     "devices": {"pocl": {"platform", "name", "driver", ...}, ...},   # the devices the costs were measured on
     "switches": [{"surround", "single_view", "below_outside_light_share", ...}],  # measured per-frame switches
     "rungs": [{"name", "kind" ("direct" | "rung" | "bn_variant" | "legacy" | "ssgi"), "file" (relative to the
                manifest's folder; null for the direct-light-only rung), "sha256",
                "layout" ("surround" | "single_view" | "ssgi_residual" | "none"), "n", "ngf", "num_downs", "bn_mode", "weights",
                "input": [1, C, H, W], "gflop", "memory_mib",
                "cost": {device key: {"generator_ms", "lightmap_ms"}},
                "accuracy": {"heldout": {"final": {ssim, psnr, mse}, "lightmap": {...}, "families": {...}},
                             "temporal": {sequence: {ssim, psnr, mabd, mabd_reference, warp_error, ...}}},
                "training": {...}}, ...]}

A rung of kind "ssgi" is a physics rung: its file (model family "ssgi", no tensors) holds the settings of the light
gather the pipeline runs on the frame's faces; it has no network, so no "ngf", "num_downs" or "bn_mode" (null
if given: ngi.Model refuses a batch-norm mode for it).

load() checks the manifest against the files: a missing file, a file whose bytes (sha256) or whose architecture
metadata (family, input channels, ngf, num_downs; for ssgi the family) disagree with its entry is a ZooError naming
the manifest, the rung and what differs. Pure Python (no native module needed).
"""

import hashlib
import json
import os
from pathlib import Path

from . import model_file

FORMAT, VERSION = "ngi-zoo", 1
INPUT_NC = {"surround": 12, "single_view": 10, "ssgi_residual": 13}  # ssgi_residual: corrects an ssgi rung
RUNG_KEYS = ("name", "file", "layout", "n", "ngf", "num_downs", "bn_mode", "cost", "accuracy")
NETWORK_KEYS = ("ngf", "num_downs", "bn_mode")  # of RUNG_KEYS, the ones an ssgi rung (no network) goes without


class ZooError(ValueError):
    """A manifest that cannot be used: names the manifest, the rung and what is wrong."""


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def load(path, check_digests=True):
    """The manifest at `path`, every rung checked against its file; rung["path"] = the file's absolute path."""
    path = Path(path)
    try:
        zoo = json.loads(path.read_text())
    except FileNotFoundError:
        raise ZooError(f"zoo {path}: no such file (python3 -m ngi_train.generator.ladder_eval --zoo writes it)") from None
    except ValueError as e:
        raise ZooError(f"zoo {path}: not valid JSON: {e}") from None
    if not isinstance(zoo, dict) or zoo.get("format") != FORMAT:
        raise ZooError(f"zoo {path}: not a zoo manifest (\"format\": \"{FORMAT}\")")
    if zoo.get("version") != VERSION:
        raise ZooError(f"zoo {path}: version {zoo.get('version')!r}; this ngi reads version {VERSION}")
    rungs = zoo.get("rungs")
    if not isinstance(rungs, list) or not rungs:
        raise ZooError(f"zoo {path}: no rungs")
    names = set()
    for r in rungs:
        where = f"zoo {path}: rung {r.get('name', '?')!r}"
        ssgi = r.get("kind") == "ssgi"
        missing = [k for k in RUNG_KEYS if k not in r and not (ssgi and k in NETWORK_KEYS)]
        if missing:
            raise ZooError(f"{where}: missing keys {missing}")
        if r["name"] in names:
            raise ZooError(f"{where}: the name appears twice")
        names.add(r["name"])
        if r["file"] is None:
            if ssgi:
                raise ZooError(f"{where}: kind 'ssgi' without a file (the file holds the gather's settings)")
            if r["layout"] != "none":
                raise ZooError(f"{where}: no file, but layout {r['layout']!r} (only the direct-light rung has none)")
            r["path"] = None
            continue
        f = (path.parent / r["file"]).resolve()
        if not f.is_file():
            raise ZooError(f"{where}: file {f} does not exist")
        if check_digests and r.get("sha256") and sha256(f) != r["sha256"]:
            raise ZooError(f"{where}: file {f} differs from the manifest (sha256 {sha256(f)[:12]}..., manifest "
                           f"{r['sha256'][:12]}...): re-run ngi_train.generator.ladder_eval --zoo")
        try:
            cfg = model_file.read_config(str(f))
        except Exception as e:  # a file that is not an ngi model at all
            raise ZooError(f"{where}: file {f}: {e}") from None
        if ssgi:
            want = {"family": "ssgi"}
        else:
            want = {"family": "pix2pix_unet", "input_nc": INPUT_NC.get(r["layout"]), "ngf": r["ngf"],
                    "num_downs": r["num_downs"]}
        for k, v in want.items():
            if cfg.get(k) != v:
                raise ZooError(f"{where}: the file's metadata disagrees with the manifest: {k} {cfg.get(k)!r} in "
                               f"{f.name}, {v!r} in the manifest")
        if ssgi and r.get("bn_mode") is not None:
            raise ZooError(f"{where}: bn_mode {r['bn_mode']!r} for kind 'ssgi' (null: it has no batch norm)")
        if not ssgi and r["bn_mode"] not in ("running", "per_image"):
            raise ZooError(f"{where}: bn_mode {r['bn_mode']!r} (running | per_image)")
        r["path"] = str(f)
    return zoo


def device_key(zoo, info):
    """The zoo's key of the device with ngi.Device.info() `info` (same platform and device name), or None."""
    for key, d in zoo.get("devices", {}).items():
        if d and d.get("name") == info.get("name") and d.get("platform") == info.get("platform"):
            return key
    return None


def build(summary, zoo_path, root):
    """The manifest from ngi_train.generator.ladder_eval's summary (its file paths relative to `root`, the repository):
    the shipped variants (each exported rung as exported and with the other batch-norm mode; the generators
    shipped before the ladder) and the direct-light rung."""
    zoo_dir = Path(zoo_path).resolve().parent
    rungs = []
    for name, v in summary["variants"].items():
        if v["kind"] not in ("direct", "rung", "bn_variant", "legacy") or (v["kind"] != "direct" and not v.get("shipped")):
            continue
        entry = {"name": name, "kind": v["kind"], "file": None, "sha256": None, "layout": v["layout"], "n": v["n"],
                 "ngf": v["ngf"], "num_downs": v.get("num_downs", 0), "bn_mode": v["bn_mode"] or "running",
                 "weights": v["weights"]}
        if v["file"]:
            f = (Path(root) / v["file"]).resolve()
            entry["file"] = os.path.relpath(f, zoo_dir)
            entry["sha256"] = sha256(f)
            t = model_file.read_config(str(f)).get("training") or {}
            entry["training"] = {"steps": t.get("steps"), "epochs": t.get("epochs"), "frames": t.get("frames"),
                                 "wall_seconds": t.get("wall_seconds"), "seed": (t.get("config") or {}).get("seed"),
                                 "dataset_config": (t.get("dataset_config") or {}).get("comment")}
        speeds = v.get("speed", {})
        first = next(iter(speeds.values()), {})
        entry["input"] = first.get("input")
        entry["gflop"] = first.get("gflop", 0.0) if v["file"] else 0.0
        entry["memory_mib"] = first.get("memory_mib")
        entry["cost"] = {d: {"generator_ms": s["generator_ms"], "lightmap_ms": s["lightmap_ms"]}
                         for d, s in speeds.items()}
        if v["kind"] == "direct":
            entry["cost"] = {d: {"generator_ms": 0.0, "lightmap_ms": 0.0} for d in summary["speed_devices"]}
        entry["accuracy"] = {"heldout": v.get("heldout"), "temporal": v.get("temporal")}
        rungs.append(entry)
    shipped = {r["name"] for r in rungs}
    switches = [s["chosen"] for s in summary.get("switch", [])
                if s["chosen"]["surround"] in shipped and s["chosen"]["single_view"] in shipped]
    return {"format": FORMAT, "version": VERSION,
            "comment": "Written by ngi_train.generator.ladder_eval (docs/RESULTS.md, 'The ladder'). cost: milliseconds per "
                       "frame on each device (generator alone: ngi_bench generator, median; lightmap: the whole "
                       "ngi lightmap command, median wall time); accuracy: mean over the held-out test frames against "
                       "converged references (ngi.scoring), and the two temporal sequences (ngi.temporal).",
            "protocol": {"datasets": summary["dataset_configs"], "noise_floor": summary["noise_floor"],
                         "recipe": summary["recipe"]},
            "devices": summary["speed_devices"], "switches": switches, "rungs": rungs}

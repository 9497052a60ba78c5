#!/usr/bin/python3
"""Issue 46's named competitor: an irradiance-probe grid (ngi.probe_grid) baked in the time the per-voxel-face bake
had, scored on the frames adapt_eval scored (docs/ADAPT.md, "The probe grid").

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.probe_grid_eval --vox-dir ../shared/scenes/vox \\
        --record docs/results/adapt/adapt.json --work runs/probe_grid --out docs/results/probe_grid

Per .vox file of --vox-dir (or --files), on the path frames of the record (engine inputs, 1,024 spp; frames cached
in --frames-dir as adapt_eval caches them):
1. the face bake again, with the record's sample count (its scores must reproduce the record's: the frames are the
   same), timed on this machine: T seconds;
2. a probe grid at each --spacings value (metres), its directions per probe calibrated (bakes of 4 and 16
   directions) so that its bake takes ~T (x --share), then path-traced (ngi.ProbeGrid.bake) and timed;
3. every frame scored with ngi.scoring: direct light, ssgi_surround, the face bake, each grid; the adapted network's
   scores per file are the record's (its models are not kept).

Writes OUT/probe_grid.json (per-frame scores, per-file bakes) and OUT/probe_grid_tables.md. Per-frame scores are cached
in WORK/probe_grid_eval.json: an interrupted run continues where it stopped.
"""

import argparse
import datetime
import math
import sys
import time
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.plan as plan
import ngi.scoring as scoring
from ngi.probe_grid import ProbeGrid

from ngi_train import adapt_eval, ngi_paths
from ngi_train.generator import engine_eval, gi_eval, ladder_eval as le

log = le.log
VERSION = "grid-2"  # part of the cache key: the grid's placement and shading


MAX_SIDE = 1024  # directions are m^2 <= 2^20, the tracer's limit per point


def calibrated_grid(grid, renderer, seconds):
    """Bakes `grid` with the most directions m^2 whose bake takes ~`seconds` (fitted as a + b directions from
    bakes of 16 and 256: on a few hundred probes the smaller bakes are all fixed cost and noise); returns
    (directions, the bake's {'seconds', 'rays'})."""
    t16 = grid.bake(renderer, directions=16, seed=99)["seconds"]
    t256 = grid.bake(renderer, directions=256, seed=98)["seconds"]
    per = max(1e-9, (t256 - t16) / 240.0)
    fixed = max(0.0, t16 - 16 * per)
    m = min(MAX_SIDE, max(1, int(math.sqrt(max(1.0, (seconds - fixed) / per)))))
    return m * m, grid.bake(renderer, directions=m * m, seed=0)


def grid_lightmap(grid, frame, camera):
    direct = frame.feature("direct")[0]
    return direct + grid.shade(frame.feature("depth")[0][0], frame.feature("normal")[0], camera)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vox-dir", type=Path, required=True, help="the folder of .vox files (read only)")
    ap.add_argument("--files", default="", help="comma-separated .vox stems (default: every file of the record)")
    ap.add_argument("--record", type=Path, required=True, help="adapt_eval's adapt.json (frames, bakes, scores)")
    ap.add_argument("--work", type=Path, required=True)
    ap.add_argument("--frames-dir", type=Path, default=le.REPO / "runs" / "engine" / "frames" / "ref1024_feat1024")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--spacings", default="1,2", help="grid spacings in metres (blocks)")
    ap.add_argument("--share", type=float, default=1.0, help="the grid's bake time as a share of the face bake's")
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    record = le.read_json(args.record)
    frames = record["settings"]["frames"]
    spacings = [float(s) for s in args.spacings.split(",") if s]
    if not spacings or any(not (s > 0) for s in spacings):
        ap.error("--spacings: positive numbers of metres")
    files = [f for f in args.files.split(",") if f] or list(record["scenes"])
    missing = [f for f in files if not (args.vox_dir / f"{f}.vox").is_file() or f not in record["scenes"]]
    if missing:
        ap.error(f"not in --vox-dir or not in the record: {missing}")
    args.work.mkdir(parents=True, exist_ok=True)
    args.out.mkdir(parents=True, exist_ok=True)
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    device = ngi.Device(args.device)
    ev = plan.Evaluator(device, None)
    ssgi = engine_eval.resolve_rungs(["ssgi_surround_n64"], le.REPO / "models" / "zoo.json")[0]
    cache_path = args.work / "probe_grid_eval.json"
    cache = le.read_json(cache_path, {"scenes": {}})
    key = f"{VERSION}-{args.spacings}-{args.share:g}"
    grid_names = [f"grid_{s:g}m" for s in spacings]

    for stem in tqdm.tqdm(files, desc="files", unit="file", **ngi_paths.progress_options()):
        sc = cache["scenes"].setdefault(stem, {})
        if sc.get("key") == key and len(sc.get("frames", {})) == len(frames):
            continue
        spec = str(args.vox_dir / f"{stem}.vox")
        scene = ngi.Scene(spec)
        renderer = ngi.Renderer(device, scene)
        probes = ngi.VoxelProbes(renderer)
        samples = record["scenes"][stem]["probes"]["samples"]
        t0 = time.monotonic()
        faces = adapt_eval.bake_faces(probes, samples, 0)
        face_s = faces[2]
        bakes = {"faces": {"samples": samples, "seconds": face_s, "wall_s": time.monotonic() - t0,
                           "voxels": probes.count}}
        grids = {}
        for name, s in zip(grid_names, spacings):
            grid = ProbeGrid(scene.blocks, spacing=s)
            directions, done = calibrated_grid(grid, renderer, args.share * face_s)
            bakes[name] = {"spacing": s, "probes": grid.count, "directions": directions, **done}
            grids[name] = grid
        sc.update({"key": key, "bakes": bakes, "frames": {}})
        for k in frames:
            name = f"{k:04d}"
            d = args.frames_dir / stem / name
            gi_eval.render_vox_frame(ngi_bin, spec, k, adapt_eval.PATH_FRAMES, 1024, 1024, d, "pocl")
            fr = ngi.read_frame(str(d))
            if float(np.max(fr.reference)) <= 0.0:
                sc["frames"][name] = {"unlit": True}
                continue
            cam = le.read_json(d / "render.json")["camera"]
            up = le.read_json(d / "camera.json")["up"]
            ref = scoring.Reference(device, ev.pipe(64), fr)
            lightmaps = {"direct": fr.feature("direct")[0], "ssgi_surround": ev.lightmap(ssgi, {64: fr}),
                         "probes": adapt_eval.probe_lightmap(probes, fr, cam["position"], faces[0])[0]}
            for gname, grid in grids.items():
                lightmaps[gname] = grid_lightmap(grid, fr, (cam["position"], cam["look"], up))
            sc["frames"][name] = {"unlit": False, "scores": {
                m: {kk: v for kk, v in ref.score(lm).items() if kk != "display"} for m, lm in lightmaps.items()}}
        le.write_json(cache_path, cache)
        log(f"probe_grid_eval: {stem}: " + ", ".join(f"{m} {b['seconds']:.1f} s" for m, b in bakes.items()))

    summary = summarize(cache, files, record, grid_names, key, args)
    le.write_json(args.out / "probe_grid.json", summary)
    (args.out / "probe_grid_tables.md").write_text(tables(summary, grid_names))
    log(f"probe_grid_eval: wrote {args.out / 'probe_grid.json'}, {args.out / 'probe_grid_tables.md'}")
    return 0


def summarize(cache, files, record, grid_names, key, args):
    methods = ["direct", "ssgi_surround", "probes", *grid_names]
    rows = {("direct_only" if m == "direct" else m): [] for m in methods}
    for stem in files:
        sc = cache["scenes"].get(stem, {})
        if sc.get("key") != key:
            continue
        for k, e in sorted(sc["frames"].items()):
            if e.get("unlit"):
                continue
            for m in methods:
                rows["direct_only" if m == "direct" else m].append(
                    {"frame": f"{stem}/{k}", "file": stem, "group": gi_eval.vox_group(stem), **e["scores"][m]})
    per = engine_eval.summarize(rows, "ssgi_surround")
    rec = record["methods"]
    return {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
            "settings": {"record": str(args.record), "frames": record["settings"]["frames"], "spacings": args.spacings,
                         "share_of_face_bake": args.share, "version": VERSION},
            "methods": per,
            "record": {m: {f: rec[m]["files"].get(f) for f in ["all", *files]} for m in ("adapted", "probes",
                                                                                         "direct_only")},
            "bakes": {stem: cache["scenes"][stem]["bakes"] for stem in files if stem in cache["scenes"]}}


def tables(s, grid_names):
    fmt, pct = gi_eval.fmt, (lambda x: "-" if x is None else f"{100 * x:.0f} %")
    L = [f"# A probe grid against the face bake and the adapted network (generated {s['generated']})", "",
         "Frames of adapt_eval's record (the same path frames, engine inputs, 1,024 spp); each grid baked in "
         f"{s['settings']['share_of_face_bake']:g} x the time the face bake took here (a tenth of each adaptation's "
         "time in the record). Written by training/ngi_train/probe_grid_eval.py.", "",
         "| method | PSNR dB | SSIM | frames > 1 dB below direct | > 1 dB below SSGI | worst frame vs direct |",
         "| --- | --- | --- | --- | --- | --- |"]
    for m, r in s["methods"].items():
        g, h = r["groups"]["all"], r["honesty"]["all"]
        w = h["worst_vs_direct"]
        L.append(f"| {m} | {fmt(g['psnr'])} | {fmt(g['ssim'], '.3f')} | {pct(h['below_direct_share'])} | "
                 f"{pct(h['below_ssgi_share'])} | "
                 f"{(w['file'] + ' ' + str(w['frame']) + ': ' + format(w['db'], '+.2f')) if w else '-'} |")
    # The record's adapted network over the files of this run (its per-file means, weighted by their frames).
    files = [f for f in s["bakes"] if s["record"]["adapted"].get(f)]
    n = sum(s["record"]["adapted"][f]["frames"] for f in files)
    ad = {k: sum(s["record"]["adapted"][f][k] * s["record"]["adapted"][f]["frames"] for f in files) / max(n, 1)
          for k in ("psnr", "ssim")}
    L.append(f"| adapted (the record's, {n} frames) | {fmt(ad['psnr'])} | {fmt(ad['ssim'], '.3f')} | | | |")
    L += ["", "Per file: mean final PSNR dB; the bakes (probes, directions per probe, seconds); the record's adapted "
          "network and face bake for the check.", "",
          "| file | direct | ssgi | face bake (record) | " + " | ".join(grid_names) + " | adapted (record) | "
          "face bake: voxels, samples, s | " + " | ".join(f"{g}: probes, dirs, s" for g in grid_names) + " |",
          "| --- | --- | --- | --- | " + "--- | " * len(grid_names) + "--- | --- | " + "--- | " * len(grid_names)]
    for stem, b in s["bakes"].items():
        cell = lambda m: s["methods"][m]["files"].get(stem, {}).get("psnr")  # noqa: E731
        rec = lambda m: (s["record"][m].get(stem) or {}).get("psnr")  # noqa: E731
        L.append(f"| {stem} | {fmt(cell('direct_only'))} | {fmt(cell('ssgi_surround'))} | {fmt(cell('probes'))} "
                 f"({fmt(rec('probes'))}) | " + " | ".join(fmt(cell(g)) for g in grid_names)
                 + f" | {fmt(rec('adapted'))} | {b['faces']['voxels']}, {b['faces']['samples']}, "
                   f"{b['faces']['seconds']:.1f} | "
                 + " | ".join(f"{b[g]['probes']}, {b[g]['directions']}, {b[g]['seconds']:.1f}" for g in grid_names)
                 + " |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())

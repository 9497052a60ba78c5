#!/usr/bin/python3
"""Issue 46's evaluation: `ngi adapt` against the base network, SSGI, direct light and a probe bake (docs/ADAPT.md).

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.adapt_eval --vox-dir ../shared/scenes/vox \\
        --work runs/adapt_eval --out docs/results/adapt [--files monu0,teapot] [--budget-minutes 10]

Per scene (every .vox file of --vox-dir, or --scenes: procedural specs, where settings may be chosen):
1. ngi_train.adapt fits the base network to the scene within --budget-minutes (its frames: other camera paths
   than the ones scored here); its time per phase is read back from the model's "adapt" record.
2. The competitor, baked in the same wall time (--probe-share x the adaptation's; the path count calibrated on
   bakes of 4 and 16 samples): the lighting path-traced at the scene's surface voxels (ngi.VoxelProbes), the
   indirect part (8 bounces minus 0) added to the frame's own direct light, in two representations:
   - probes: per exposed voxel face (a lightmap baked at block-face resolution; each pixel takes the face of the
     voxel behind it that its normal points out of);
   - probe_points: one value per voxel at seed 004's probe point (its occupancy-gradient normal): what one
     irradiance probe per surface block gives;
   and probes_half: the face bake with half the samples and another seed (whether the bake had converged).
3. The frames scored: path frames --frames (of 100) of the scene's dataset camera path (what engine_eval scores:
   `ngi render` without --path-seed), engine inputs (direct light and references at 1,024 spp; cached in
   --frames-dir). Each method's lightmap is scored with ngi.scoring (final image tone-mapped, data range 1).

Writes OUT/adapt.json (every per-frame score, per-scene times) and OUT/adapt_tables.md; OUT/adapt_strip.png
(direct | base | probes | adapted | reference, the middle frame of each scene). Scores are cached per frame and
model digest in WORK/adapt_eval.json: an interrupted run continues where it stopped.
"""

import argparse
import datetime
import sys
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.model_file as model_file
import ngi.plan as plan
import ngi.scoring as scoring
import ngi.temporal as temporal

from ngi_train import adapt, ngi_paths
from ngi_train.generator import engine_eval, gi_eval, ladder_eval as le

PATH_FRAMES = 100
METHODS = ("direct", "ssgi_surround", "base", "probe_points", "probes", "probes_half", "adapted")
PROBE_METHOD = "-faces-points"  # part of the score cache's key: the probe shading's version (per voxel face)
log = le.log


def scenes(args):
    if args.scenes:
        return [(spec, spec.replace(":", "_").replace("=", "")) for spec in args.scenes]
    files = {f.stem: f for f in sorted(Path(args.vox_dir).glob("*.vox"))}
    order = [s for s in args.files if s in files] if args.files else list(files)  # --files' order when given
    return [(str(files[s]), s) for s in order]


def bake_faces(probes, samples, seed):
    """Two bakes of `samples` paths (8 bounces and 0) -> (the indirect light of every exposed voxel face [V, 6, 3]:
    full lighting minus direct light, each averaged over the face; the indirect light at every voxel's probe point
    [V, 3], seed 004's one irradiance value per voxel; seconds; rays)."""
    full = probes.bake(samples=samples, bounces=8, seed=seed)
    direct = probes.bake(samples=samples, bounces=0, seed=seed)
    return (full["face_lighting"] - direct["face_lighting"], full["lighting"] - full["direct"],
            full["seconds"] + direct["seconds"], full["rays"] + direct["rays"])


def calibrated_bake(probes, seconds, share):
    """The face bake with as many samples as ~share x seconds allow (its time fitted as a + b samples from bakes
    of 4 and 16 samples), and one with half of them and another seed (the convergence check)."""
    t4, t16 = bake_faces(probes, 4, 99)[2], bake_faces(probes, 16, 98)[2]
    per_sample = max(1e-9, (t16 - t4) / 12.0)
    fixed = max(0.0, t4 - 4 * per_sample)
    samples = int(max(1, min(1 << 20, (share * seconds - fixed) / per_sample)))
    return samples, bake_faces(probes, samples, 0), bake_faces(probes, max(1, samples // 2), 1)


def probe_lightmap(probes, frame, position, faces):
    """The frame's direct light + the baked indirect light of the voxel face each front pixel sees (the face whose
    axis the pixel's normal is closest to: a voxel scene's faces are axis-aligned)."""
    direct = frame.feature("direct")[0]
    normal = frame.feature("normal")[0]
    axis = np.argmax(np.abs(normal), axis=0)
    negative = np.take_along_axis(normal, axis[None], 0)[0] < 0
    face = 2 * axis + negative  # +x -x +y -y +z -z, as face_lighting
    indirect = np.zeros_like(direct)
    misses = 0
    for f in range(6):
        pick = face == f
        if pick.any():
            lit, misses = probes.shade(frame, position, faces[:, f, :])  # misses: the same count for every field
            indirect[:, pick] = lit[:, pick]
    return direct + indirect, misses


def sequence_flicker(args, ev, stem, spec, ngi_bin, rungs, probes, faces):
    """Warping error (ngi.temporal.warp_error, of the tone-mapped final images) of every method over consecutive
    path frames --sequence of the dataset path, and its ratio to the reference's own (1 = as stable as the truth)."""
    ks = list(range(args.sequence[0], args.sequence[1] + 1))
    images = {m: [] for m in ("reference", *METHODS)}
    depths, cameras = [], []
    for k in tqdm.tqdm(ks, desc=f"{stem}: sequence", unit="frame", **ngi_paths.progress_options()):
        d = args.frames_dir / stem / f"{k:04d}"
        gi_eval.render_vox_frame(ngi_bin, spec, k, PATH_FRAMES, 1024, 1024, d, "pocl")
        fr = ngi.read_frame(str(d))
        cam = le.read_json(d / "render.json")["camera"]
        up = le.read_json(d / "camera.json")["up"]
        cameras.append((cam["position"], cam["look"], up))
        depths.append(fr.feature("depth")[0][0])
        ref = scoring.Reference(ev.device, ev.pipe(64), fr)
        images["reference"].append(ref.final)
        direct = fr.feature("direct")[0]
        lms = {"direct": direct, **{m: ev.lightmap(r, {64: fr}) for m, r in rungs.items()}}
        lms["probes"] = probe_lightmap(probes, fr, cam["position"], faces)[0]
        for m in METHODS:
            if m in lms:
                images[m].append(ref.score(lms[m])["display"])
    masks = temporal.warp_masks(depths, cameras)
    ref_err, share = temporal.warp_error(images["reference"], masks)
    errs = {m: temporal.warp_error(images[m], masks)[0] for m in METHODS if images[m]}
    return {"frames": ks, "valid_share": share, "reference": ref_err, "warp_error": errs,
            "ratio": {m: e / ref_err if ref_err > 0 else None for m, e in errs.items()}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--vox-dir", type=Path, help="the folder of .vox files (read only)")
    where.add_argument("--scenes", default="", help="comma-separated procedural specs instead (room:seed=301,...)")
    ap.add_argument("--files", default="", help="comma-separated .vox stems (default: every file)")
    ap.add_argument("--work", type=Path, required=True, help="adaptation folders, models and the score cache")
    ap.add_argument("--frames-dir", type=Path, default=le.REPO / "runs" / "engine" / "frames" / "ref1024_feat1024",
                    help="the scored frames (engine_eval's cache: <stem>/<frame>)")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--frames", default="10,30,50,70,90", help="path frames (of 100) scored per scene")
    ap.add_argument("--budget-minutes", type=float, default=10.0)
    ap.add_argument("--probe-share", type=float, default=1.0,
                    help="the probe bake's time as a share of the adaptation's (1 = equal time)")
    ap.add_argument("--base", default=adapt.DEFAULT_BASE)
    ap.add_argument("--lr", type=float, default=adapt.FINE_TUNE_LR, help="the adaptation's learning rate")
    ap.add_argument("--sequence", default="40,47",
                    help="first,last consecutive path frames whose flicker (warping error) is measured ('' = none)")
    ap.add_argument("--sequence-files", default="",
                    help="comma-separated scenes whose sequence is measured (default: every scene)")
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    args.frames = [int(k) for k in args.frames.split(",")]
    args.sequence = [int(k) for k in args.sequence.split(",")] if args.sequence else None
    if args.sequence and (len(args.sequence) != 2 or not 0 <= args.sequence[0] < args.sequence[1] < PATH_FRAMES):
        ap.error(f"--sequence: first,last with 0 <= first < last < {PATH_FRAMES}")
    args.sequence_files = set(x for x in args.sequence_files.split(",") if x)
    args.files = list(dict.fromkeys(x for x in args.files.split(",") if x))
    args.scenes = [x for x in args.scenes.split(",") if x]
    args.out.mkdir(parents=True, exist_ok=True)
    args.work.mkdir(parents=True, exist_ok=True)
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    device = ngi.Device(args.device)
    ev = plan.Evaluator(device, None)
    ssgi = engine_eval.resolve_rungs(["ssgi_surround_n64"], le.REPO / "models" / "zoo.json")[0]
    cache_path = args.work / "adapt_eval.json"
    cache = le.read_json(cache_path, {"scenes": {}})

    digests = {}
    for spec, stem in scenes(args):
        sc = cache["scenes"].setdefault(stem, {"frames": {}})
        model = args.work / stem / "adapted.safetensors"
        if not model.is_file():
            log(f"adapt_eval: adapting to {stem} ({args.budget_minutes:g} min)")
            code = adapt.main(["--scene", spec, "--out", str(model), "--budget-minutes", str(args.budget_minutes),
                               "--work", str(args.work / stem / "adapt"), "--base", args.base, "--ngi", ngi_bin,
                               "--lr", str(args.lr)])
            if code != 0:
                raise SystemExit(f"adapt_eval: adapt failed for {stem} ({code})")
        record = model_file.read_model(str(model))[1]["adapt"]
        asked = {"budget_s": args.budget_minutes * 60.0, "lr": args.lr, "base": Path(ngi.resolve_model(args.base)).stem}
        if {k: record.get(k) for k in asked} != asked:
            raise SystemExit(f"adapt_eval: {model} was adapted with {({k: record.get(k) for k in asked})}, not "
                             f"{asked}: use another --work folder")
        adapt_s = sum(record["spent_s"].values())
        sc["adapt"] = {k: record[k] for k in ("spent_s", "budget_s", "frames", "steps", "chosen_step", "note")}
        sc["adapt"]["validation"] = {k: record["validation"][k]["l1"] for k in ("base", "chosen")}
        sc["adapt"]["curve"] = record["validation"]["curve"]
        digest = le.digest(str(model))[:16] + PROBE_METHOD
        digests[stem] = digest
        rungs = {"ssgi_surround": ssgi,
                 "base": {"name": "base", "kind": "rung", "path": ngi.resolve_model(args.base), "n": 64, "bn_mode": None},
                 "adapted": {"name": f"adapted_{stem}", "kind": "rung", "path": str(model), "n": 64, "bn_mode": None}}
        renderer = ngi.Renderer(device, ngi.Scene(spec))
        probes = None
        for k in tqdm.tqdm(args.frames, desc=f"{stem}: frames", unit="frame", **ngi_paths.progress_options()):
            name = f"{k:04d}"
            e = sc["frames"].get(name)
            if e is not None and e.get("digest") == digest and (sc.get("probes") or {}).get("share") == args.probe_share:
                continue
            d = args.frames_dir / stem / name
            gi_eval.render_vox_frame(ngi_bin, spec, k, PATH_FRAMES, 1024, 1024, d, "pocl")
            fr = ngi.read_frame(str(d))
            if float(np.max(fr.reference)) <= 0.0:
                sc["frames"][name] = {"digest": digest, "unlit": True}
                continue
            if probes is None:
                probes = ngi.VoxelProbes(renderer)
                samples, full, half = calibrated_bake(probes, adapt_s, args.probe_share)
                sc["probes"] = {"voxels": probes.count, "samples": samples, "seconds": full[2], "rays": full[3],
                                "half_seconds": half[2], "share": args.probe_share}
                np.save(args.work / stem / "probe_faces.npy", full[0])  # for the strip
            position = le.read_json(d / "render.json")["camera"]["position"]
            ref = scoring.Reference(device, ev.pipe(64), fr)
            direct = fr.feature("direct")[0]
            lightmaps = {"direct": direct}
            for m, r in rungs.items():
                lightmaps[m] = ev.lightmap(r, {64: fr})
            for m, b in (("probes", full), ("probes_half", half)):
                lightmaps[m], misses = probe_lightmap(probes, fr, position, b[0])
            lightmaps["probe_points"] = direct + probes.shade(fr, position, full[1])[0]
            scores = {m: {kk: v for kk, v in ref.score(lm).items() if kk != "display"} for m, lm in lightmaps.items()}
            sc["frames"][name] = {"digest": digest, "unlit": False, "scores": scores, "probe_misses": int(misses)}
            le.write_json(cache_path, cache)
        seq_key = f"{digest}-{args.sequence}"
        if args.sequence and (not args.sequence_files or stem in args.sequence_files) and \
                (sc.get("sequence") or {}).get("key") != seq_key:
            if probes is None:
                probes = ngi.VoxelProbes(renderer)
            faces = np.load(args.work / stem / "probe_faces.npy")
            sc["sequence"] = {"key": seq_key, **sequence_flicker(args, ev, stem, spec, ngi_bin, rungs, probes, faces)}
        le.write_json(cache_path, cache)

    summary = summarize(cache, [stem for _, stem in scenes(args)], args, digests)
    le.write_json(args.out / "adapt.json", summary)
    (args.out / "adapt_tables.md").write_text(tables(summary))
    strip(args, ev, summary, args.out / "adapt_strip.png")
    log(f"adapt_eval: wrote {args.out / 'adapt.json'}, {args.out / 'adapt_tables.md'}, {args.out / 'adapt_strip.png'}")
    return 0


def rows_by_method(cache, stems, frames, digests):
    """engine_eval's rows ({frame 'scene/KKKK', file, group, final, lightmap}) per method over the lit frames of
    this run (path frames `frames`, scored with the models of `digests`: {stem: digest}; older entries of the
    cache are left out), the direct-light method named direct_only, as engine_eval.summarize expects."""
    rows = {("direct_only" if m == "direct" else m): [] for m in METHODS}
    wanted = {f"{k:04d}" for k in frames}
    for stem in stems:
        for k, e in sorted(cache["scenes"].get(stem, {}).get("frames", {}).items()):
            if e.get("unlit") or k not in wanted or e.get("digest") != digests.get(stem):
                continue
            for m in METHODS:
                rows["direct_only" if m == "direct" else m].append(
                    {"frame": f"{stem}/{k}", "file": stem, "group": gi_eval.vox_group(stem), **e["scores"][m]})
    return rows


def summarize(cache, stems, args, digests):
    rows = rows_by_method(cache, stems, args.frames, digests)
    per = engine_eval.summarize(rows, "ssgi_surround")
    scenes_below = lambda m, base: sum(  # noqa: E731
        per[m]["files"][f]["psnr"] < per[base]["files"][f]["psnr"] for f in per[m]["files"] if f != "all")
    for m in per:
        per[m]["scenes_below_direct"] = scenes_below(m, "direct_only")
        per[m]["scenes_below_ssgi"] = scenes_below(m, "ssgi_surround")
    return {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
            "settings": {"vox_dir": args.vox_dir.name if args.vox_dir else None, "scenes": args.scenes,
                         "frames": args.frames, "budget_minutes": args.budget_minutes, "probe_share": args.probe_share,
                         "base": args.base, "lr": args.lr, "face": 64, "eval_feature_spp": 1024, "eval_ref_spp": 1024},
            "methods": per,
            "scenes": {stem: {k: cache["scenes"][stem].get(k) for k in ("adapt", "probes", "sequence")}
                       for stem in stems if stem in cache["scenes"]}}


def tables(s):
    fmt, pct = gi_eval.fmt, (lambda x: "-" if x is None else f"{100 * x:.0f} %")
    names = list(s["methods"])
    L = [f"# ngi adapt against a probe bake (generated {s['generated']})", "",
         f"Budget {s['settings']['budget_minutes']:g} min per scene (render + train); the probe bake gets "
         f"{s['settings']['probe_share']:g} x the adaptation's time; path frames {s['settings']['frames']} of each "
         "scene's dataset path (no adaptation frame is on it), engine inputs (direct light and references at "
         "1,024 spp), final images (ACES, sRGB). Written by training/ngi_train/adapt_eval.py.", "",
         "| method | PSNR dB | SSIM | frames > 1 dB below direct | > 1 dB below SSGI | worst frame vs direct | "
         "scenes below direct | scenes below SSGI |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for m in names:
        r, h = s["methods"][m], s["methods"][m]["honesty"]["all"]
        g, w = r["groups"]["all"], h["worst_vs_direct"]
        L.append(f"| {m} | {fmt(g['psnr'])} | {fmt(g['ssim'], '.3f')} | {pct(h['below_direct_share'])} | "
                 f"{pct(h['below_ssgi_share'])} | {(w['file'] + ' ' + str(w['frame']) + ': ' + format(w['db'], '+.2f')) if w else '-'} | "
                 f"{r['scenes_below_direct']} | {r['scenes_below_ssgi']} |")
    L += ["", "Per scene: mean final PSNR dB (SSIM); the adaptation's frames, steps and seconds; the probe bake.", "",
          "| scene | group | " + " | ".join(names) + " | adapt: train frames, steps (chosen), render / train s | "
          "probes: voxels, samples, s |", "| --- | --- | " + "--- | " * len(names) + "--- | --- |"]
    for stem, sc in s["scenes"].items():
        cells = [s["methods"][m]["files"].get(stem) for m in names]
        if not all(cells) or not sc.get("adapt"):
            continue
        a, pr = sc["adapt"], sc.get("probes") or {}
        L.append(f"| {stem} | {gi_eval.vox_group(stem)} | "
                 + " | ".join(f"{fmt(c['psnr'])} ({fmt(c['ssim'], '.3f')})" for c in cells)
                 + f" | {a['frames']['train']}, {a['steps']} ({a['chosen_step']}), "
                   f"{a['spent_s'].get('render', 0):.0f} / {a['spent_s'].get('train', 0):.0f} | "
                   f"{pr.get('voxels')}, {pr.get('samples')}, {pr.get('seconds', 0):.1f} |")
    seqs = {stem: sc["sequence"] for stem, sc in s["scenes"].items() if sc.get("sequence")}
    if seqs:
        ms = [m for m in names if m != "probes_half" and m != "probe_points"]
        L += ["", "Flicker under the moving camera: warping error of the final images over consecutive path frames "
              "(ngi.temporal), as a ratio to the reference's own (1 = as stable as the path-traced truth).", "",
              "| scene | frames | reference warping error | " + " | ".join(ms) + " |",
              "| --- | --- | --- | " + "--- | " * len(ms)]
        for stem, q in seqs.items():
            ratio = {("direct_only" if k == "direct" else k): v for k, v in q["ratio"].items()}
            L.append(f"| {stem} | {q['frames'][0]}-{q['frames'][-1]} | {q['reference']:.4f} | "
                     + " | ".join(fmt(ratio.get(m)) for m in ms) + " |")
        mean = {m: np.mean([q["ratio"][("direct" if m == "direct_only" else m)] for q in seqs.values()]) for m in ms}
        L.append(f"| mean ({len(seqs)} scenes) | | | " + " | ".join(fmt(mean[m]) for m in ms) + " |")
    return "\n".join(L) + "\n"


def strip(args, ev, summary, out_png):
    """direct | base | probes | adapted | reference: the middle scored frame of every scene."""
    cache = le.read_json(args.work / "adapt_eval.json", {"scenes": {}})
    rows = []
    middle = f"{args.frames[len(args.frames) // 2]:04d}"
    for stem in summary["scenes"]:
        d = args.frames_dir / stem / middle
        sc = cache["scenes"].get(stem, {})
        if not d.is_dir() or sc.get("frames", {}).get(middle, {}).get("unlit", True):
            continue
        fr = ngi.read_frame(str(d))
        ref = scoring.Reference(ev.device, ev.pipe(64), fr)
        direct = fr.feature("direct")[0]
        base = {"name": "base", "kind": "rung", "path": ngi.resolve_model(args.base), "n": 64, "bn_mode": None}
        adapted = {"name": f"adapted_{stem}", "kind": "rung", "path": str(args.work / stem / "adapted.safetensors"),
                   "n": 64, "bn_mode": None}
        spec = next(sp for sp, st in scenes(args) if st == stem)
        probes = ngi.VoxelProbes(ngi.Renderer(ev.device, ngi.Scene(spec)))
        faces = np.load(args.work / stem / "probe_faces.npy")
        probe_lm, _ = probe_lightmap(probes, fr, le.read_json(d / "render.json")["camera"]["position"], faces)
        lms = [direct, ev.lightmap(base, {64: fr}), probe_lm, ev.lightmap(adapted, {64: fr})]
        rows.append((f"{stem}/{middle}", [ref.score(lm)["display"] for lm in lms] + [ref.final]))
    if rows:
        gi_eval.draw_strip(rows, ["direct light", "base network", "probe bake", "adapted", "reference"], out_png)


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Issue 46 under a moving sun: `ngi adapt --times` against bakes, at times of day nobody trained or baked at.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.adapt_sun_eval --vox-dir ../shared/scenes/vox \\
        --files monu0,teapot --work runs/adapt_sun_eval --out docs/results/adapt_sun [--budget-minutes 4]

A baked lightmap holds one sun; a network reads the sun from the frame's direct light. This measures whether that
matters, per scene:
1. ngi_train.adapt fits the base network to the scene with its training and validation views spread over
   --train-times (hours of day), within --budget-minutes.
2. The competitors, baked in --probe-share x the adaptation's time (ngi.VoxelProbes, per exposed voxel face, as
   adapt_eval's "probes"):
   - bake_fixed: one bake at the scene's own time (what a static lightmap is), used at every time of day;
   - bake_blend: a bake at every --train-times hour, the same total time split between them, blended linearly
     between the two baked hours around the frame's (time-of-day lightmap blending).
   Also scored: direct light, ssgi_surround (recomputed every frame, so it follows the sun), the base network,
   and, where --fixed-work holds one, the model adapt_eval fitted at the scene's own time only (adapted_fixed).
3. The frames scored: path frames --frames of the scene's dataset path (no adaptation frame is on it) at every
   --eval-times hour (none of them trained or baked at), engine inputs (direct light and references at 1,024 spp).
4. Flicker under a moving sun: the camera at path frame --sun-frame, --sun-steps frames whose time of day advances
   by --sun-step hours from --sun-start; the warping error of each method's final images (ngi.temporal; a still
   camera: every pixel valid) as a ratio to the reference's own.

Writes OUT/adapt_sun.json, OUT/adapt_sun_tables.md and OUT/adapt_sun_strip.png (direct | ssgi | bake_fixed |
bake_blend | adapted_sun | reference, one unseen time per scene). Scores are cached in WORK/adapt_sun_eval.json.
"""

import argparse
import bisect
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

from ngi_train import adapt, adapt_eval, ngi_paths
from ngi_train.generator import engine_eval, gi_eval, ladder_eval as le

PATH_FRAMES = adapt_eval.PATH_FRAMES
METHODS = ("direct", "ssgi_surround", "base", "adapted_fixed", "bake_fixed", "bake_blend", "adapted_sun")
EVAL_SPP = 1024
log = le.log


def hours_list(text):
    return [float(h) for h in text.split(",") if h.strip()]


def render_at(ngi_bin, spec, k, hours, out):
    """`ngi render` of dataset path frame k at time of day `hours` into `out` (engine inputs), unless it is there."""
    gi_eval.render_vox_frame(ngi_bin, spec, k, PATH_FRAMES, EVAL_SPP, EVAL_SPP, out, "pocl", hours)


def blend_weights(baked, hours):
    """[(index into baked, weight)]: linear between the two baked hours around `hours`, the nearest outside."""
    j = bisect.bisect_left(baked, hours)
    if j == 0:
        return [(0, 1.0)]
    if j == len(baked):
        return [(len(baked) - 1, 1.0)]
    w = (hours - baked[j - 1]) / (baked[j] - baked[j - 1])
    return [(j - 1, 1.0 - w), (j, w)]


def bakes(renderer, scene_time, train_times, seconds, share, cache_dir, load_only=False):
    """(bake_fixed's faces [V, 6, 3], [bake_blend's faces per train time], record): the fixed bake in share x seconds
    at the scene's own time; the blend's bakes in the same time split between the train times (the sample count of
    each calibrated on the scene's own time, as adapt_eval's). Cached as .npy in cache_dir, reused when the record
    has the same share and hours; load_only: the cache or None."""
    files = [cache_dir / "bake_fixed.npy"] + [cache_dir / f"bake_t{h:05.2f}.npy" for h in train_times]
    record_path = cache_dir / "bakes.json"
    record = le.read_json(record_path)
    if all(f.is_file() for f in files) and record and record["share"] == share and \
            record["blend"]["hours"] == train_times:
        return np.load(files[0]), [np.load(f) for f in files[1:]], record
    if load_only:
        return None
    probes = ngi.VoxelProbes(renderer, scene_time)
    t4, t16 = adapt_eval.bake_faces(probes, 4, 99)[2], adapt_eval.bake_faces(probes, 16, 98)[2]
    per_sample = max(1e-9, (t16 - t4) / 12.0)
    fixed_cost = max(0.0, t4 - 4 * per_sample)
    samples = lambda total: int(max(1, min(1 << 20, (total - fixed_cost) / per_sample)))  # noqa: E731
    fixed_samples = samples(share * seconds)
    fixed = adapt_eval.bake_faces(probes, fixed_samples, 0)
    blend_samples = samples(share * seconds / len(train_times))
    blend, blend_s = [], 0.0
    for i, h in enumerate(train_times):
        b = adapt_eval.bake_faces(ngi.VoxelProbes(renderer, h), blend_samples, 10 + i)
        blend.append(b[0])
        blend_s += b[2]
    cache_dir.mkdir(parents=True, exist_ok=True)
    for f, a in zip(files, [fixed[0]] + blend):
        np.save(f, a)
    record = {"voxels": probes.count, "fixed": {"hours": scene_time, "samples": fixed_samples, "seconds": fixed[2]},
              "blend": {"hours": train_times, "samples_each": blend_samples, "seconds": blend_s}, "share": share}
    le.write_json(record_path, record)
    return fixed[0], blend, record


def lightmaps(ev, rungs, probes, fr, position, hours, fixed, blend, train_times):
    direct = fr.feature("direct")[0]
    out = {"direct": direct, **{m: ev.lightmap(r, {64: fr}) for m, r in rungs.items()}}
    out["bake_fixed"] = adapt_eval.probe_lightmap(probes, fr, position, fixed)[0]
    faces = sum(w * blend[i] for i, w in blend_weights(train_times, hours))
    out["bake_blend"] = adapt_eval.probe_lightmap(probes, fr, position, faces)[0]
    return out


def sun_flicker(args, ev, stem, spec, ngi_bin, rungs, probes, fixed, blend):
    """Warping error of every method over --sun-steps frames of a still camera whose sun moves, and its ratio to
    the reference's."""
    hours = [args.sun_start + i * args.sun_step for i in range(args.sun_steps)]
    images = {m: [] for m in ("reference", *METHODS)}
    depths, cameras = [], []
    for h in tqdm.tqdm(hours, desc=f"{stem}: moving sun", unit="frame", **ngi_paths.progress_options()):
        d = args.frames_dir / stem / f"t{h:05.2f}" / f"{args.sun_frame:04d}"
        render_at(ngi_bin, spec, args.sun_frame, h, d)
        fr = ngi.read_frame(str(d))
        cam = le.read_json(d / "render.json")["camera"]
        cameras.append((cam["position"], cam["look"], le.read_json(d / "camera.json")["up"]))
        depths.append(fr.feature("depth")[0][0])
        ref = scoring.Reference(ev.device, ev.pipe(64), fr)
        images["reference"].append(ref.final)
        for m, lm in lightmaps(ev, rungs, probes, fr, cam["position"], h, fixed, blend, args.train_times).items():
            images[m].append(ref.score(lm)["display"])
    masks = temporal.warp_masks(depths, cameras)
    ref_err, share = temporal.warp_error(images["reference"], masks)
    errs = {m: temporal.warp_error(images[m], masks)[0] for m in METHODS if images[m]}
    return {"hours": hours, "frame": args.sun_frame, "valid_share": share, "reference": ref_err, "warp_error": errs,
            "ratio": {m: e / ref_err if ref_err > 0 else None for m, e in errs.items()}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vox-dir", type=Path, required=True, help="the folder of .vox files (read only)")
    ap.add_argument("--files", required=True, help="comma-separated .vox stems")
    ap.add_argument("--work", type=Path, required=True, help="adaptation folders, models, bakes and the score cache")
    ap.add_argument("--fixed-work", type=Path, default=le.REPO / "runs" / "adapt_eval",
                    help="adapt_eval's --work: its STEM/adapted.safetensors (fitted at the scene's own time) is scored "
                         "too where it exists")
    ap.add_argument("--frames-dir", type=Path, default=le.REPO / "runs" / "engine" / "frames" / "ref1024_sun",
                    help="the scored frames (<stem>/t<hours>/<frame>)")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--frames", default="10,50,90", help="path frames (of 100) scored at every --eval-times hour")
    ap.add_argument("--train-times", default="7.5,10,12.5,15,17.5", help="hours the adaptation and the blend see")
    ap.add_argument("--eval-times", default="8.75,11.25,13.75,16.25", help="hours scored (none trained or baked)")
    ap.add_argument("--budget-minutes", type=float, default=4.0)
    ap.add_argument("--probe-share", type=float, default=0.1, help="the bakes' time as a share of the adaptation's")
    ap.add_argument("--sun-frame", type=int, default=50)
    ap.add_argument("--sun-start", type=float, default=14.0)
    ap.add_argument("--sun-step", type=float, default=0.1, help="hours between the moving sun's frames")
    ap.add_argument("--sun-steps", type=int, default=8)
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    args.frames = [int(k) for k in args.frames.split(",")]
    try:
        args.train_times, args.eval_times = sorted(hours_list(args.train_times)), hours_list(args.eval_times)
    except ValueError:
        ap.error("--train-times, --eval-times: comma-separated hours expected")
    for opt, hs in (("--train-times", args.train_times), ("--eval-times", args.eval_times)):
        if not hs or not all(0 <= h <= 48 for h in hs) or len({round(h, 2) for h in hs}) != len(hs):
            ap.error(f"{opt}: distinct hours in [0, 48] (to 0.01 h) expected")
    if {round(h, 2) for h in args.train_times} & {round(h, 2) for h in args.eval_times}:
        ap.error("--eval-times must not repeat a --train-times hour")
    if args.sun_steps < 2:
        ap.error("--sun-steps: at least 2 frames")
    args.files = list(dict.fromkeys(x for x in args.files.split(",") if x))
    for d in (args.out, args.work):
        d.mkdir(parents=True, exist_ok=True)
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    device = ngi.Device(args.device)
    ev = plan.Evaluator(device, None)
    ssgi = engine_eval.resolve_rungs(["ssgi_surround_n64"], le.REPO / "models" / "zoo.json")[0]
    cache_path = args.work / "adapt_sun_eval.json"
    cache = le.read_json(cache_path, {"scenes": {}})
    times_arg = ",".join(repr(h) for h in args.train_times)

    digests = {}
    for stem in args.files:
        spec = str(args.vox_dir / f"{stem}.vox")
        sc = cache["scenes"].setdefault(stem, {"frames": {}})
        model = args.work / stem / "adapted_sun.safetensors"
        if not model.is_file():
            log(f"adapt_sun_eval: adapting to {stem} over {times_arg} h ({args.budget_minutes:g} min)")
            code = adapt.main(["--scene", spec, "--out", str(model), "--budget-minutes", str(args.budget_minutes),
                               "--work", str(args.work / stem / "adapt"), "--ngi", ngi_bin, "--times", times_arg])
            if code != 0:
                raise SystemExit(f"adapt_sun_eval: adapt failed for {stem} ({code})")
        record = model_file.read_model(str(model))[1]["adapt"]
        if record["frames"].get("times_h") != args.train_times or record["budget_s"] != args.budget_minutes * 60:
            raise SystemExit(f"adapt_sun_eval: {model} was adapted over {record['frames'].get('times_h')} h in "
                             f"{record['budget_s']} s: use another --work folder")
        adapt_s = sum(record["spent_s"].values())
        sc["adapt"] = {k: record[k] for k in ("spent_s", "budget_s", "frames", "steps", "chosen_step", "note")}
        rungs = {"ssgi_surround": ssgi,
                 "base": {"name": "base", "kind": "rung", "path": ngi.resolve_model(adapt.DEFAULT_BASE), "n": 64,
                          "bn_mode": None},
                 "adapted_sun": {"name": f"adapted_sun_{stem}", "kind": "rung", "path": str(model), "n": 64,
                                 "bn_mode": None}}
        fixed_model = args.fixed_work / stem / "adapted.safetensors"
        if fixed_model.is_file():
            rungs["adapted_fixed"] = {"name": f"adapted_{stem}", "kind": "rung", "path": str(fixed_model), "n": 64,
                                      "bn_mode": None}
        scene = ngi.Scene(spec)
        renderer = ngi.Renderer(device, scene)
        fixed, blend, sc["bakes"] = bakes(renderer, scene.default_time, args.train_times, adapt_s, args.probe_share,
                                          args.work / stem)
        probes = ngi.VoxelProbes(renderer)  # shading only: the baked fields carry the light
        b = sc["bakes"]
        digest = ("-".join(le.digest(r["path"])[:12] for r in rungs.values())
                  + f"-{args.probe_share:g}-{b['fixed']['samples']}-{b['blend']['samples_each']}")
        digests[stem] = digest
        views = [(h, k) for h in args.eval_times for k in args.frames]
        for h, k in tqdm.tqdm(views, desc=f"{stem}: frames", unit="frame", **ngi_paths.progress_options()):
            name = f"t{h:05.2f}/{k:04d}"
            if (sc["frames"].get(name) or {}).get("digest") == digest:
                continue
            d = args.frames_dir / stem / name
            render_at(ngi_bin, spec, k, h, d)
            fr = ngi.read_frame(str(d))
            if float(np.max(fr.reference)) <= 0.0:
                sc["frames"][name] = {"digest": digest, "unlit": True}
                continue
            position = le.read_json(d / "render.json")["camera"]["position"]
            ref = scoring.Reference(device, ev.pipe(64), fr)
            lms = lightmaps(ev, rungs, probes, fr, position, h, fixed, blend, args.train_times)
            sc["frames"][name] = {"digest": digest, "unlit": False, "hours": h,
                                  "scores": {m: {kk: v for kk, v in ref.score(lm).items() if kk != "display"}
                                             for m, lm in lms.items()}}
            le.write_json(cache_path, cache)
        seq_key = f"{digest}-{args.sun_frame}-{args.sun_start}-{args.sun_step}-{args.sun_steps}"
        if (sc.get("sun_sequence") or {}).get("key") != seq_key:
            sc["sun_sequence"] = {"key": seq_key,
                                  **sun_flicker(args, ev, stem, spec, ngi_bin, rungs, probes, fixed, blend)}
        le.write_json(cache_path, cache)

    summary = summarize(cache, args, digests)
    le.write_json(args.out / "adapt_sun.json", summary)
    (args.out / "adapt_sun_tables.md").write_text(tables(summary))
    strip(args, ev, ssgi, args.out / "adapt_sun_strip.png")
    log(f"adapt_sun_eval: wrote {args.out / 'adapt_sun.json'}, {args.out / 'adapt_sun_tables.md'}")
    return 0


def summarize(cache, args, digests):
    methods = [m for m in METHODS if all(
        m in e["scores"] for stem in args.files for e in cache["scenes"][stem]["frames"].values()
        if not e.get("unlit") and e.get("digest") == digests[stem])]
    rows = {("direct_only" if m == "direct" else m): [] for m in methods}
    wanted = {f"t{h:05.2f}/{k:04d}" for h in args.eval_times for k in args.frames}
    for stem in args.files:
        for name, e in sorted(cache["scenes"][stem]["frames"].items()):
            if e.get("unlit") or name not in wanted or e.get("digest") != digests[stem]:
                continue
            for m in methods:
                rows["direct_only" if m == "direct" else m].append(
                    {"frame": f"{stem}/{name}", "file": stem, "group": f"{e['hours']:g} h", **e["scores"][m]})
    per = engine_eval.summarize(rows, "ssgi_surround")
    for m in per:
        for base in ("direct_only", "ssgi_surround"):
            per[m][f"scenes_below_{base.split('_')[0]}"] = sum(
                per[m]["files"][f]["psnr"] < per[base]["files"][f]["psnr"] for f in per[m]["files"] if f != "all")
    return {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
            "settings": {"files": args.files, "frames": args.frames, "train_times": args.train_times,
                         "eval_times": args.eval_times, "budget_minutes": args.budget_minutes,
                         "probe_share": args.probe_share, "face": 64, "eval_spp": EVAL_SPP,
                         "sun_sequence": {"frame": args.sun_frame, "start": args.sun_start, "step": args.sun_step,
                                          "steps": args.sun_steps}},
            "methods": per,
            "scenes": {stem: {k: cache["scenes"][stem].get(k) for k in ("adapt", "bakes", "sun_sequence")}
                       for stem in args.files}}


def tables(s):
    fmt, pct = gi_eval.fmt, (lambda x: "-" if x is None else f"{100 * x:.0f} %")
    names = list(s["methods"])
    st = s["settings"]
    if not names or not s["methods"][names[0]]["groups"].get("all"):
        return f"# ngi adapt under a moving sun (generated {s['generated']})\n\nNo lit frame was scored.\n"
    L = [f"# ngi adapt under a moving sun (generated {s['generated']})", "",
         f"{len(st['files'])} scenes; adaptation over {', '.join(f'{h:g}' for h in st['train_times'])} h in "
         f"{st['budget_minutes']:g} min; bakes in {st['probe_share']:g} x the adaptation's time; scored at "
         f"{', '.join(f'{h:g}' for h in st['eval_times'])} h (never trained or baked at), path frames {st['frames']} "
         "of each scene's dataset path, engine inputs, final images. Written by training/ngi_train/adapt_sun_eval.py.",
         "", "| method | PSNR dB | SSIM | frames > 1 dB below direct | > 1 dB below SSGI | worst frame vs direct | "
         "scenes below direct | scenes below SSGI |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for m in names:
        r, h = s["methods"][m], s["methods"][m]["honesty"]["all"]
        g, w = r["groups"]["all"], h["worst_vs_direct"]
        L.append(f"| {m} | {fmt(g['psnr'])} | {fmt(g['ssim'], '.3f')} | {pct(h['below_direct_share'])} | "
                 f"{pct(h['below_ssgi_share'])} | "
                 f"{(w['file'] + ' ' + str(w['frame']) + ': ' + format(w['db'], '+.2f')) if w else '-'} | "
                 f"{r['scenes_below_direct']} | {r['scenes_below_ssgi']} |")
    hours = [g for g in s["methods"][names[0]]["groups"] if g != "all"]
    L += ["", "Per time of day: mean final PSNR dB.", "", "| hours | " + " | ".join(names) + " |",
          "| --- | " + "--- | " * len(names)]
    for g in hours:
        L.append(f"| {g} | " + " | ".join(fmt(s["methods"][m]["groups"][g]["psnr"]) for m in names) + " |")
    L += ["", "Per scene: mean final PSNR dB (SSIM); the adaptation's frames and steps; the bakes.", "",
          "| scene | " + " | ".join(names) + " | adapt: train frames, steps (chosen) | bakes: samples fixed / each "
          "of the blend, seconds |", "| --- | " + "--- | " * len(names) + "--- | --- |"]
    for stem, sc in s["scenes"].items():
        cells = [s["methods"][m]["files"].get(stem) for m in names]
        if not all(cells):
            continue
        a, b = sc["adapt"], sc["bakes"]
        L.append(f"| {stem} | " + " | ".join(f"{fmt(c['psnr'])} ({fmt(c['ssim'], '.3f')})" for c in cells)
                 + f" | {a['frames']['train']}, {a['steps']} ({a['chosen_step']}) | {b['fixed']['samples']} / "
                   f"{b['blend']['samples_each']}, {b['fixed']['seconds']:.1f} / {b['blend']['seconds']:.1f} |")
    seqs = {stem: sc["sun_sequence"] for stem, sc in s["scenes"].items() if sc.get("sun_sequence")}
    if seqs:
        q0 = next(iter(seqs.values()))
        L += ["", f"Flicker under a moving sun: a still camera (path frame {q0['frame']}), {len(q0['hours'])} frames "
              f"from {q0['hours'][0]:g} h in steps of {st['sun_sequence']['step']:g} h; warping error of the final "
              "images as a ratio to the reference's own (1 = as stable as the path-traced truth).", "",
              "| scene | reference warping error | " + " | ".join(names) + " |",
              "| --- | --- | " + "--- | " * len(names)]
        key = lambda m: "direct" if m == "direct_only" else m  # noqa: E731
        for stem, q in seqs.items():
            L.append(f"| {stem} | {q['reference']:.4f} | " + " | ".join(fmt(q["ratio"].get(key(m))) for m in names)
                     + " |")
        mean = {m: np.mean([q["ratio"][key(m)] for q in seqs.values() if q["ratio"].get(key(m)) is not None])
                for m in names}
        L.append(f"| mean ({len(seqs)} scenes) | | " + " | ".join(fmt(mean[m]) for m in names) + " |")
    return "\n".join(L) + "\n"


def strip(args, ev, ssgi, out_png):
    """direct | ssgi | bake_fixed | bake_blend | adapted_sun | reference: path frame --frames' middle at the
    --eval-times hour farthest from the scene's own time, per scene."""
    rows = []
    k = args.frames[len(args.frames) // 2]
    for stem in args.files:
        spec = str(args.vox_dir / f"{stem}.vox")
        scene = ngi.Scene(spec)
        h = max(args.eval_times, key=lambda x: abs(x - scene.default_time))
        d = args.frames_dir / stem / f"t{h:05.2f}" / f"{k:04d}"
        if not d.is_dir():
            continue
        fr = ngi.read_frame(str(d))
        if float(np.max(fr.reference)) <= 0.0:
            continue
        renderer = ngi.Renderer(ev.device, scene)
        cached = bakes(renderer, scene.default_time, args.train_times, 0, args.probe_share, args.work / stem, True)
        if cached is None:
            continue
        fixed, blend, _ = cached
        rungs = {"ssgi_surround": ssgi,
                 "adapted_sun": {"name": f"adapted_sun_{stem}", "kind": "rung", "n": 64, "bn_mode": None,
                                 "path": str(args.work / stem / "adapted_sun.safetensors")}}
        position = le.read_json(d / "render.json")["camera"]["position"]
        lms = lightmaps(ev, rungs, ngi.VoxelProbes(renderer), fr, position, h, fixed, blend, args.train_times)
        ref = scoring.Reference(ev.device, ev.pipe(64), fr)
        cols = ["direct", "ssgi_surround", "bake_fixed", "bake_blend", "adapted_sun"]
        rows.append((f"{stem}/{k:04d} at {h:g} h", [ref.score(lms[c])["display"] for c in cols] + [ref.final]))
    if rows:
        gi_eval.draw_strip(rows, ["direct light", "SSGI", "bake (own time)", "bakes blended", "adapted over the day",
                                  "reference"], out_png)


if __name__ == "__main__":
    sys.exit(main())

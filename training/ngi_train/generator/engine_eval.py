#!/usr/bin/python3
"""Issue 45: every GI result judged with the inputs an engine has.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.engine_eval \\
        --vox-dir ../shared/scenes/vox --work runs/engine --out docs/results [--frames 10,50,90] \\
        [--rungs direct_only,ssgi_surround_n64,ssgi_front_n64,gi_surround_n64_ngf16,gi_single_view_n64_ngf16]

An engine's direct light is converged (a shadow-mapped sun, a prefiltered sky), so every frame is rendered with a
noise-free direct-light feature: `ngi render --scene F.vox --frame K --path-frames 100 --face 64 --spp REF_SPP
--feature-spp FEATURE_SPP` (defaults 1024 and 1024), path frames --frames of every .vox file of --vox-dir (read
from there, never copied). Each rung runs through ngi's pipeline (ngi.plan's Evaluator: ngi.Model +
Pipeline.run; "direct_only" is the frame's direct light alone) and is scored with ngi.scoring as `ngi lightmap`
scores it (final image tone-mapped, data range 1; linear lightmap). A rung is a name of the zoo manifest (--zoo),
a shipped model's name (ngi.resolve_model) or a .safetensors file; one that does not resolve is skipped with a note.
Frames whose reference is all zero are counted and left out (as gi_eval does).

Reported per rung and per scene group (gi_eval.VOX_GROUPS, and all): mean final PSNR / SSIM and lightmap PSNR; the
honesty numbers over the frames (honesty()): the share of frames more than 1 dB below direct light (final PSNR), the
share more than 1 dB below the ssgi_surround rung (when it runs), the count more than 0.5 dB below direct light, the
worst frame against direct light; per .vox file the mean PSNR; the in-process pipeline time per frame (median of
--repeats runs after a warm-up on one frame); the render timings of every frame (its render.json).

Results: WORK/engine_eval.json (every per-frame score, render timing and pipeline time, cached by model digest, so a
rerun or an interrupted run only does what is missing), OUT/engine.json (summary), OUT/engine_tables.md and
OUT/engine_strip.png (direct | ssgi_surround | best network | reference for one frame of one file per group).
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
import ngi.zoo as zoo_mod

from ngi_train import ngi_paths
from ngi_train.generator import gi_eval, ladder_eval as le

PATH_FRAMES = 100
DEFAULT_RUNGS = "direct_only,ssgi_surround_n64,ssgi_front_n64,gi_surround_n64_ngf16,gi_single_view_n64_ngf16"
BELOW_DB, SSGI_BELOW_DB = 1.0, 0.5  # honesty thresholds (module doc)
RENDER_MS = ("features_ms", "reference_ms")  # of render.json's timing
log = le.log


# --------------------------------------------------------------------------
# Rungs
# --------------------------------------------------------------------------

def resolve_rungs(names, zoo_path):
    """Rungs as ngi.plan's Evaluator runs them ({name, kind, path, n, bn_mode} + digest), in the order given."""
    try:
        zoo = {r["name"]: r for r in zoo_mod.load(zoo_path)["rungs"]}
    except (OSError, zoo_mod.ZooError) as e:
        log(f"engine_eval: zoo not used: {e}")
        zoo = {}
    out = []
    for name in names:
        if name in zoo:
            r = dict(zoo[name])
        elif name == "direct_only":
            r = {"name": name, "kind": "direct", "path": None, "n": 64, "bn_mode": None}
        else:
            try:
                path = Path(ngi.resolve_model(name))
            except ngi.Error:
                path = None
            if path is None or not path.is_file():
                log(f"engine_eval: rung {name!r} is neither in {zoo_path} nor a model file: skipped")
                continue
            kind = "ssgi" if model_file.read_config(str(path)).get("family") == "ssgi" else "rung"
            r = {"name": Path(name).stem if name.endswith(".safetensors") else name, "kind": kind, "path": str(path),
                 "n": 64, "bn_mode": None}
        if any(o["name"] == r["name"] for o in out):
            log(f"engine_eval: rung {name!r}: a rung named {r['name']!r} is already measured: skipped")
            continue
        if r["n"] != 64:
            log(f"engine_eval: rung {name!r} runs at N = {r['n']}, the frames are rendered at 64: skipped")
            continue
        r.setdefault("bn_mode", None)  # an ssgi rung of the zoo has no batch norm and no bn_mode
        r["digest"] = "direct" if r["path"] is None else f"{le.digest(r['path'])[:16]}-{r['bn_mode']}"
        out.append(r)
    return out


def ssgi_baseline(rungs):
    """The ssgi_surround rung (the honesty baseline beside direct light), if it runs."""
    return next((r["name"] for r in rungs if r["kind"] == "ssgi" and "surround" in r["name"]), None)


# --------------------------------------------------------------------------
# Per-frame scores (cached)
# --------------------------------------------------------------------------

def score_frames(args, ev, rungs, work):
    """{frame name: cache entry} of every frame: its render timing, unlit flag and per-rung scores (and its dir)."""
    cache_path = work / "engine_eval.json"
    cache = le.read_json(cache_path, {})
    label = f"ref{args.ref_spp}_feat{args.feature_spp}"
    entries = cache.setdefault("frames", {}).setdefault(label, {})
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    jobs = [(scene, k, f"{stem}/{k:04d}", work / "frames" / label / stem / f"{k:04d}")
            for scene, stem in scene_list(args) for k in args.frames]
    for f, k, name, d in tqdm.tqdm(jobs, desc=f"frames ({len(rungs)} rungs)", unit="frame",
                                   **ngi_paths.progress_options()):
        e = entries.setdefault(name, {"scores": {}})
        todo = [r for r in rungs if e["scores"].get(r["name"], {}).get("digest") != r["digest"]]
        if "render" in e and (e["unlit"] or not todo):
            continue
        gi_eval.render_vox_frame(ngi_bin, f, k, PATH_FRAMES, args.ref_spp, args.feature_spp, d, args.render_device)
        e["render"] = le.read_json(d / "render.json")["timing"]
        fr = ngi.read_frame(str(d))
        e["unlit"] = float(np.max(fr.reference)) <= 0.0
        if not e["unlit"]:
            ref = scoring.Reference(ev.device, ev.pipe(64), fr)
            for r in todo:
                s = ref.score(ev.lightmap(r, {64: fr}))
                e["scores"][r["name"]] = {"digest": r["digest"], "final": s["final"], "lightmap": s["lightmap"]}
        le.write_json(cache_path, cache)
    return {name: dict(entries[name], dir=d) for _, _, name, d in jobs}


def scene_list(args):
    """(the `ngi render --scene` argument, the folder name) of every scene: the .vox files of --vox-dir, or the
    procedural specs of --scenes (e.g. room:seed=301 -> room_seed301; this project's own scenes, on which settings
    may be chosen: the .vox files are for evaluation only)."""
    if args.scenes:
        return [(spec, spec.replace(":", "_").replace("=", "")) for spec in args.scenes]
    files = sorted(Path(args.vox_dir).glob("*.vox"))
    return [(f, f.stem) for f in files if not args.files or f.stem in args.files]


def rows_of(frames, name):
    """The rung's per-frame rows ({frame, file, group, final, lightmap}) over the lit frames."""
    return [{"frame": fn, "file": fn.rsplit("/", 1)[0], "group": gi_eval.vox_group(fn.rsplit("/", 1)[0]),
             **e["scores"][name]} for fn, e in frames.items() if not e["unlit"]]


def pipeline_times(args, ev, rungs, frames, work):
    """Per rung: in-process pipeline ms per frame (Evaluator.time_ms on the first lit frame), cached per device."""
    cache_path = work / "engine_eval.json"
    cache = le.read_json(cache_path, {})
    lit = next((fn for fn, e in frames.items() if not e["unlit"]), None)
    if lit is None:
        return {}
    per = cache.setdefault("pipeline_ms", {}).setdefault(ev.device.info["name"], {})
    fr = None
    for r in rungs:
        if per.get(r["name"], {}).get("digest") != r["digest"]:
            fr = fr or ngi.read_frame(str(frames[lit]["dir"]))
            per[r["name"]] = {"digest": r["digest"], "frame": lit, "repeats": args.repeats,
                              "ms": ev.time_ms(r, {64: fr}, args.repeats)}
            le.write_json(cache_path, cache)
    return {r["name"]: per[r["name"]] for r in rungs}


# --------------------------------------------------------------------------
# Aggregation (pure)
# --------------------------------------------------------------------------

def margins(rows, base_rows):
    """{frame: final PSNR of rows minus base_rows' on the same frame} (both must hold the same frames)."""
    base = {r["frame"]: r["final"]["psnr"] for r in base_rows}
    if set(base) != {r["frame"] for r in rows}:
        raise ValueError("honesty: the rung and its baseline were scored on different frames")
    return {r["frame"]: r["final"]["psnr"] - base[r["frame"]] for r in rows}


def honesty(rows, direct_rows, ssgi_rows=None):
    """Per-frame honesty of a rung: shares of frames more than BELOW_DB below direct light and below the ssgi
    baseline (None without it), frames more than SSGI_BELOW_DB below direct light, the worst frame against direct
    light. A margin that is not a number (both PSNRs infinite) counts as not below."""
    vs_direct = margins(rows, direct_rows)
    n = len(vs_direct)
    below = lambda m, db: sum(d < -db for d in m.values())  # noqa: E731
    finite = {k: d for k, d in vs_direct.items() if np.isfinite(d)}
    worst = min(finite, key=finite.get) if finite else None
    return {"frames": n,
            "below_direct_share": below(vs_direct, BELOW_DB) / n if n else None,
            "below_ssgi_share": (below(margins(rows, ssgi_rows), BELOW_DB) / n if n else None)
            if ssgi_rows is not None else None,
            "below_direct_half_db_frames": below(vs_direct, SSGI_BELOW_DB),
            "worst_vs_direct": None if worst is None else
            {"file": worst.rsplit("/", 1)[0], "frame": int(worst.rsplit("/", 1)[1]), "db": finite[worst]}}


def summarize(rows_by_rung, ssgi):
    """Per rung: means per scene group and per file, honesty per scene group (all = every frame)."""
    out = {}
    for name, rows in rows_by_rung.items():
        groups = {"all": rows}
        for r in rows:
            groups.setdefault(r["group"], []).append(r)
        pick = lambda base, g: [r for r in rows_by_rung[base] if g == "all" or r["group"] == g]  # noqa: E731
        out[name] = {"groups": gi_eval.by_group(rows, lambda r: r["group"]),
                     "files": gi_eval.by_group(rows, lambda r: r["file"]),
                     "honesty": {g: honesty(rs, pick("direct_only", g), pick(ssgi, g) if ssgi else None)
                                 for g, rs in groups.items()}}
    return out


# --------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------

def strip(ev, rungs, frames, summary, out_png, middle):
    """direct | ssgi_surround | best network | reference: frame `middle` (else the first lit one) of the first file
    of each scene group (this project's own scenes are the group "other")."""
    cols = [c for c in ("direct_only", summary["ssgi_baseline"], summary["best_network"]) if c]
    by_name = {r["name"]: r for r in rungs}
    rows = []
    for group in list(gi_eval.VOX_GROUPS) + ["other"]:
        lit = [fn for fn, e in frames.items() if not e["unlit"] and gi_eval.vox_group(fn.rsplit("/", 1)[0]) == group]
        if not lit:
            continue
        first = [fn for fn in lit if fn.rsplit("/", 1)[0] == lit[0].rsplit("/", 1)[0]]
        fn = next((x for x in first if x.endswith(f"/{middle:04d}")), first[0])
        fr = ngi.read_frame(str(frames[fn]["dir"]))
        ref = scoring.Reference(ev.device, ev.pipe(64), fr)
        rows.append((fn, [ref.score(ev.lightmap(by_name[c], {64: fr}))["display"] for c in cols] + [ref.final]))
    if rows:
        gi_eval.draw_strip(rows, [c.replace("direct_only", "direct light") for c in cols] + ["reference"], out_png)


def stats(values):
    values = [v for v in values if v is not None]
    return {"mean": float(np.mean(values)), "median": float(np.median(values)), "total": float(np.sum(values))} \
        if values else None


def header(cols):
    return ["| " + " | ".join(cols) + " |", "|" + " --- |" * len(cols)]


def tables(s):
    fmt = gi_eval.fmt
    st, fr = s["settings"], s["frames"]
    groups = ["all"] + list(gi_eval.VOX_GROUPS)
    L = ["# Issue 45: GI with the inputs an engine has", "",
         f"{fr['lit']} lit frames (path frames {st['frames']} of {fr['files']} .vox files, {len(fr['unlit'])} unlit "
         f"left out), N = 64, direct-light feature {st['feature_spp']} spp (1024: converged, as an engine's), "
         f"references {st['ref_spp']} spp. Final images (ACES, sRGB) against path-traced references. Written by "
         "training/ngi_train/generator/engine_eval.py.", "",
         "## Mean final PSNR (dB) / SSIM / lightmap PSNR per scene group", "",
         *header(["rung", "pipeline ms"] + groups)]
    for name, r in s["rungs"].items():
        cells = [f"{fmt(g['psnr'])} / {fmt(g['ssim'], '.3f')} / {fmt(g['lightmap_psnr'])}" if g else "-"
                 for g in (r["groups"].get(k) for k in groups)]
        L.append(f"| {name} | {fmt((r['pipeline'] or {}).get('ms'), '.1f')} | " + " | ".join(cells) + " |")
    L += ["", "## Honesty per frame (all frames; final PSNR)", "",
          *header(["rung", "frames", f"> {BELOW_DB:g} dB below direct",
                   f"> {BELOW_DB:g} dB below {s['ssgi_baseline'] or 'ssgi_surround (absent)'}",
                   f"> {SSGI_BELOW_DB:g} dB below direct (frames)", "worst vs direct"])]
    pct = lambda x: "-" if x is None else f"{100 * x:.0f}%"  # noqa: E731
    for name, r in s["rungs"].items():
        h = r["honesty"].get("all")
        if h:
            w = h["worst_vs_direct"]
            worst = f"{w['file']} {w['frame']}: {w['db']:+.2f} dB" if w else "-"
            L.append(f"| {name} | {h['frames']} | {pct(h['below_direct_share'])} | {pct(h['below_ssgi_share'])} | "
                     f"{h['below_direct_half_db_frames']} | {worst} |")
    names = list(s["rungs"])
    order = list(gi_eval.VOX_GROUPS) + ["other"]
    files = sorted({f for r in s["rungs"].values() for f in r["files"] if f != "all"},
                   key=lambda f: (order.index(gi_eval.vox_group(f)), f))
    L += ["", "## Mean final PSNR (dB) per file", "", *header(["file", "group"] + names)]
    for f in files:
        L.append(f"| {f} | {gi_eval.vox_group(f)} | "
                 + " | ".join(fmt((s["rungs"][n]["files"].get(f) or {}).get("psnr")) for n in names) + " |")
    L += ["", "## Render time per frame (ms)", "", *header(["", "mean", "median"])]
    for k in RENDER_MS:
        t = s["render_timing"][k]
        L.append(f"| {k} | {fmt((t or {}).get('mean'), '.0f')} | {fmt((t or {}).get('median'), '.0f')} |")
    return "\n".join(L) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--vox-dir", type=Path, help="the folder of .vox files (read only)")
    where.add_argument("--scenes", default="", help="comma-separated procedural scene specs instead (room:seed=301,...)")
    ap.add_argument("--work", type=Path, required=True, help="rendered frames and the per-frame cache")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--frames", default="10,50,90", help="path frames (of 100) of every file")
    ap.add_argument("--files", default="", help="comma-separated .vox stems (default: every file)")
    ap.add_argument("--rungs", default=DEFAULT_RUNGS)
    ap.add_argument("--feature-spp", type=int, default=1024, help="direct-light feature spp (converged)")
    ap.add_argument("--ref-spp", type=int, default=1024, help="reference spp")
    ap.add_argument("--zoo", type=Path, default=le.REPO / "models" / "zoo.json")
    ap.add_argument("--device", default="pocl", help="the device the rungs run on")
    ap.add_argument("--render-device", default="pocl")
    ap.add_argument("--repeats", type=int, default=5, help="timed pipeline runs per rung (after a warm-up)")
    ap.add_argument("--ngi", default=None)
    args = ap.parse_args(argv)
    args.frames = [int(k) for k in args.frames.split(",")]
    args.files = set(args.files.split(",")) - {""}
    args.scenes = [x for x in args.scenes.split(",") if x]
    args.out.mkdir(parents=True, exist_ok=True)
    rungs = resolve_rungs([n for n in args.rungs.split(",") if n], args.zoo)
    if not any(r["name"] == "direct_only" for r in rungs):
        rungs.insert(0, resolve_rungs(["direct_only"], args.zoo)[0])  # the honesty baseline always runs
    ev = plan.Evaluator(ngi.Device(args.device), None)
    frames = score_frames(args, ev, rungs, args.work)
    speed = pipeline_times(args, ev, rungs, frames, args.work)
    ssgi = ssgi_baseline(rungs)
    per = summarize({r["name"]: rows_of(frames, r["name"]) for r in rungs}, ssgi)
    nets = [r["name"] for r in rungs if r["kind"] not in ("direct", "ssgi")]
    psnr = lambda n: gi_eval.psnr_key(per[n]["groups"]["all"])  # noqa: E731
    summary = {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
               "settings": {"vox_dir": args.vox_dir.name if args.vox_dir else None, "scenes": args.scenes, "frames": args.frames, "path_frames": PATH_FRAMES,
                            "face": 64, "feature_spp": args.feature_spp, "ref_spp": args.ref_spp,
                            "device": ev.device.info, "render_device": args.render_device},
               "frames": {"files": len({fn.rsplit("/", 1)[0] for fn in frames}),
                          "lit": sum(not e["unlit"] for e in frames.values()),
                          "unlit": sorted(fn for fn, e in frames.items() if e["unlit"])},
               "render_timing": {**{k: stats([e["render"].get(k) for e in frames.values()]) for k in RENDER_MS},
                                 "per_frame": {fn: {k: e["render"].get(k) for k in RENDER_MS}
                                               for fn, e in frames.items()}},
               "ssgi_baseline": ssgi, "best_network": max(nets, key=psnr) if nets else None,
               "rungs": {r["name"]: {"kind": r["kind"], "file": le.rel(r["path"]) if r["path"] else None,
                                     "bn_mode": r["bn_mode"], "pipeline": speed.get(r["name"]), **per[r["name"]]}
                         for r in rungs}}
    le.write_json(args.out / "engine.json", summary)
    (args.out / "engine_tables.md").write_text(tables(summary))
    strip(ev, rungs, frames, summary, args.out / "engine_strip.png", args.frames[len(args.frames) // 2])
    log(f"engine_eval: wrote {args.out / 'engine.json'}, {args.out / 'engine_tables.md'} and "
        f"{args.out / 'engine_strip.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

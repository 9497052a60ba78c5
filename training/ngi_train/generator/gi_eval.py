#!/usr/bin/python3
"""Issue 25's evaluation: is a generator worth running, i.e. better than direct light alone, on every scene group?

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.gi_eval \\
        --work runs/gi --data data/gi_n64 \\
        --seq data/seq_n64 --vox-dir ../shared/scenes/vox --out docs/results [--zoo models/zoo.json]

Variants: direct light alone (the free baseline), every rung of the GI ladder (training/configs/gi.json: output
mode indirect; shipped and unshipped, as exported), the N = 64 rungs of the thesis-mode ladder
(training/configs/ladder.json, as shipped) and the two generators shipped before it. Each is run by ngi's own
pipeline (Python bindings) and scored with ngi.scoring against path-traced references, as ladder_eval.py does:

1. held-out: every frame of the dataset's test split (scenes in no training set), reported per scene group:
   all, indoor (rooms, caves, backlit, bleed, Cornell boxes), outdoor (street, sculpture), and per family;
2. public .vox scenes (--vox-dir, read from there, never copied): `ngi render --scene F.vox` along the default
   camera path at N = 64 with 256-spp references, --vox-frames frames per file; frames whose reference is all
   zero (nothing lit in view) are counted and left out; groups as the folder's README lists them; compare strips
   (direct | network | reference) per file;
3. moving camera (the ladder's room:seed=204 sequence, path frames 39-81, at 11.02 h; --seq DIR to use a rendered
   configs/sequences_clean_n64.json, else only those 43 frames are rendered into WORK/seq, at its sample counts, with
   the cameras of a 1-spp `ngi dataset` run of the same sequence): MABD and warping error beside the reference's
   (ngi.temporal);
4. the per-frame guard: for each indirect rung, the share of the final image's luminance its indirect light adds
   (ngi.indirect_share); frames above a threshold fall back to direct light. The shipped threshold is the one with
   the best mean PSNR on all held-out frames, then applied to the .vox frames; its held-out effect is estimated
   leaving one scene out (each scene guarded with the threshold chosen on the others);
5. inputs an engine has (issue 25 item 2): NOISE_FRAMES frames of every held-out scene rendered again with the
   same camera, time and seed but the direct-light feature at other sample counts (NOISE_SPP: a noisier host, and a
   converged one like a shadow-mapped sun and a prefiltered sky), scored against the dataset's reference;
6. learning curves: every kept checkpoint of every GI rung (WORK/runs/<rung>/checkpoints/step_*.pt) scored in PyTorch
   on CURVE_FRAMES held-out frames (evaluate.heldout_scores: L1 of the encoded composed lightmap, linear MSE), beside
   the training loss (log.jsonl, mean over windows of 500 steps): OUT/gi_curves.png;
7. speed of the shipped GI rungs on each --devices device (ladder_eval's speed stage: ngi_bench generator and the
   whole ngi lightmap command, medians).

Results: WORK/gi_eval.json (everything, cached per stage and model digest, so a rerun or an interrupted run only
measures what is missing), OUT/gi.json (summary), OUT/gi_tables.md, OUT/gi_vox_strip.png; with --zoo the shipped
GI rungs are added to (or replaced in) the zoo manifest.
"""

import argparse
import datetime
import json
import shutil
import sys
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.scoring as scoring
import ngi.temporal as temporal
import ngi.zoo as zoo_mod

from ngi_train import ngi_paths
from ngi_train.generator import ladder as ladder_mod, ladder_eval as le

REPO = ngi_paths.REPO
GI_LADDER = REPO / "training" / "configs" / "gi.json"
INDOOR = ("room", "cave", "backlit", "bleed", "cornell", "cornell_pink")
OUTDOOR = ("street", "sculpture")
VOX_GROUPS = {"monuments": ("monu0", "monu4", "monu5", "monu6-without-water", "monu7", "monu8-without-water", "monu9"),
              "procedural": ("nature", "menger", "maze", "snow"), "scans": ("dragon", "teapot"),
              "characters": ("chr_cat", "chr_fox", "chr_man", "T-Rex", "horse")}
NOISE_FRAMES = (0, 10, 20)  # frame indices of every held-out scene re-rendered for the direct-light noise stage
NOISE_SPP = (8, 1024)  # the dataset's direct feature has 64 spp
CURVE_FRAMES = 48
GUARD_THRESHOLDS = [0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.01]
LUMA = scoring.LUMA


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def variants(work):
    """direct, the GI rungs as exported, the thesis-mode ladder's N = 64 shipped rungs, the two legacy models."""
    out = []
    gi = ladder_mod.load_ladder(GI_LADDER)
    for v in le.variants(gi, work):
        if v["kind"] in ("direct", "rung"):
            v["output_mode"] = "indirect" if v["kind"] == "rung" else "none"
            out.append(v)
    thesis = ladder_mod.load_ladder(ladder_mod.LADDER)
    for v in le.variants(thesis, work / "thesis_unused"):
        if v["kind"] in ("rung", "legacy") and v["n"] == 64 and v.get("shipped"):
            v["output_mode"] = "lightmap"
            out.append(v)
    return out


def group_of(fam):
    return "indoor" if fam in INDOOR else "outdoor" if fam in OUTDOOR else "other"


def vox_group(stem):
    return next((g for g, names in VOX_GROUPS.items() if stem in names), "other")


# --------------------------------------------------------------------------
# Public .vox frames
# --------------------------------------------------------------------------

def render_vox(args, work):
    """{stem: [frame dirs]} of every .vox file: --vox-frames frames spread over the default camera path."""
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    out = {}
    files = sorted(Path(args.vox_dir).glob("*.vox"))
    jobs = [(f, k) for f in files for k in range(args.vox_frames)]
    for f, k in tqdm.tqdm(jobs, desc="render .vox frames", unit="frame", **ngi_paths.progress_options()):
        frame = k * args.vox_path_frames // args.vox_frames
        d = work / "vox" / f.stem / f"{frame:04d}"
        out.setdefault(f.stem, []).append(d)
        render_vox_frame(ngi_bin, f, frame, args.vox_path_frames, args.vox_spp, 64, d, args.render_device)
    return out


def render_vox_frame(ngi_bin, vox, frame, path_frames, spp, feature_spp, out, device, hours=None):
    """`ngi render` of frame `frame` of a .vox file's default camera path at N = 64 (at time of day `hours`; None:
    the scene's) into the frame folder `out` (render.json in it), unless it is there; written beside it and renamed,
    so an interrupted render is redone."""
    if (out / "camera.json").is_file():
        return
    tmp = out.with_name(out.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.parent.mkdir(parents=True, exist_ok=True)
    ngi_paths.run([ngi_bin, "render", "--scene", vox, "--frame", frame, "--path-frames", path_frames, "--face", 64,
                   "--spp", spp, "--feature-spp", feature_spp, "--out", tmp, "--device", device]
                  + ([] if hours is None else ["--time", f"{hours:g}"]))
    tmp.rename(out)


def score_frames(runner, vs, frames, label):
    """[{frame, ...scores}] per variant over (name, ngi.Frame) pairs; frames with an all-zero reference skipped."""
    rows = {v["name"]: [] for v in vs}
    skipped = []
    for name, fr in tqdm.tqdm(frames, desc=f"{label} ({len(vs)} variants)", unit="frame",
                              **ngi_paths.progress_options()):
        if float(np.max(fr.reference)) <= 0.0:
            skipped.append(name)
            continue
        ref = scoring.Reference(runner.device, runner.pipe(64), fr)
        direct = fr.feature("direct")[0]
        for v in vs:
            lm, _ = runner.lightmap(v, {64: fr})
            s = ref.score(lm)
            rows[v["name"]].append({"frame": name, "final": s["final"], "lightmap": s["lightmap"],
                                    "indirect_share": indirect_share(fr, lm, direct)})
    return rows, skipped


def indirect_share(frame, lightmap, direct=None):
    """The guard's signal: the share of the final image's luminance the lightmap adds beyond direct light
    (ngi.indirect_share, docs/CONVENTIONS.md section 17)."""
    return float(ngi.indirect_share(frame, np.ascontiguousarray(lightmap, np.float32)))


def heldout_rows(args, runner, vs, work):
    """Per variant, per held-out frame: scores, family and the guard's signal (cached by model digest)."""
    cache_path = work / "gi_heldout.json"
    cache = le.read_json(cache_path, {})
    frames = le.test_frames(args.data)
    if args.max_frames:
        frames = frames[::max(1, len(frames) // args.max_frames)]
    key = data_digest(frames)
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]
            or cache[v["name"]].get("frames_digest") != key]
    if todo:
        pairs = ((rel, ngi.read_frame(str(args.data / rel))) for rel in frames)
        rows, _ = score_frames(runner, todo, list(pairs), "held-out")
        for v in todo:
            for r in rows[v["name"]]:
                r["family"] = le.family(r["frame"])
                r["family_scene"] = r["frame"].split("/")[1]
                r["index"] = int(Path(r["frame"]).name)
            cache[v["name"]] = {"digest": v["digest"], "frames_digest": key, "frames": rows[v["name"]]}
        le.write_json(cache_path, cache)
    return {v["name"]: cache[v["name"]]["frames"] for v in vs}


def data_digest(names):
    import hashlib
    return hashlib.sha1("\n".join(map(str, names)).encode()).hexdigest()[:16]


def vox_rows(args, runner, vs, work):
    cache_path = work / "gi_vox.json"
    cache = le.read_json(cache_path, {})
    dirs = render_vox(args, work)
    names = [f"{stem}/{d.name}" for stem, ds in dirs.items() for d in ds]
    key = data_digest(names)
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]
            or cache[v["name"]].get("frames_digest") != key]
    if todo:
        pairs = [(f"{stem}/{d.name}", ngi.read_frame(str(d))) for stem, ds in dirs.items() for d in ds]
        rows, skipped = score_frames(runner, todo, pairs, ".vox")
        for v in todo:
            for r in rows[v["name"]]:
                r["family"] = r["frame"].split("/")[0]
                r["group"] = vox_group(r["family"])
            cache[v["name"]] = {"digest": v["digest"], "frames_digest": key, "frames": rows[v["name"]],
                                "skipped": skipped}
        le.write_json(cache_path, cache)
    return {v["name"]: cache[v["name"]]["frames"] for v in vs}, cache[vs[0]["name"]]["skipped"], dirs


# --------------------------------------------------------------------------
# Summaries
# --------------------------------------------------------------------------

def finite_mean(values):
    values = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.mean(values)) if values else None


def mean_scores(rows):
    """Mean final-image PSNR / SSIM and linear-lightmap MSE / PSNR / SSIM over frames (a PSNR that is not finite,
    identical images, is left out of its mean, as ladder_eval and training/ngi_train/generator/report.py do)."""
    if not rows:
        return None
    return {"frames": len(rows), "psnr": finite_mean([r["final"]["psnr"] for r in rows]),
            "ssim": finite_mean([r["final"]["ssim"] for r in rows]),
            "lightmap_mse": finite_mean([r["lightmap"]["mse"] for r in rows]),
            "lightmap_psnr": finite_mean([r["lightmap"]["psnr"] for r in rows]),
            "lightmap_ssim": finite_mean([r["lightmap"]["ssim"] for r in rows])}


def by_group(rows, key):
    groups = {"all": rows}
    for r in rows:
        groups.setdefault(key(r), []).append(r)
    return {g: mean_scores(rs) for g, rs in groups.items()}


def guarded(rows, direct_rows, t):
    """Rows with the guard at threshold t: frames whose indirect share exceeds t take direct light's scores (matched
    by frame name: both lists must hold the same frames)."""
    direct = {d["frame"]: d for d in direct_rows}
    if set(direct) != {r["frame"] for r in rows}:
        raise RuntimeError("guard: the rung and direct light were scored on different frames")
    return [direct[r["frame"]] if r["indirect_share"] > t else r for r in rows]


def psnr_key(scores):
    return -np.inf if scores is None or scores["psnr"] is None else round(scores["psnr"], 3)


def choose_threshold(rows, direct_rows):
    """The threshold with the best mean final PSNR on these frames (ties: the larger, i.e. fewer fallbacks)."""
    table = []
    for t in GUARD_THRESHOLDS:
        m = mean_scores(guarded(rows, direct_rows, t))
        table.append({"threshold": t, "fallbacks": sum(r["indirect_share"] > t for r in rows),
                      "psnr": m["psnr"] if m else None, "ssim": m["ssim"] if m else None})
    best = max(table, key=lambda x: (psnr_key(x), x["threshold"]))
    return best["threshold"], table


def guard_stage(held, vox, vs):
    """Per indirect rung: the guard's threshold chosen on every held-out frame (what the zoo ships, then applied to
    the public .vox frames, which played no part in choosing it), and its held-out effect estimated honestly by
    leaving one scene out: each held-out scene's frames are guarded with the threshold chosen on the other scenes."""
    out = {}
    direct = held["direct_only"]
    for v in vs:
        rows = held.get(v["name"]) or []
        if v["output_mode"] != "indirect" or not rows:
            continue
        t, table = choose_threshold(rows, direct)
        loso = []
        for scene in sorted({r["family_scene"] for r in rows}):
            inside = [r for r in rows if r["family_scene"] == scene]
            others = [r for r in rows if r["family_scene"] != scene]
            names = {r["frame"] for r in others}
            t_s, _ = choose_threshold(others, [d for d in direct if d["frame"] in names])
            names_in = {r["frame"] for r in inside}
            loso += guarded(inside, [d for d in direct if d["frame"] in names_in], t_s)
        entry = {"calibration_frames": len(rows), "thresholds": table, "chosen": t,
                 "heldout_leave_one_scene_out": {"frames": len(rows), "on": mean_scores(loso),
                                                 "off": mean_scores(rows), "direct": mean_scores(direct)}}
        vr, vd = vox.get(v["name"], []), vox.get("direct_only", [])
        if vr:
            entry["vox"] = {"frames": len(vr), "fallbacks": sum(r["indirect_share"] > t for r in vr),
                            "off": mean_scores(vr), "on": mean_scores(guarded(vr, vd, t)), "direct": mean_scores(vd)}
        out[v["name"]] = entry
    return out


def direct_noise_stage(args, runner, vs, work):
    """Per variant and direct-feature spp: mean scores on the held-out frames NOISE_FRAMES re-rendered (module doc)."""
    cache_path = work / "gi_direct_noise.json"
    cache = le.read_json(cache_path, {})
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]]
    if todo:
        rows = {v["name"]: {str(spp): [] for spp in NOISE_SPP} for v in todo}
        scenes = sorted(d for d in (args.data / "test").iterdir() if (d / "scene.json").is_file())
        for scene_dir in tqdm.tqdm(scenes, desc="direct-light noise", unit="scene", **ngi_paths.progress_options()):
            info = le.read_json(scene_dir / "scene.json")
            renderer = ngi.Renderer(runner.device, ngi.Scene(info["spec"]))
            for k in (k for k in NOISE_FRAMES if k < len(info["frame_info"])):
                fi = info["frame_info"][k]
                base = ngi.read_frame(str(scene_dir / f"{k:04d}"))
                for spp in NOISE_SPP:
                    fr = renderer.render(n=base.n, feature_spp=spp, reference=False, time=fi["time"],
                                         position=fi["position"], look=fi["look"], up=fi["up"], seed=fi["seed"])
                    d = fr.to_dict()
                    d["reference"] = base.reference
                    fr = ngi.Frame.from_dict(d)
                    ref = scoring.Reference(runner.device, runner.pipe(64), fr)
                    for v in todo:
                        s = ref.score(runner.lightmap(v, {64: fr})[0])
                        rows[v["name"]][str(spp)].append({"frame": f"{scene_dir.name}/{k:04d}", "final": s["final"],
                                                          "lightmap": s["lightmap"]})
        for v in todo:
            cache[v["name"]] = {"digest": v["digest"], "spp": rows[v["name"]]}
        le.write_json(cache_path, cache)
    return {v["name"]: {spp: mean_scores(r) for spp, r in cache[v["name"]]["spp"].items()} for v in vs}


SEQ_CONFIG = REPO / "configs" / "sequences_clean_n64.json"


def render_moving_camera(args, runner, work):
    """WORK/seq: the frames of ladder_eval's MOVING_CAMERA the evaluation uses, as `ngi dataset` renders them from
    configs/sequences_clean_n64.json (same camera path, seeds and sample counts), and that dataset's scene.json
    (from a 1-spp run of the whole path at N = 2: the cameras only)."""
    seq = work / "seq"
    scene = le.MOVING_CAMERA["scene"]
    cfg = le.read_json(SEQ_CONFIG)
    if not (seq / "paths" / "test" / scene / "scene.json").is_file():
        cheap = dict(cfg, n=2, feature_spp=1, reference_spp=1, comment="cameras only")
        (seq / "paths").mkdir(parents=True, exist_ok=True)
        le.write_json(seq / "paths.json", cheap)
        ngi_paths.run([ngi_paths.find_ngi(args.ngi), "dataset", "--config", seq / "paths.json", "--out",
                       seq / "paths", "--device", args.render_device])
    info = le.read_json(seq / "paths" / "test" / scene / "scene.json")
    out = seq / "data" / "test" / scene
    out.mkdir(parents=True, exist_ok=True)
    le.write_json(out / "scene.json", info)
    (spec,) = [e["scene"] for e in cfg["test"]]
    renderer = ngi.Renderer(runner.device, ngi.Scene(spec))
    for f in tqdm.tqdm(le.MOVING_CAMERA["frames"], desc="moving-camera frames", unit="frame",
                       **ngi_paths.progress_options()):
        d = out / f"{f:04d}"
        if (d / "camera.json").is_file():
            continue
        fi = info["frame_info"][f]
        fr = renderer.render(n=cfg["n"], spp=cfg["reference_spp"], feature_spp=cfg["feature_spp"],
                             bounces=cfg["max_bounces"], time=fi["time"], position=fi["position"], look=fi["look"],
                             up=fi["up"], seed=fi["seed"])
        tmp = d.with_name(d.name + ".tmp")
        ngi.write_frame(str(tmp), fr)
        tmp.rename(d)
    return seq / "data"


def temporal_stage(args, runner, vs, work):
    """Moving camera (ladder_eval's MOVING_CAMERA sequence): quality, MABD and warping error per variant."""
    cache_path = work / "gi_temporal.json"
    cache = le.read_json(cache_path, {})
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]]
    if todo:
        scene = le.MOVING_CAMERA["scene"]
        seq_dir = args.seq or render_moving_camera(args, runner, work)
        info = le.read_json(seq_dir / "test" / scene / "scene.json")
        cams, frames = [], []
        for f in le.MOVING_CAMERA["frames"]:
            fi = info["frame_info"][f]
            cams.append((fi["position"], fi["look"], fi["up"]))
            frames.append(ngi.read_frame(str(seq_dir / "test" / scene / f"{f:04d}")))
        refs = [scoring.Reference(runner.device, runner.pipe(64), f) for f in frames]
        masks = temporal.warp_masks([f.feature("depth")[0][0] for f in frames], cams)
        ref_disp = [r.final for r in refs]
        mabd_ref, warp_ref = temporal.mabd(ref_disp), temporal.warp_error(ref_disp, masks)[0]
        for v in tqdm.tqdm(todo, desc="moving camera", unit="variant", **ngi_paths.progress_options()):
            shown, per = [], []
            for fr, ref in zip(frames, refs):
                s = ref.score(runner.lightmap(v, {64: fr})[0])
                shown.append(s["display"])
                per.append(s["final"])
            warp, valid = temporal.warp_error(shown, masks)
            cache[v["name"]] = {"digest": v["digest"], "frames": len(frames),
                                "psnr": float(np.mean([p["psnr"] for p in per])),
                                "ssim": float(np.mean([p["ssim"] for p in per])),
                                "mabd": temporal.mabd(shown), "mabd_reference": mabd_ref, "warp_error": warp,
                                "warp_error_reference": warp_ref, "warp_valid_share": valid}
        le.write_json(cache_path, cache)
    return {v["name"]: {k: x for k, x in cache[v["name"]].items() if k != "digest"} for v in vs}


def curves_stage(args, work, out_png):
    """Held-out scores of every kept checkpoint (module doc, stage 6) and the training loss, per GI rung."""
    from ngi_train import checkpoint
    from ngi_train.generator import data
    from ngi_train.generator import evaluate
    cache_path = work / "gi_curves.json"
    cache = le.read_json(cache_path, {})
    gi = ladder_mod.load_ladder(GI_LADDER)
    sets = {}
    for rung in gi["rungs"]:
        run = work / "runs" / rung["name"]
        ckpts = sorted((run / "checkpoints").glob("step_*.pt"))
        entry = cache.setdefault(rung["name"], {"heldout": {}})
        for ck in ckpts:
            stamp = f"{ck.name}@{ck.stat().st_mtime_ns}"
            if stamp in entry["heldout"]:
                continue
            state = checkpoint.load(ck)
            cfg = state["config"]
            if cfg["layout"] not in sets:
                sets[cfg["layout"]] = data.load_split(args.data, "test", cfg["layout"],
                                                      data.default_cache_dir(args.data, cfg["layout"]),
                                                      max_frames=CURVE_FRAMES)[0]
            s = evaluate.heldout_scores(state["model"]["G"], cfg, sets[cfg["layout"]], state["n"], "per_image")
            entry["heldout"] = {k: x for k, x in entry["heldout"].items() if not k.startswith(ck.name + "@")}
            entry["heldout"][stamp] = {"step": state["step"], **s}
            le.write_json(cache_path, cache)
        log_path = run / "log.jsonl"
        if log_path.is_file():
            lines = [json.loads(x) for x in log_path.read_text().splitlines() if x.strip()]
            lines = [x for x in lines if "G_L1" in x]
            entry["train"] = [{"step": lines[i + 499]["step"],
                               "G_L1": float(np.mean([x["G_L1"] for x in lines[i:i + 500]])),
                               "G_final": float(np.mean([x.get("G_final", 0.0) for x in lines[i:i + 500]]))}
                              for i in range(0, len(lines) - 499, 500)]
    le.write_json(cache_path, cache)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
    for name, e in cache.items():
        if e.get("train"):
            axes[0].plot([x["step"] for x in e["train"]], [x["G_L1"] for x in e["train"]], label=name)
        pts = sorted(e["heldout"].values(), key=lambda x: x["step"])
        if pts:
            axes[1].plot([x["step"] for x in pts], [x["l1"] for x in pts], marker="o", label=name)
    axes[0].set_title("training L1 (encoded lightmap), mean of 500 steps", fontsize=8)
    axes[1].set_title(f"held-out L1 ({CURVE_FRAMES} test frames)", fontsize=8)
    for ax in axes:
        ax.set_xlabel("step")
        ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
    return cache


# --------------------------------------------------------------------------
# Figures and tables
# --------------------------------------------------------------------------

def vox_strip(runner, vs, dirs, best, out_png):
    """One row per .vox file (its first frame that sees lit geometry): direct | best rung | reference."""
    v_best = next(v for v in vs if v["name"] == best)
    rows = []
    for stem, ds in sorted(dirs.items()):
        for d in ds:
            fr = ngi.read_frame(str(d))
            if float(np.max(fr.reference)) > 0:
                ref = scoring.Reference(runner.device, runner.pipe(64), fr)
                rows.append((stem, [ref.score(fr.feature("direct")[0])["display"],
                                    ref.score(runner.lightmap(v_best, {64: fr})[0])["display"], ref.final]))
                break
    draw_strip(rows, ("direct light", best, "reference"), out_png)


def draw_strip(rows, titles, out_png):
    """A grid of tone-mapped [3, H, W] images: rows [(label, [image per column])], one title per column."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(rows), len(titles), figsize=(2 * len(titles), 2 * len(rows)), squeeze=False)
    for i, (label, imgs) in enumerate(rows):
        for j, img in enumerate(imgs):
            axes[i][j].imshow(np.clip(np.transpose(img, (1, 2, 0)), 0, 1), interpolation="nearest")
            axes[i][j].set_xticks([])
            axes[i][j].set_yticks([])
            if i == 0:
                axes[i][j].set_title(titles[j], fontsize=7)
        axes[i][0].set_ylabel(label, fontsize=7)
    fig.tight_layout()
    fig.savefig(out_png, dpi=72)
    plt.close(fig)


def fmt(x, spec=".2f"):
    return "-" if x is None else format(x, spec)


def tables(summary):
    lines = ["# Issue 25: generators against direct light alone", "",
             "Final images (ACES, sRGB) against path-traced references; mean PSNR (dB) / SSIM per scene group. "
             "Written by training/ngi_train/generator/gi_eval.py.", ""]
    for part, label in (("heldout", "Held-out split"), ("vox", "Public MagicaVoxel scenes")):
        groups = list(next(iter(summary["variants"].values()))[part].keys())
        lines += [f"## {label}", "", "| variant | mode | " + " | ".join(groups) + " |",
                  "| --- | --- | " + " | ".join("---" for _ in groups) + " |"]
        for name, v in summary["variants"].items():
            cells = [f"{fmt(g['psnr'])} / {fmt(g['ssim'], '.3f')}" if g else "-" for g in
                     (v[part].get(k) for k in groups)]
            lines.append(f"| {name} | {v['output_mode']} | " + " | ".join(cells) + " |")
        frames = [f"{k}: {g['frames']}" for k, g in summary["variants"]["direct_only"][part].items() if g]
        lines += ["", "Frames: " + ", ".join(frames) + ".", ""]
    if summary.get("temporal"):
        lines += ["## Moving camera (room:seed=204, path frames 39-81)", "",
                  "| variant | PSNR | SSIM | warping error | reference's | ratio | MABD | reference's |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for name, t in summary["temporal"].items():
            lines.append(f"| {name} | {fmt(t['psnr'])} | {fmt(t['ssim'], '.3f')} | {fmt(t['warp_error'], '.4f')} | "
                         f"{fmt(t['warp_error_reference'], '.4f')} | "
                         f"{fmt(t['warp_error'] / t['warp_error_reference'])} | {fmt(t['mabd'], '.4f')} | "
                         f"{fmt(t['mabd_reference'], '.4f')} |")
        lines.append("")
    if summary.get("direct_noise"):
        spps = sorted({int(k) for per in summary["direct_noise"].values() for k in per})
        lines += ["## Direct-light feature noise (the same held-out frames, direct feature at other spp)", "",
                  "| variant | " + " | ".join(f"{k} spp" for k in spps) + " |",
                  "| --- | " + " | ".join("---" for _ in spps) + " |"]
        for name, per in summary["direct_noise"].items():
            cells = [f"{fmt(per[str(k)]['psnr'])} / {fmt(per[str(k)]['ssim'], '.3f')}" if per.get(str(k)) else "-"
                     for k in spps]
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
        lines.append("")
    if summary.get("guard"):
        lines += ["## Per-frame guard (fall back to direct light when the added indirect share exceeds t)", "",
                  "t is chosen on all held-out frames (shipped in the zoo) and applied to the .vox frames; the "
                  "held-out row guards each scene with the t chosen on the other scenes (leave one scene out).", "",
                  "| rung | t | set | fallbacks | off | on | direct |", "| --- | --- | --- | --- | --- | --- | --- |"]
        for name, g in summary["guard"].items():
            for label in ("heldout_leave_one_scene_out", "vox"):
                if label in g:
                    e = g[label]
                    cell = lambda s: f"{fmt(s['psnr'])} / {fmt(s['ssim'], '.3f')}"  # noqa: E731
                    lines.append(f"| {name} | {g['chosen']:g} | {label} | {e.get('fallbacks', '-')}/{e['frames']} | "
                                 f"{cell(e['off'])} | {cell(e['on'])} | {cell(e['direct'])} |")
        lines.append("")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------
# Zoo
# --------------------------------------------------------------------------

def merge_zoo(zoo_path, vs, summary, speed):
    """Adds (or replaces) the shipped GI rungs in the zoo manifest; the other rungs stay, each told its mode."""
    zoo = json.loads(Path(zoo_path).read_text())
    # A device key names one device: costs measured on another CPU than the zoo's entry of that key get their own
    # key (the planner matches keys by device name, and measures in process where a rung has no cost there).
    keys = {}
    for d, s in speed.items():
        if not s:
            continue
        info = next(iter(s.values()))["device"]
        known = zoo["devices"].get(d)
        keys[d] = d if not known or known.get("name") == info.get("name") else f"{d}:{info.get('name')}"
    speed = {keys[d]: s for d, s in speed.items() if d in keys}
    fake = {"variants": {}, "speed_devices": {d: next(iter(s.values()))["device"] for d, s in speed.items() if s},
            "dataset_configs": {}, "noise_floor": {}, "recipe": {}}
    for v in vs:
        if v["kind"] != "rung" or not v.get("shipped") or v["output_mode"] != "indirect":
            continue
        s = summary["variants"][v["name"]]
        fake["variants"][v["name"]] = {
            **{k: (le.rel(v[k]) if k == "file" else v[k]) for k in ("kind", "layout", "n", "ngf", "num_downs",
                                                                       "bn_mode", "weights", "file", "shipped")},
            "speed": {d: speed[d][v["name"]] for d in speed if v["name"] in speed[d]},
            "heldout": {"frames": s["heldout"]["all"]["frames"],
                        "final": {"psnr": s["heldout"]["all"]["psnr"], "ssim": s["heldout"]["all"]["ssim"]},
                        "lightmap": {k: s["heldout"]["all"][f"lightmap_{k}"] for k in ("psnr", "ssim", "mse")},
                        "groups": s["heldout"], "vox": s["vox"]},
            "temporal": {"moving_camera": summary["temporal"].get(v["name"])}}
    new = zoo_mod.build(fake, zoo_path, REPO)["rungs"]
    for r in new:
        r["output_mode"] = "indirect"
        g = summary["guard"].get(r["name"])
        loso = (g or {}).get("heldout_leave_one_scene_out") or {}
        # Shipped only where it falls back on some frames and, estimated leaving one scene out, improves PSNR.
        if g and g["chosen"] <= 1.0 and psnr_key(loso.get("on")) > psnr_key(loso.get("off")):
            r["guard"] = {"max_indirect_share": g["chosen"], "calibration_frames": g["calibration_frames"],
                          "heldout_leave_one_scene_out": g.get("heldout_leave_one_scene_out"), "vox": g.get("vox")}
    names = {r["name"] for r in new}
    kept = [r for r in zoo["rungs"] if r["name"] not in names]
    for r in kept:
        r.setdefault("output_mode", "lightmap" if r["file"] else "none")
    zoo["rungs"] = kept + new
    for d, info in fake["speed_devices"].items():
        zoo["devices"].setdefault(d, info)
    le.write_json(zoo_path, zoo)
    zoo_mod.load(zoo_path)  # what was written must load
    return [r["name"] for r in new]


def gi_cards(zoo):
    """models/ladder/GI.md: one model card per shipped indirect-light rung (from the zoo manifest)."""
    L = ["# The indirect-light rungs (issue 25)", "",
         "Pix2pix U-Net generators whose output is **indirect light only** (`output_mode` \"indirect\" in the file's "
         "metadata): ngi adds the frame's front direct light to the decoded output, so a network that predicts nothing "
         "still gives direct light alone. Trained here with one recipe (training/configs/gi.json: L1 of the encoded "
         "composed lightmap + L1 of the tone-mapped final image, no GAN term) on configs/dataset_gi_n64.json, exported "
         "with F16 weights. Measured cost and accuracy: [models/zoo.json](../zoo.json); the comparison with direct "
         "light, the thesis-mode rungs and the public .vox scenes: [docs/RESULTS.md](../../docs/RESULTS.md). "
         "Reproduce: training/README.md, \"Indirect-light generators\".", ""]
    for r in zoo["rungs"]:
        if r.get("output_mode") != "indirect" or r["kind"] != "rung":
            continue
        h = (r["accuracy"] or {}).get("heldout") or {}
        t = r.get("training") or {}
        g = h.get("groups") or {}
        what = ("the global view (6 faces merged to 4N x 2N, 12 channels)" if r["layout"] == "surround"
                else "the front face only (10 channels)")
        L += [f"## `{r['file']}`", "",
              f"- **Sees** {what}; N = {r['n']}, input {r['input']}; ngf {r['ngf']}, {r['num_downs']} downsamplings; "
              f"{fmt(r.get('gflop'), '.2f')} GFLOP per frame.",
              "- **Output**: indirect diffuse light of the front view (>= 0); lightmap = the frame's direct light + it; "
              f"batch norm at inference: {r['bn_mode']} (chosen at export by L1 on frames of the held-out test split itself, not on a validation split: a known flaw of this record; scores in the file's training.bn_mode_selection).",
              f"- **Training**: {t.get('steps')} steps = {fmt(t.get('epochs'), '.1f')} epochs over {t.get('frames')} "
              f"frames, seed {t.get('seed')}, {fmt((t.get('wall_seconds') or 0) / 60, '.0f')} min on one core."]
        if h:
            parts = [f"{k} {fmt(v['psnr'])} dB / SSIM {fmt(v['ssim'], '.3f')} ({v['frames']} frames)"
                     for k, v in g.items() if v]
            L.append("- **Held-out** final images against converged references: " + "; ".join(parts) + ".")
        vox = h.get("vox") or {}
        if vox.get("all"):
            L.append(f"- **Public .vox scenes** (evaluation only): {fmt(vox['all']['psnr'])} dB / SSIM "
                     f"{fmt(vox['all']['ssim'], '.3f')} over {vox['all']['frames']} frames.")
        if r.get("guard"):
            L.append(f"- **Guard**: falls back to direct light when the indirect share exceeds "
                     f"{r['guard']['max_indirect_share']:g} (calibrated on {r['guard']['calibration_frames']} frames; "
                     "`ngi lightmap --guard`, applied by `ngi.plan`).")
        costs = "; ".join(f"{d}: generator {c['generator_ms']:.1f} ms, whole `ngi lightmap` {c['lightmap_ms']:.0f} ms"
                          for d, c in r["cost"].items())
        L += [f"- **Cost**: {costs}.",
              "- **Limits**: trained on procedural block scenes (rooms, streets, caves, backlit and colour-bleeding "
              "rooms, sculptures, Cornell boxes) at N = 64 with a 64-spp direct-light feature; see docs/RESULTS.md "
              "for where it gains least.", ""]
    return "\n".join(L) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", type=Path, required=True, help="the GI ladder's work folder (ngi_train.generator.ladder --work)")
    ap.add_argument("--data", type=Path, required=True, help="the N = 64 dataset (configs/dataset_gi_n64.json)")
    ap.add_argument("--seq", type=Path, help="a rendered configs/sequences_clean_n64.json (default: render the frames "
                                             "used into WORK/seq)")
    ap.add_argument("--skip", default="", help="comma-separated stages to skip: vox,temporal,noise,curves,speed")
    ap.add_argument("--vox-dir", type=Path, help="a folder of .vox files to evaluate on (read only)")
    ap.add_argument("--vox-frames", type=int, default=3, help="frames per .vox file")
    ap.add_argument("--vox-path-frames", type=int, default=30, help="length of the .vox camera path")
    ap.add_argument("--vox-spp", type=int, default=256, help="reference spp of the .vox frames")
    ap.add_argument("--devices", default="pocl", help="comma-separated ngi device specs to time on ('' = none)")
    ap.add_argument("--device", default="pocl", help="the device the quality is measured on")
    ap.add_argument("--render-device", default="pocl")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--lightmap-frames", type=int, default=5)
    ap.add_argument("--max-frames", type=int, default=0, help="held-out frames (0 = all; for a quick check)")
    ap.add_argument("--ngi", default=None)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--zoo", type=Path, help="add the shipped GI rungs to this zoo manifest")
    args = ap.parse_args(argv)
    args.skip = set(args.skip.split(",")) - {""}
    args.work.mkdir(parents=True, exist_ok=True)
    args.out.mkdir(parents=True, exist_ok=True)
    vs = variants(args.work)
    runner = le.Runner(ngi.Device(args.device))
    held = heldout_rows(args, runner, vs, args.work)
    vox, vox_skipped, vox_dirs = (vox_rows(args, runner, vs, args.work) if args.vox_dir and "vox" not in args.skip
                                  else ({}, [], {}))
    temp = temporal_stage(args, runner, vs, args.work) if "temporal" not in args.skip else {}
    noise = (direct_noise_stage(args, runner, [v for v in vs if v["output_mode"] != "lightmap"], args.work)
             if "noise" not in args.skip else {})
    held_noise = {v["name"]: mean_scores([r for r in held[v["name"]] if r["index"] in NOISE_FRAMES]) for v in vs}
    curves = curves_stage(args, args.work, args.out / "gi_curves.png") if "curves" not in args.skip else {}
    speed_args = argparse.Namespace(ngi=args.ngi, devices=[d for d in args.devices.split(",") if d],
                                    repeats=args.repeats, lightmap_frames=args.lightmap_frames, data={64: args.data})
    speed = (le.speed_stage(speed_args, [v for v in vs if v["output_mode"] == "indirect"], args.work)
             if "speed" not in args.skip else {})

    summary = {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
               "dataset": le.rel(args.data), "dataset_config": le.read_json(args.data / "dataset.json"),
               "vox_dir": args.vox_dir.name if args.vox_dir else None, "vox_skipped_unlit": vox_skipped,
               "variants": {}, "temporal": temp, "speed": speed,
               "direct_noise": {name: {"64": held_noise[name], **per} for name, per in noise.items()},
               "curves": curves}
    for v in vs:
        summary["variants"][v["name"]] = {
            "kind": v["kind"], "output_mode": v["output_mode"], "layout": v["layout"], "ngf": v["ngf"],
            "file": le.rel(v["file"]) if v["file"] else None, "shipped": bool(v.get("shipped")),
            "heldout": by_group(held[v["name"]], lambda r: group_of(r["family"])),
            "heldout_families": by_group(held[v["name"]], lambda r: r["family"]),
            "vox": by_group(vox.get(v["name"], []), lambda r: r["group"]) if vox else {},
            "vox_files": by_group(vox.get(v["name"], []), lambda r: r["family"]) if vox else {}}
    summary["guard"] = guard_stage(held, vox, vs)
    gi = [v for v in vs if v["output_mode"] == "indirect"]
    if gi:
        best = max(gi, key=lambda v: psnr_key(summary["variants"][v["name"]]["heldout"]["all"]))["name"]
        summary["best_indirect_rung"] = best
        if vox_dirs:
            vox_strip(runner, vs, vox_dirs, best, args.out / "gi_vox_strip.png")
    le.write_json(args.out / "gi.json", summary)
    (args.out / "gi_tables.md").write_text(tables(summary))
    if args.zoo:
        log(f"gi_eval: zoo {args.zoo}: added {merge_zoo(args.zoo, vs, summary, speed)}")
        (args.zoo.parent / "ladder" / "GI.md").write_text(gi_cards(json.loads(args.zoo.read_text())))
    log(f"gi_eval: wrote {args.out / 'gi.json'} and {args.out / 'gi_tables.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

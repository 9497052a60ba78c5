#!/usr/bin/python3
"""Everything docs/RESULTS.md shows, from the trained models, in one command:

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.report --dataset DATA \\
        --surround models/surround.safetensors --single-view models/single_view.safetensors --out docs/results \\
        [--ngi build/ngi] [--max-frames K]

1. Held-out table: `ngi lightmap` (through evaluate.py) on every frame of DATA's test split (scenes disjoint
   from training) for the surround-aware and the single-view model; SSIM / MSE / PSNR of the tone-mapped final
   images (final_ldr, data range 1) and of the linear lightmaps, against the path-traced reference, with the
   direct-light-only baseline; means over all frames and per scene family. The thesis's Table 5.3 beside it
   (another dataset and resolution; quoted, not recomputed).
2. Temporal sequences like the thesis's Figures 5.10 / 5.11, rendered with `ngi render` at DATA's N, spp and
   bounces: (a) the camera moving along the path of a held-out room scene, light fixed; (b) a fixed camera in a
   held-out backlit scene while the sun turns until it shines in through the opening behind the camera. Per
   frame SSIM / PSNR of both models and the direct-only baseline (line plot) and an image strip (rows direct
   only | single view | surround | reference). `ngi merge` of every frame gives the light on and off screen
   (the plot's bottom panel), which shows what the sequence does to the light the single-view model can see.
3. Speed and accuracy: per model, the generator alone (`ngi_bench generator`, median of --repeats runs at the
   model's input size) and the whole `ngi lightmap` command (median wall time over --speed-frames test
   frames, after a warm-up), next to the held-out SSIM / PSNR: table and scatter plot.
4. OUT/*.png, OUT/results.json (every number, per frame included) and OUT/tables.md (Markdown for
   docs/RESULTS.md; image links relative to docs/).

Intermediate files (rendered frames, ngi lightmap outputs, merges, timings) go to --work (default out/report),
keyed by the model files' hashes and the render settings, so a rerun skips whatever exists (resumable; a new
model file gets new outputs). --max-frames K caps every stage (held-out frames spread evenly over the split,
sequence frames spread evenly, speed frames): for a quick check. Progress with ETA on stderr.
"""

import argparse
import datetime
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

import ngi.model_file as model_file

from ngi_train import ngi_paths
from ngi_train.generator import data, evaluate

VARIANTS = ("surround", "single_view")
LABEL = {"surround": "surround-aware", "single_view": "single view", "direct_only": "direct light only",
         "reference": "reference (path traced)"}
STYLE = {"surround": dict(color="#1f77b4", ls="-", marker="o"),
         "single_view": dict(color="#ff7f0e", ls="--", marker="s"),
         "direct_only": dict(color="#7f7f7f", ls=":", marker="^"), "reference": dict(color="black", ls="-", marker="")}
FAMILIES = ("room", "street", "cave", "backlit", "bleed")

# Thesis (shared/seeds/000_*), section 5.2.3, Table 5.3 "Quality Evaluation Metrics comparison at 40th epoch".
THESIS_TABLE_5_3 = {
    "rows": [{"approach": "Surrounding-Aware (ours)", "ssim": 0.90811, "mse": 0.00093, "psnr": 30.30576},
             {"approach": "DeepIllumination [15] (single view)", "ssim": 0.89329, "mse": 0.00108, "psnr": 29.63102}],
    "what": "the generator's output against the ray-traced ground truth on the thesis's test set, after 40 epochs "
            "(section 5.2.3: 'generated images, tested against the ray-traced ground truth ... recorded for every "
            "epochs' generated output on the test dataset'). Its generator outputs the GI lightmap and its data are "
            "8-bit PNGs; MSE 0.00093 <-> PSNR 30.3 dB means a data range of 1. It does not say whether the "
            "lightmap or the blended final image was scored.",
    "dataset": "Blender scenes: 5,300 training frames from 19 scenes, 1,525 test frames from 6 other scenes "
               "(section 4.2), 256 x 256 per view (global view 1024 x 512), features from EEVEE, reference from "
               "Cycles X, light stored as 8-bit PNG (clipped at 1); ngf 64 U-Net, 40 epochs.",
}


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def file_digest(path, length=12):
    h = hashlib.sha1()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:length]


def text_digest(obj, length=10):
    return hashlib.sha1(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:length]


def write_json(path, obj):
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1) + "\n")
    tmp.replace(path)


def repo_relative(obj, root=ngi_paths.REPO):
    """obj with every absolute path string made relative to the repository: results.json is committed, and
    machine paths in it would mean nothing elsewhere."""
    if isinstance(obj, dict):
        return {k: repo_relative(v, root) for k, v in obj.items()}
    if isinstance(obj, list):
        return [repo_relative(v, root) for v in obj]
    if isinstance(obj, str) and os.path.isabs(obj):
        return os.path.relpath(obj, root)
    return obj


class Stage:
    """Progress with ETA for `total` pieces of work of which `todo` still have to be done (resumed ones are
    reported as skipped and do not count in the rate)."""

    def __init__(self, name, total, todo, unit):
        self.name, self.todo, self.done = name, todo, 0
        log(f"== {name}: {total} {unit}s, {total - todo} already done, {todo} to do")
        self.bar = tqdm(total=todo, desc=name, unit=unit, **ngi_paths.progress_options()) if todo else None

    def step(self):
        self.done += 1
        if self.bar:
            self.bar.update(1)
            if self.done == self.todo:
                self.bar.close()


# --------------------------------------------------------------------------
# 1. Held-out table
# --------------------------------------------------------------------------

def scene_family(dataset, rel):
    """Family of a frame's scene (room, street, cave, backlit, bleed; 'vox' for .vox scenes) from scene.json."""
    scene_dir = Path(dataset) / Path(rel).parent
    spec = json.loads((scene_dir / "scene.json").read_text())["spec"] if (scene_dir / "scene.json").is_file() \
        else scene_dir.name
    head = re.split(r"[:_]", Path(spec).name if spec.endswith(".vox") else spec)[0]
    return head if head in FAMILIES else "vox" if spec.endswith(".vox") else head


def pick(metrics, who):
    """{final_ldr, lightmap_linear} of one party ('network' or 'direct_only') of a metrics.json."""
    return {space: dict(metrics[who][space]) for space in evaluate.SPACES}


def scene_folder(spec):
    """ngi's dataset_scene_folder: 'room:seed=3' -> 'room_seed3', a .vox path -> its stem."""
    if spec.endswith(".vox"):
        return Path(spec).stem
    return spec.replace(":", "_").replace(",", "_").replace("=", "")


def check_held_out(args, models, ds_cfg, specs):
    """Warnings (also kept in results.json) when a model was trained on another N, or on any scene this report
    treats as held out: the test split's scenes and the sequences' scenes."""
    notes = []
    held_out = {scene_folder(e["scene"]): e["scene"] for e in ds_cfg.get("test", [])}
    held_out.update({scene_folder(s["scene"]): s["scene"] for s in specs})
    for v, m in models.items():
        t = m["config"].get("training") or {}
        trained = t.get("dataset_config")
        if not trained:
            notes.append(f"{v}: the model file has no training dataset config; cannot check that the test scenes "
                         "were held out")
            continue
        if trained.get("n") != ds_cfg["n"]:
            notes.append(f"{v}: trained at N = {trained.get('n')}, this dataset has N = {ds_cfg['n']}")
        seen = {scene_folder(e["scene"]) for e in trained.get("train", [])}
        for folder in sorted(seen & set(held_out)):
            notes.append(f"{v}: {held_out[folder]} was in its training set, but this report uses it as held out")
    for n in notes:
        log(f"warning: {n}")
    return notes


def heldout(args, ngi, models, work):
    frames = data.select_frames(data.list_frames(args.dataset, "test"), args.max_frames)
    out_dirs = {v: work / "heldout" / f"{v}-{models[v]['digest']}" for v in VARIANTS}
    todo = sum(not (out_dirs[v] / rel / "metrics.json").is_file() for v in VARIANTS for rel in frames)
    stage = Stage("held-out", 2 * len(frames), todo, "frame")
    per_frame = {}
    for v in VARIANTS:
        evaluate.evaluate_with_ngi(ngi, models[v]["path"], args.dataset, "test", out_dirs[v], args.max_frames,
                                   args.device, resume=True,
                                   on_frame=lambda k, n, rel, s: s is not None and stage.step())
        per_frame[v] = json.loads((out_dirs[v] / "per_frame.json").read_text())
    # Direct-only is the same computation in both runs (it does not involve the model): take the surround run's
    # and check that the two agree.
    rows = {}
    for rel in frames:
        a, b = per_frame["surround"][rel], per_frame["single_view"][rel]
        for space in evaluate.SPACES:
            x, y = a["direct_only"][space]["ssim"], b["direct_only"][space]["ssim"]
            if abs(x - y) > 1e-6:
                raise RuntimeError(f"{rel}: direct-only {space} SSIM differs between the two runs ({x} vs {y})")
        rows[rel] = {"scene": Path(rel).parent.name, "family": scene_family(args.dataset, rel),
                     "surround": pick(a, "network"), "single_view": pick(b, "network"),
                     "direct_only": pick(a, "direct_only")}

    def means(rels):
        return {who: {space: {m: evaluate._mean([rows[r][who][space][m] for r in rels]) for m in evaluate.METRICS}
                      for space in evaluate.SPACES} for who in ("surround", "single_view", "direct_only")}

    families = [f for f in FAMILIES if any(r["family"] == f for r in rows.values())]
    families += sorted({r["family"] for r in rows.values()} - set(families))
    by_family = {f: dict(frames=sum(r["family"] == f for r in rows.values()),
                         scenes=sorted({r["scene"] for r in rows.values() if r["family"] == f}),
                         **means([k for k, r in rows.items() if r["family"] == f])) for f in families}
    by_scene = {s: dict(frames=sum(r["scene"] == s for r in rows.values()),
                        **means([k for k, r in rows.items() if r["scene"] == s]))
                for s in sorted({r["scene"] for r in rows.values()})}
    # Paired comparison surround vs single view, per frame (the same frames, the same reference).
    d_ssim = [rows[r]["surround"]["final_ldr"]["ssim"] - rows[r]["single_view"]["final_ldr"]["ssim"] for r in rows]
    d_psnr = [rows[r]["surround"]["final_ldr"]["psnr"] - rows[r]["single_view"]["final_ldr"]["psnr"] for r in rows
              if rows[r]["surround"]["final_ldr"]["psnr"] is not None
              and rows[r]["single_view"]["final_ldr"]["psnr"] is not None]
    paired = {"frames_surround_ssim_higher": sum(d > 0 for d in d_ssim), "frames": len(d_ssim),
              "mean_ssim_difference": float(np.mean(d_ssim)) if d_ssim else None,
              "mean_psnr_difference_db": float(np.mean(d_psnr)) if d_psnr else None,
              "scenes_surround_ssim_higher": sum(
                  by_scene[s]["surround"]["final_ldr"]["ssim"] > by_scene[s]["single_view"]["final_ldr"]["ssim"]
                  for s in by_scene),
              "scenes": len(by_scene)}
    return {"split": "test", "frames": len(frames), "scenes": sorted(by_scene), "all": means(list(rows)),
            "by_family": by_family, "by_scene": by_scene, "paired": paired, "per_frame": rows,
            "outputs": {v: str(out_dirs[v]) for v in VARIANTS}}


# --------------------------------------------------------------------------
# 2. Temporal sequences
# --------------------------------------------------------------------------

def parse_frames(text):
    """'A:B:S' -> range(A, B, S) (B exclusive), or 'a,b,c'."""
    if ":" in text:
        a, b, s = (int(x) for x in text.split(":"))
        return list(range(a, b, s))
    return [int(x) for x in text.split(",")]


def parse_times(text):
    """'T0:T1:COUNT' -> COUNT times from T0 to T1 inclusive, or 't,t,t'."""
    if ":" in text:
        a, b, n = text.split(":")
        return [round(float(x), 4) for x in np.linspace(float(a), float(b), int(n))]
    return [float(x) for x in text.split(",")]


def sequence_specs(args):
    room = [{"frame": f, "time": args.room_time} for f in parse_frames(args.room_frames)]
    sun = [{"frame": args.backlit_frame, "time": t} for t in parse_times(args.backlit_times)]
    if args.max_frames:
        room, sun = data.select_frames(room, args.max_frames), data.select_frames(sun, args.max_frames)
    return [
        {"name": "moving_camera", "scene": args.room_scene, "path_frames": args.room_path_frames, "items": room,
         "x": "frame", "xlabel": "camera path frame (light fixed)",
         "title": f"Moving camera, fixed light: {args.room_scene} (not in training)",
         "thesis": "Figure 5.10 (moving camera, stationary light)"},
        {"name": "moving_sun", "scene": args.backlit_scene, "path_frames": args.backlit_path_frames, "items": sun,
         "x": "time", "xlabel": "time of day (h), camera fixed",
         "title": f"Fixed camera, sun entering from behind: {args.backlit_scene} (not in training)",
         "thesis": "Figure 5.11 (stationary camera, moving light)"},
    ]


def render_frame(ngi, seq, item, dest, settings, device):
    """`ngi render` of one sequence frame into dest (a frame folder); returns its camera info (kept beside it)."""
    info_path = dest.with_name(dest.name + ".json")
    if (dest / "camera.json").is_file() and info_path.is_file():
        return json.loads(info_path.read_text()), None
    cmd = [ngi, "render", "--scene", seq["scene"], "--out", dest, "--face", settings["n"],
           "--spp", settings["reference_spp"], "--feature-spp", settings["feature_spp"],
           "--bounces", settings["max_bounces"], "--frame", item["frame"], "--path-frames", seq["path_frames"]]
    if item["time"] is not None:
        cmd += ["--time", item["time"]]
    if device:
        cmd += ["--device", device]
    if dest.exists():  # a frame folder without its info file: render again
        shutil.rmtree(dest)
    proc, seconds = ngi_paths.run(cmd)
    camera = json.loads((dest / "render.json").read_text())["camera"]  # what ngi render rendered
    info = {"frame": camera["frame"], "path_frames": camera["path_frames"], "position": camera["position"],
            "look": camera["look"], "time": camera["time_h"], "render_seconds": seconds, "render_log": proc.stdout}
    write_json(info_path, info)
    return info, seconds


def decode_light(v):
    """Encoded lumination / target in [-1, 1] -> linear light (Reinhard inverse, docs/CONVENTIONS.md 8)."""
    return evaluate.decode(v)


def light_diagnostics(merge_dir, n):
    """From `ngi merge` (surround layout): mean light on visible surfaces in the front view and elsewhere in the
    global view (direct + emission, irradiance / pi; sky texels, albedo 0, left out), and the reference
    lightmap's front-view mean (direct + indirect, the target the models should produce)."""
    x = np.load(merge_dir / "input.npy")[0].astype(np.float64)
    target = np.load(merge_dir / "target.npy")[0].astype(np.float64)
    albedo = (x[0:3] + 1) / 2
    light = decode_light(x[7:10]).mean(axis=0)
    surface = albedo.sum(axis=0) > 1e-6
    rows, cols = data.front_region(n)
    front = np.zeros_like(surface)
    front[rows, cols] = True

    def mean(mask):
        return float(light[mask].mean()) if mask.any() else 0.0

    return {"direct_on_screen": mean(surface & front), "direct_off_screen": mean(surface & ~front),
            "reference_front_mean": float(decode_light(target).mean())}


def image_mean(png):
    import matplotlib.image as mpimg
    return float(mpimg.imread(png)[..., :3].mean())


def sequences(args, ngi, models, work, settings):
    specs = sequence_specs(args)
    results = []
    render_key = {k: settings[k] for k in ("n", "reference_spp", "feature_spp", "max_bounces")}
    plan = []
    for seq in specs:
        key = text_digest({"scene": seq["scene"], "path_frames": seq["path_frames"], **render_key})
        seq["dir"] = work / "sequences" / f"{seq['name']}-{key}"
        if (seq["dir"] / "frames").is_dir():  # temporaries of an ngi render killed mid-write never become frames
            for leftover in (seq["dir"] / "frames").glob("*.tmp-*"):
                shutil.rmtree(leftover, ignore_errors=True)
        for i, item in enumerate(seq["items"]):
            item["id"] = f"f{item['frame']:04d}_t{'default' if item['time'] is None else format(item['time'], '.3f')}"
            plan.append((seq, item))
    todo_render = sum(not (s["dir"] / "frames" / it["id"] / "camera.json").is_file() for s, it in plan)
    stage = Stage("sequence renders", len(plan), todo_render, "frame")
    for seq, item in plan:
        info, seconds = render_frame(ngi, seq, item, seq["dir"] / "frames" / item["id"], settings, args.device)
        item["camera"] = {k: v for k, v in info.items() if k != "render_log"}
        if seconds is not None:
            stage.step()
    todo = sum(not (s["dir"] / v / it["id"] / "metrics.json").is_file()
               for s, it in plan for v in [f"{x}-{models[x]['digest']}" for x in VARIANTS])
    stage = Stage("sequence lightmaps", 2 * len(plan), todo, "frame")
    for seq, item in plan:
        frame_dir = seq["dir"] / "frames" / item["id"]
        item["metrics"] = {}
        item["outputs"] = {}
        for v in VARIANTS:
            dest = seq["dir"] / f"{v}-{models[v]['digest']}" / item["id"]
            m, seconds = evaluate.run_lightmap(ngi, frame_dir, models[v]["path"], dest, args.device, resume=True)
            item["metrics"][v] = pick(m, "network")
            item["metrics"]["direct_only"] = pick(m, "direct_only")
            item["outputs"][v] = str(dest)
            if seconds is not None:
                stage.step()
        merge_dir = seq["dir"] / "merge" / item["id"]
        if not (merge_dir / "target.npy").is_file():
            data.run_merge(frame_dir, merge_dir, "surround", args.device)
        item["light"] = light_diagnostics(merge_dir, settings["n"])
        # Mean brightness of the tone-mapped final images (compare.png: direct only | network | reference).
        item["brightness"] = {}
        for v in VARIANTS:
            cmp = strip_images(Path(item["outputs"][v]) / "compare.png")
            item["brightness"][v] = float(cmp["network"].mean())
            item["brightness"]["direct_only"] = float(cmp["direct_only"].mean())
            item["brightness"]["reference"] = float(cmp["reference"].mean())
    for seq in specs:
        seq["summary"] = {who: {m: evaluate._mean([it["metrics"][who]["final_ldr"][m] for it in seq["items"]])
                                for m in evaluate.METRICS} for who in ("surround", "single_view", "direct_only")}
        for who in ("surround", "single_view", "direct_only"):
            ssims = [it["metrics"][who]["final_ldr"]["ssim"] for it in seq["items"]]
            seq["summary"][who]["ssim_min"] = min(ssims)
            # Frame-to-frame change of the mean final brightness against the reference's: how much the model's
            # light drifts from what the reference does over the sequence.
            b = np.array([it["brightness"][who] for it in seq["items"]])
            r = np.array([it["brightness"]["reference"] for it in seq["items"]])
            seq["summary"][who]["brightness_error_mean"] = float(np.mean(np.abs(b - r)))
        seq["dir"] = str(seq["dir"])
        results.append(seq)
    return results


def strip_images(compare_png):
    """ngi lightmap's compare.png (direct only | network | reference, each N x N, tone mapped, sRGB)."""
    import matplotlib.image as mpimg
    im = mpimg.imread(compare_png)[..., :3]
    n = im.shape[1] // 3
    return {"direct_only": im[:, :n], "network": im[:, n:2 * n], "reference": im[:, 2 * n:3 * n]}


# --------------------------------------------------------------------------
# 3. Speed
# --------------------------------------------------------------------------

def ngi_devices(ngi):
    try:
        out = ngi_paths.run([ngi, "devices"])[0].stdout
    except RuntimeError as e:
        out = str(e)
    return out


def speed(args, ngi, bench, models, work, settings, heldout_result):
    n = settings["n"]
    frames = data.select_frames(data.list_frames(args.dataset, "test"), args.speed_frames)
    if args.max_frames:
        frames = frames[:max(1, min(len(frames), args.max_frames))]
    results = {}

    def cache_path(v):
        return work / "speed" / (f"{v}-{models[v]['digest']}-{args.device or 'default'}-{len(frames)}f-"
                                 f"{args.repeats}r.json")

    todo = [v for v in VARIANTS if args.redo_speed or not cache_path(v).is_file()]
    stage = Stage("speed", len(VARIANTS), len(todo), "model")
    for v in VARIANTS:
        cache = cache_path(v)
        if v not in todo:
            results[v] = json.loads(cache.read_text())
            continue
        cfg = models[v]["config"]
        w, h = (4 * n, 2 * n) if cfg["input_nc"] == 12 else (n, n)
        load_before = os.getloadavg()
        cmd = [bench, "generator", "--model", models[v]["path"], "--width", w, "--height", h,
               "--repeats", args.repeats]
        if args.device:
            cmd += ["--device", args.device]
        b = json.loads(ngi_paths.run(cmd)[0].stdout)
        # The whole ngi lightmap command per frame: process start, device, model load (cached kernels), reading
        # the frame's EXRs, preprocessing + merge, generator, decode, compose, tone map, metrics, writing.
        tmp = work / "speed" / "tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        evaluate.run_lightmap(ngi, Path(args.dataset) / frames[0], models[v]["path"], tmp / "warmup", args.device)
        walls = []
        for k, rel in enumerate(frames):
            _, s = evaluate.run_lightmap(ngi, Path(args.dataset) / rel, models[v]["path"], tmp / str(k), args.device)
            walls.append(s * 1e3)
        shutil.rmtree(tmp, ignore_errors=True)
        results[v] = {"device": b["device"], "input": [1, cfg["input_nc"], h, w],
                      "generator_ms_median": b["ms_median"], "generator_ms_all": b["ms_all"],
                      "generator_device_ms_total": b.get("device_ms_total"), "gflop": b.get("gflop_total"),
                      "memory_mib": b.get("memory_mib"), "repeats": args.repeats,
                      "lightmap_wall_ms_median": float(np.median(walls)), "lightmap_wall_ms_all": walls,
                      "lightmap_frames": frames, "loadavg_before": load_before, "loadavg_after": os.getloadavg(),
                      "measured": datetime.datetime.now().isoformat(timespec="seconds")}
        cache.parent.mkdir(parents=True, exist_ok=True)
        write_json(cache, results[v])
        stage.step()
    for v in VARIANTS:
        results[v]["heldout_final_ldr"] = heldout_result["all"][v]["final_ldr"]
    return results


# --------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------

def plt_module():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.rcParams.update({"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "figure.dpi": 110})
    return plt


def fmt(v, spec):
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def plot_sequence(seq, path):
    plt = plt_module()
    items = seq["items"]
    xs = [it["camera"]["frame"] if seq["x"] == "frame" else it["camera"]["time"] for it in items]
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for ax, (metric, ylabel) in zip(axes[:2], (("ssim", "SSIM (final image)"), ("psnr", "PSNR dB (final image)"))):
        for who in ("surround", "single_view", "direct_only"):
            ys = [it["metrics"][who]["final_ldr"][metric] for it in items]
            ys = [np.nan if y is None else y for y in ys]
            mean = np.nanmean(ys)
            ax.plot(xs, ys, label=f"{LABEL[who]} (mean {mean:.3f})" if metric == "ssim" else
                    f"{LABEL[who]} (mean {mean:.2f} dB)", ms=4, **STYLE[who])
        ax.set_ylabel(ylabel)
        ax.legend(loc="best", fontsize=8)
    ax = axes[2]
    for who in ("reference", "surround", "single_view", "direct_only"):
        ax.plot(xs, [it["brightness"][who] for it in items], label=LABEL[who], ms=4, **STYLE[who])
    ax.set_ylabel("mean of the final image\n(tone mapped, sRGB)")
    ax.legend(loc="best", fontsize=8)
    ax = axes[3]
    floor = 1e-4  # log scale: a view without lit surfaces shows as 1e-4
    ax.plot(xs, [max(floor, it["light"]["direct_on_screen"]) for it in items],
            label="direct + emitted light on screen (front view)",
            color="#2ca02c", marker="o", ms=4)
    ax.plot(xs, [max(floor, it["light"]["direct_off_screen"]) for it in items],
            label="direct + emitted light off screen (other five faces)", color="#d62728", marker="v", ms=4)
    ax.plot(xs, [max(floor, it["light"]["reference_front_mean"]) for it in items],
            label="reference GI lightmap, front view",
            color="black", ls="--", ms=0)
    ax.set_yscale("log")
    ax.set_ylabel("mean light on surfaces\n(irradiance / π, log scale)")
    ax.set_xlabel(seq["xlabel"])
    ax.legend(loc="best", fontsize=8)
    fig.suptitle(seq["title"], fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path)
    plt.close(fig)


def plot_strip(seq, path, columns):
    plt = plt_module()
    items = data.select_frames(seq["items"], columns)
    rows = ("direct_only", "single_view", "surround", "reference")
    cell = 1.75
    fig, axes = plt.subplots(len(rows), len(items), figsize=(cell * len(items) + 1.0, cell * len(rows) + 0.9),
                             squeeze=False)
    for j, it in enumerate(items):
        sv = strip_images(Path(it["outputs"]["single_view"]) / "compare.png")
        su = strip_images(Path(it["outputs"]["surround"]) / "compare.png")
        images = {"direct_only": su["direct_only"], "single_view": sv["network"], "surround": su["network"],
                  "reference": su["reference"]}
        for i, who in enumerate(rows):
            ax = axes[i][j]
            ax.imshow(images[who], interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.grid(False)
            if who != "reference":
                m = it["metrics"][who]["final_ldr"]
                ax.set_xlabel(f"SSIM {fmt(m['ssim'], '.3f')}  {fmt(m['psnr'], '.1f')} dB", fontsize=7.5, labelpad=2)
            if j == 0:
                ax.set_ylabel(LABEL[who].replace(" (path traced)", "\n(path traced)").replace("light only",
                                                                                            "\nlight only"),
                              fontsize=9)
        cam = it["camera"]
        axes[0][j].set_title(f"frame {cam['frame']}" if seq["x"] == "frame" else f"{cam['time']:.2f} h", fontsize=9)
    fig.suptitle(seq["title"], fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97), h_pad=0.6, w_pad=0.3)
    fig.savefig(path)
    plt.close(fig)


def plot_families(heldout_result, path):
    plt = plt_module()
    fams = list(heldout_result["by_family"])
    groups = fams + ["all"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    width = 0.27
    for ax, metric, ylabel in ((axes[0], "ssim", "SSIM (final image)"), (axes[1], "psnr", "PSNR dB (final image)")):
        for k, who in enumerate(("direct_only", "single_view", "surround")):
            ys = [(heldout_result["by_family"][f] if f != "all" else heldout_result["all"])[who]["final_ldr"][metric]
                  for f in groups]
            ax.bar(np.arange(len(groups)) + (k - 1) * width, [np.nan if y is None else y for y in ys], width,
                   label=LABEL[who], color=STYLE[who]["color"])
        ax.set_xticks(np.arange(len(groups)))
        counts = [heldout_result["by_family"][g]["frames"] if g != "all" else heldout_result["frames"] for g in groups]
        ax.set_xticklabels([f"{g}\n({c})" for g, c in zip(groups, counts)])
        ax.set_ylabel(ylabel)
        if metric == "ssim":
            ax.set_ylim(0, 1)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, 0.93), frameon=False)
    fig.suptitle(f"Held-out test split ({heldout_result['frames']} frames, scenes not in training; "
                 f"frames per family in brackets)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.86))
    fig.savefig(path)
    plt.close(fig)


def plot_speed(speed_result, heldout_result, path, device_name):
    plt = plt_module()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for ax, metric, ylabel in ((axes[0], "ssim", "held-out SSIM (final image)"),
                               (axes[1], "psnr", "held-out PSNR dB (final image)")):
        for v in VARIANTS:
            s = speed_result[v]
            y = heldout_result["all"][v]["final_ldr"][metric]
            xs = [s["generator_ms_median"], s["lightmap_wall_ms_median"]]
            ax.plot(xs, [y, y], color=STYLE[v]["color"], lw=1, alpha=0.6)
            ax.scatter(xs[0], y, color=STYLE[v]["color"], marker=STYLE[v]["marker"], s=50,
                       label=f"{LABEL[v]}: generator")
            ax.scatter(xs[1], y, facecolors="none", edgecolors=STYLE[v]["color"], marker=STYLE[v]["marker"], s=50,
                       label=f"{LABEL[v]}: whole ngi lightmap")
            for x in xs:
                ax.annotate(f"{x:.3g} ms", (x, y), textcoords="offset points", xytext=(0, 7), ha="center",
                            fontsize=7.5, color=STYLE[v]["color"])
        yd = heldout_result["all"]["direct_only"]["final_ldr"][metric]
        ax.axhline(yd, color=STYLE["direct_only"]["color"], ls=":", label="direct light only (no network)")
        ax.set_xscale("log")
        lo = min(speed_result[v]["generator_ms_median"] for v in VARIANTS)
        hi = max(speed_result[v]["lightmap_wall_ms_median"] for v in VARIANTS)
        ax.set_xlim(lo / 2, hi * 2)
        ys = [heldout_result["all"][w]["final_ldr"][metric] for w in ("surround", "single_view", "direct_only")]
        ys = [y for y in ys if y is not None]
        span = (max(ys) - min(ys)) or abs(max(ys)) * 0.1 or 1.0
        ax.set_ylim(min(ys) - 0.15 * span, max(ys) + 0.25 * span)
        ax.set_xlabel(f"ms per frame, log scale ({device_name})")
        ax.set_ylabel(ylabel)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle("Speed and accuracy: one frame at the dataset's N (generator: median of runs; whole ngi lightmap: "
                 "median wall time)", fontsize=10)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(path)
    plt.close(fig)


# --------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------

def markdown(res, link):
    L = []
    s, h = res["settings"], res["heldout"]
    L.append(f"<!-- generated by training/ngi_train/generator/report.py on {res['environment']['date']}; numbers in "
             f"{link('results.json')} -->")
    L.append("")
    for note in res["checks"]:
        L.append(f"**Warning:** {note}")
        L.append("")
    L.append(f"### Held-out test split (N = {s['n']}, reference {s['reference_spp']} spp)")
    L.append("")
    L.append(f"{h['frames']} frames of {len(h['scenes'])} scenes that are not in the training set "
             f"({', '.join(h['scenes'])}). Metrics of `ngi lightmap` (metrics.json): *final* = tone-mapped final "
             "images (lightmap x albedo + emission + sky, ACES, sRGB, data range 1) against the path-traced "
             "reference's; *lightmap* = linear HDR lightmaps, data range = the reference's maximum. PSNR is the "
             "mean of per-frame PSNRs.")
    L.append("")
    L.append("| | final SSIM | final MSE | final PSNR (dB) | lightmap SSIM | lightmap PSNR (dB) |")
    L.append("|---|---|---|---|---|---|")
    for who in ("surround", "single_view", "direct_only"):
        f, l = h["all"][who]["final_ldr"], h["all"][who]["lightmap_linear"]
        L.append(f"| {LABEL[who]} | {fmt(f['ssim'], '.4f')} | {fmt(f['mse'], '.5f')} | {fmt(f['psnr'], '.2f')} | "
                 f"{fmt(l['ssim'], '.4f')} | {fmt(l['psnr'], '.2f')} |")
    p = h["paired"]
    L.append("")
    L.append(f"Surround-aware minus single view, same frames: SSIM {fmt(p['mean_ssim_difference'], '+.4f')}, "
             f"PSNR {fmt(p['mean_psnr_difference_db'], '+.2f')} dB; the surround-aware SSIM is higher on "
             f"{p['frames_surround_ssim_higher']} of {p['frames']} frames and in {p['scenes_surround_ssim_higher']} "
             f"of {p['scenes']} scenes.")
    L.append("")
    L.append("Per scene family (final images, SSIM / PSNR dB):")
    L.append("")
    L.append("| family | frames | surround-aware | single view | direct light only |")
    L.append("|---|---|---|---|---|")
    for fam, r in h["by_family"].items():
        cells = [f"{fmt(r[w]['final_ldr']['ssim'], '.4f')} / {fmt(r[w]['final_ldr']['psnr'], '.2f')}"
                 for w in ("surround", "single_view", "direct_only")]
        L.append(f"| {fam} ({', '.join(r['scenes'])}) | {r['frames']} | " + " | ".join(cells) + " |")
    L.append("")
    L.append(f"![held-out per family]({link('heldout_families.png')})")
    L.append("")
    t = res["thesis_table_5_3"]
    L.append("**The thesis's Table 5.3, for reference — a different dataset, resolution and network size; not "
             "comparable number for number.** " + t["dataset"] + " What it measured: " + t["what"])
    L.append("")
    L.append("| thesis, 40th epoch | SSIM | MSE | PSNR (dB) |")
    L.append("|---|---|---|---|")
    for r in t["rows"]:
        L.append(f"| {r['approach']} | {r['ssim']:.5f} | {r['mse']:.5f} | {r['psnr']:.5f} |")
    L.append("")
    for seq in res["sequences"]:
        L.append(f"### {seq['title']}")
        L.append("")
        items = seq["items"]
        span = (f"path frames {items[0]['camera']['frame']}–{items[-1]['camera']['frame']} of {seq['path_frames']}, "
                f"time {items[0]['camera']['time']:.2f} h" if seq["x"] == "frame" else
                f"path frame {items[0]['camera']['frame']} of {seq['path_frames']}, time "
                f"{items[0]['camera']['time']:.2f}–{items[-1]['camera']['time']:.2f} h")
        L.append(f"Like the thesis's {seq['thesis']}: {len(items)} frames rendered with `ngi render` ({span}), "
                 f"N = {s['n']}, {s['reference_spp']} spp reference. Final images against the reference:")
        L.append("")
        L.append("| | mean SSIM | min SSIM | mean PSNR (dB) | mean \\|brightness − reference's\\| |")
        L.append("|---|---|---|---|---|")
        for who in ("surround", "single_view", "direct_only"):
            m = seq["summary"][who]
            L.append(f"| {LABEL[who]} | {fmt(m['ssim'], '.4f')} | {fmt(m['ssim_min'], '.4f')} | "
                     f"{fmt(m['psnr'], '.2f')} | {fmt(m['brightness_error_mean'], '.4f')} |")
        L.append("")
        L.append("Brightness = mean of the tone-mapped final image; its mean distance from the reference's over the "
                 "sequence measures how far a model's overall light level strays (the thesis's 'luminance ... gets "
                 "dimmer' effect). The plot's bottom panel shows the light the models can see: direct + emitted light "
                 "on surfaces in the front view and in the other five faces (from `ngi merge`).")
        L.append("")
        L.append(f"![{seq['name']} strip]({link(seq['name'] + '_strip.png')})")
        L.append("")
        L.append(f"![{seq['name']} per frame]({link(seq['name'] + '_plot.png')})")
        L.append("")
    sp = res["speed"]
    L.append(f"### Speed and accuracy ({res['environment']['speed_device']})")
    L.append("")
    L.append(res["environment"]["gpu_note"])
    L.append("")
    L.append("| model | input | generator ms (median) | whole `ngi lightmap` ms (median wall) | held-out SSIM | "
             "held-out PSNR (dB) |")
    L.append("|---|---|---|---|---|---|")
    for v in VARIANTS:
        x = sp[v]
        f = x["heldout_final_ldr"]
        L.append(f"| {LABEL[v]} | {' x '.join(map(str, x['input']))} | {x['generator_ms_median']:.1f} | "
                 f"{x['lightmap_wall_ms_median']:.0f} | {fmt(f['ssim'], '.4f')} | {fmt(f['psnr'], '.2f')} |")
    d = h["all"]["direct_only"]["final_ldr"]
    L.append(f"| {LABEL['direct_only']} | – | 0 | – | {fmt(d['ssim'], '.4f')} | {fmt(d['psnr'], '.2f')} |")
    L.append("")
    loads = [sp[v]["loadavg_before"][0] for v in VARIANTS]
    L.append(f"Generator: `ngi_bench generator` at the model's input size, median of {sp[VARIANTS[0]]['repeats']} "
             f"runs after a warm-up. Whole path: wall time of the `ngi lightmap` command (process start, device "
             f"open, model load with cached kernels, EXR reading, preprocessing and merge, generator, decode, "
             f"compose, tone map, metrics, writing), median over {len(sp[VARIANTS[0]]['lightmap_frames'])} "
             f"test frames after a warm-up run. Load average when measured: "
             f"{', '.join(format(x, '.1f') for x in loads)} (2-core machine).")
    L.append("")
    L.append(f"![speed vs accuracy]({link('speed_accuracy.png')})")
    L.append("")
    return "\n".join(L)


# --------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, help="dataset folder (ngi dataset --out): its test split")
    ap.add_argument("--surround", required=True, help="surround-aware model (.safetensors)")
    ap.add_argument("--single-view", required=True, help="single-view model (.safetensors)")
    ap.add_argument("--out", required=True, help="folder for the PNGs, results.json and tables.md")
    ap.add_argument("--work", help="intermediate files (default: out/report in the repository)")
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN or build*/ngi)")
    ap.add_argument("--bench", help="ngi_bench binary (default: perf/ngi_bench beside the ngi binary)")
    ap.add_argument("--device", help="ngi --device for everything")
    ap.add_argument("--max-frames", type=int, default=0, help="cap every stage at K frames (0 = no cap)")
    # Defaults chosen by looking at renders (global views of every frame): room:seed=204 at its own time (11.0 h)
    # walks up to a large opening onto sunlit ground (frames ~40-60) and turns into the room (~60-80), so the lit
    # opening leaves the view while the light stays. (room:seed=201 at its default noon has no sun patch.)
    ap.add_argument("--room-scene", default="room:seed=204")
    ap.add_argument("--room-path-frames", type=int, default=100, help="length of the room scene's camera path")
    ap.add_argument("--room-frames", default="39:84:3", help="path frames A:B:STEP (B exclusive) or a,b,c")
    ap.add_argument("--room-time", type=float, default=None, help="hours (default: the scene's own)")
    ap.add_argument("--backlit-scene", default="backlit:seed=201")
    ap.add_argument("--backlit-path-frames", type=int, default=100)
    ap.add_argument("--backlit-frame", type=int, default=0, help="the fixed camera: this path frame")
    # backlit:seed=201, camera at path frame 0 looking +z: until ~13.75 h the sun does not reach into the room;
    # from 14 h it falls through the opening behind the camera onto the floor behind and below the view
    # (14-15.75 h), at 16 h the patch reaches the bottom of the front view.
    ap.add_argument("--backlit-times", default="12:16:17", help="T0:T1:COUNT hours (inclusive), or t,t,t")
    ap.add_argument("--strip-columns", type=int, default=6, help="frames shown in each image strip")
    ap.add_argument("--speed-frames", type=int, default=5, help="test frames timed with ngi lightmap")
    ap.add_argument("--repeats", type=int, default=5, help="ngi_bench generator --repeats")
    ap.add_argument("--redo-speed", action="store_true", help="time again even when timings are stored")
    args = ap.parse_args(argv)

    t_start = time.monotonic()
    ngi = ngi_paths.find_ngi(args.ngi)
    bench = args.bench or str(Path(ngi).parent / "perf" / "ngi_bench")
    if not os.access(bench, os.X_OK):
        raise SystemExit(f"{bench}: not found (build it: ninja -C {Path(ngi).parent} ngi_bench, or pass --bench)")
    out = Path(args.out).resolve()
    work = Path(args.work).resolve() if args.work else ngi_paths.REPO / "out" / "report"
    out.mkdir(parents=True, exist_ok=True)
    work.mkdir(parents=True, exist_ok=True)
    ds_cfg = data.read_dataset_config(args.dataset)
    if ds_cfg is None:
        raise SystemExit(f"{args.dataset}/dataset.json: missing (the report needs N and the spp the dataset used)")
    settings = {k: ds_cfg[k] for k in ("n", "reference_spp", "feature_spp", "max_bounces", "rr_start")}
    if settings["rr_start"] != 2:
        log(f"warning: the dataset used rr_start {settings['rr_start']}; ngi render always uses 2")
    models = {}
    for v, p in (("surround", args.surround), ("single_view", args.single_view)):
        cfg = model_file.read_config(p)
        models[v] = {"path": str(Path(p).resolve()), "digest": file_digest(p), "config": cfg}
        want = 12 if v == "surround" else 10
        if cfg.get("input_nc") != want:
            raise SystemExit(f"{p}: input_nc {cfg.get('input_nc')}, expected {want} for --{v.replace('_', '-')}")
    log(f"report: ngi {ngi}, dataset {args.dataset} (N = {settings['n']}, {settings['reference_spp']} spp), "
        f"work {work}, out {out}")

    checks = check_held_out(args, models, ds_cfg, sequence_specs(args))
    devices = ngi_devices(ngi)
    has_gpu = "[gpu]" in devices
    heldout_result = heldout(args, ngi, models, work)
    seqs = sequences(args, ngi, models, work, settings)
    speed_result = speed(args, ngi, bench, models, work, settings, heldout_result)
    dev = speed_result["surround"]["device"]
    device_name = dev.get("name", "?") if isinstance(dev, dict) else str(dev)
    speed_device = f"{dev.get('platform', 'OpenCL')} on {device_name}" if isinstance(dev, dict) else device_name
    gpu_note = ("A GPU was listed by `ngi devices`; the timings are on the device named above." if has_gpu else
                "No GPU was available to this run (`ngi devices` lists only the CPU): every timing is PoCL on the "
                "2-core CPU; the thesis's 3-4 ms (Table 5.4) were on GTX 1050 Ti / 1660 Ti GPUs at 1024 x 512.")

    log("== figures")
    plot_families(heldout_result, out / "heldout_families.png")
    for seq in seqs:
        plot_sequence(seq, out / f"{seq['name']}_plot.png")
        plot_strip(seq, out / f"{seq['name']}_strip.png", args.strip_columns)
    plot_speed(speed_result, heldout_result, out / "speed_accuracy.png", device_name)

    git = subprocess.run(["git", "-C", str(ngi_paths.REPO), "rev-parse", "HEAD"], capture_output=True, text=True)
    res = {
        "environment": {"date": datetime.datetime.now().isoformat(timespec="seconds"), "ngi": ngi, "bench": bench,
                        "git_commit": git.stdout.strip(), "ngi_devices": devices, "has_gpu": has_gpu,
                        "speed_device": speed_device, "gpu_note": gpu_note, "loadavg_end": os.getloadavg(),
                        "seconds": None},
        "arguments": vars(args),
        "checks": checks,
        "dataset": {"path": str(Path(args.dataset).resolve()), "config": ds_cfg},
        "settings": settings,
        "models": {v: {"path": m["path"], "sha1_12": m["digest"],
                       "config": {k: x for k, x in m["config"].items() if k != "training"},
                       "training": {k: m["config"].get("training", {}).get(k) for k in
                                    ("steps", "epochs", "frames", "wall_seconds", "bn_mode_selection")}}
                   for v, m in models.items()},
        "heldout": heldout_result,
        "thesis_table_5_3": THESIS_TABLE_5_3,
        "sequences": seqs,
        "speed": speed_result,
    }
    res["environment"]["seconds"] = time.monotonic() - t_start
    docs = ngi_paths.REPO / "docs"

    def link(name):
        return os.path.relpath(out / name, docs)

    md = markdown(res, link)
    (out / "tables.md").write_text(md + "\n")
    write_json(out / "results.json", repo_relative(res))
    print(md)
    log(f"report: done in {tqdm.format_interval(time.monotonic() - t_start)}: {out}/tables.md, results.json, "
        f"{len(list(out.glob('*.png')))} PNGs")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        log("\nreport: interrupted; the same command resumes (finished frames are kept)")
        sys.exit(130)

#!/usr/bin/python3
"""Issue 47: GI as an application displays it -- at display resolution, stable from frame to frame.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.display_eval \\
        --vox-dir ../shared/scenes/vox --work runs/display --out docs/results/display [--stages static,heldout,moving,sun]

Every frame is rendered with engine inputs (docs/RESULTS.md, issue 45): the N = 64 cluster with a converged direct
feature (1024 spp), and the front view again at display resolution S (its own G-buffer: albedo, normals, depth and a
256-spp direct feature, as an engine's full-resolution direct light) with a 256-spp path-traced reference of S x S.
Each rung (engine_eval's names: direct_only, the ssgi rungs, the networks) runs through ngi's pipeline at N = 64;
its lightmap is brought to S x S three ways:
  upscaled        the whole N x N lightmap resized bilinearly and composed with the display's albedo and emission
                  (ngi.scoring's way, what `--size` gave users),
  bilinear        ngi.DisplayView(upsampler="bilinear", temporal=False): the indirect part (lightmap - direct) resized
                  bilinearly, the display's own direct light added,
  jbu             ngi.DisplayView(temporal=False): the indirect part joint-bilaterally upsampled (radius 2: 4 x 4 taps),
  jbu_r1          the same with radius 1 (2 x 2 taps, a quarter of the cost; static frames only),
  jbu_temporal    ngi.DisplayView(): the same, accumulated over frames (sequences only).
Stages:
  static  frame 50 of the orbit path of every .vox file of --vox-dir (evaluation only; read from there, never copied),
          S = 512: final PSNR / SSIM (tone-mapped, data range 1) and lightmap PSNR against the 512^2 reference.
  heldout the same at frame 50 of the eight held-out test scenes of configs/dataset_gi_n64.json (HELDOUT).
  moving  path frames 39-62 of room:seed=204 (this project's own scene; ladder_eval's moving-camera sequence), S = 256:
          quality per frame and the warping error (ngi.temporal, the display's depth and cameras) against the
          reference's own.
  sun     backlit:seed=201 with a fixed camera, 12.00-16.00 h in 0.25 h steps (ladder_eval's moving-sun sequence),
          S = 256: the per-frame error curve with and without accumulation and the lag of the accumulated light (the
          frame shift k that best matches the unaccumulated sequence shifted by k).
Costs: perf/display_cost.py. Results: WORK/display_eval.json (per frame; a rerun redoes only what is missing, renders are kept), OUT/display.json
(summary), OUT/display_tables.md, OUT/display_strip.png.
"""

import argparse
import datetime
import json
import sys
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.plan as plan
import ngi.scoring as scoring
import ngi.temporal as temporal

from ngi_train import ngi_paths
from ngi_train.generator import engine_eval

DEFAULT_RUNGS = "direct_only,ssgi_surround_n64,gi_surround_n64_ngf16"
N = 64
STATIC = {"frame": 50, "path_frames": 100, "size": 512}
# The held-out test scenes of configs/dataset_gi_n64.json (issue 25's test split; never trained on), one hour each
# where the split has several: the same static protocol as the .vox files.
HELDOUT = [("room:seed=101", None), ("room:seed=102", 16.0), ("street:seed=101", 10.0), ("cave:seed=101", None),
           ("backlit:seed=101", None), ("bleed:seed=101", None), ("sculpture:seed=101", None),
           ("cornell_pink:seed=101", None)]
STATIC_SECTIONS = {"static": ("../shared/scenes/vox/ files", "display_strip.png"),
                   "heldout": ("the held-out test scenes of configs/dataset_gi_n64.json", "display_strip_heldout.png")}
MOVING = {"scene": "room:seed=204", "frames": list(range(39, 63)), "path_frames": 100, "size": 256}
SUN = {"scene": "backlit:seed=201", "frame": 0, "times": [12.0 + 0.25 * k for k in range(17)], "size": 256}
SPP = {"low_feature": 1024, "display_feature": 256, "reference": 256}
METHODS_STATIC = ("upscaled", "bilinear", "jbu", "jbu_r1")
METHODS_SEQ = ("upscaled", "bilinear", "jbu", "jbu_temporal")


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def render(ngi_bin, scene, out, face, feature_spp, reference_spp=None, frame=0, path_frames=100, time=None,
           device="pocl"):
    """`ngi render` of one frame (kept: a folder with render.json is not rendered again)."""
    if (out / "render.json").is_file():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    cmd = [ngi_bin, "render", "--scene", scene, "--frame", frame, "--path-frames", path_frames, "--face", face,
           "--feature-spp", feature_spp, "--out", out, "--device", device]
    cmd += ["--spp", reference_spp] if reference_spp else ["--no-reference"]
    if time is not None:
        cmd += ["--time", time]
    ngi_paths.run([str(c) for c in cmd])
    return out


def camera_of(folder):
    """(position, look, up): render.json records the position, camera.json the look and up the frame is read with."""
    cam = json.loads((folder / "render.json").read_text())["camera"]
    frame_cam = json.loads((folder / "camera.json").read_text())
    return tuple(cam["position"]), tuple(frame_cam["look"]), tuple(frame_cam["up"])


class Runner:
    """The rungs at N = 64 (ngi.plan's Evaluator) and the display views, per display size."""

    def __init__(self, device, rungs):
        self.device = device
        self.rungs = rungs
        self.ev = plan.Evaluator(device, None)
        self.pipes = {}

    def pipe(self, n):
        if n not in self.pipes:
            self.pipes[n] = ngi.Pipeline(self.device, n)
        return self.pipes[n]

    def lightmap(self, rung, low):
        if rung["kind"] == "direct":
            return np.asarray(low.feature("direct")[0], np.float32)
        return self.ev.lightmap(rung, {N: low})

    def view(self, size, method):
        if method == "bilinear":
            return ngi.DisplayView(self.device, size, upsampler="bilinear", temporal=False)
        if method == "jbu_r1":  # the 2 x 2 tap window: a quarter of the default's taps (the speed trade)
            return ngi.DisplayView(self.device, size, temporal=False, radius=1)
        return ngi.DisplayView(self.device, size, temporal=method == "jbu_temporal")


def display_lightmap(runner, views, method, low, hi, lightmap, position):
    """The S x S linear lightmap of one method."""
    if method == "upscaled":
        return scoring.upsample(scoring._clean_light(lightmap), hi.n)
    return views[method].run(low, lightmap, hi, position, outputs=("lightmap",))["lightmap"]


def score(ref, lightmap_s):
    s = ref.score(lightmap_s)
    return {"psnr": s["final"]["psnr"], "ssim": s["final"]["ssim"], "lightmap_psnr": s["lightmap"]["psnr"]}, s["display"]


# --------------------------------------------------------------------------
# static: .vox files at 512^2
# --------------------------------------------------------------------------

def static_jobs(args, section):
    """(the `ngi render --scene` argument, the frame's key stem, the hour or None) of a static section."""
    if section == "static":
        return [(f, f.stem, None) for f in sorted(Path(args.vox_dir).glob("*.vox"))]
    return [(spec, spec.replace(":", "_").replace("=", ""), hour) for spec, hour in HELDOUT]


def static_stage(args, runner, cache, work, ngi_bin, section="static"):
    rows = cache.setdefault(section, {})
    strip = None
    folder = "vox" if section == "static" else section
    strip_file = args.strip_file if section == "static" else args.heldout_strip_file
    for scene, stem, hour in tqdm.tqdm(static_jobs(args, section), desc=f"{section} (512^2)", unit="scene",
                                       **ngi_paths.progress_options()):
        key = f"{stem}_f{STATIC['frame']}"
        lo_dir = render(ngi_bin, scene, work / folder / f"{key}_{N}", N, SPP["low_feature"], SPP["low_feature"],
                        STATIC["frame"], STATIC["path_frames"], time=hour, device=args.render_device)
        hi_dir = render(ngi_bin, scene, work / folder / f"{key}_{STATIC['size']}", STATIC["size"],
                        SPP["display_feature"], SPP["reference"], STATIC["frame"], STATIC["path_frames"], time=hour,
                        device=args.render_device)
        need = [r for r in runner.rungs if not all(m in rows.get(key, {}).get(r["name"], {}) for m in METHODS_STATIC)]
        if not need and strip is not None:
            continue
        low, hi = ngi.read_frame(str(lo_dir)), ngi.read_frame(str(hi_dir))
        if float(np.max(hi.reference)) <= 0.0:
            log(f"display_eval: {key}: all-zero reference, skipped")
            continue
        position = camera_of(hi_dir)[0]
        ref = scoring.Reference(runner.device, runner.pipe(STATIC["size"]), hi)
        views = {m: runner.view(STATIC["size"], m) for m in METHODS_STATIC if m != "upscaled"}
        shown = {}
        for r in runner.rungs:
            lm = runner.lightmap(r, low)
            for m in METHODS_STATIC:
                s, disp = score(ref, display_lightmap(runner, views, m, low, hi, lm, position))
                rows.setdefault(key, {}).setdefault(r["name"], {})[m] = s
                shown[(r["name"], m)] = disp
        if strip is None or key.startswith(strip_file):
            strip = (key, shown, ref.final)
        save(cache, work)
    return strip


# --------------------------------------------------------------------------
# sequences: moving camera, moving sun
# --------------------------------------------------------------------------

def sequence(args, runner, work, ngi_bin, name, spec, frames):
    """Per rung and method: per-frame scores and the tone-mapped finals; the cameras, depths and the reference's
    tone-mapped finals."""
    lows, his, cams = [], [], []
    for k, kw in enumerate(tqdm.tqdm(frames, desc=f"{name}: render", unit="frame", **ngi_paths.progress_options())):
        lows.append(render(ngi_bin, spec["scene"], work / name / f"{k:03d}_{N}", N, SPP["low_feature"], None,
                           device=args.render_device, **kw))
        his.append(render(ngi_bin, spec["scene"], work / name / f"{k:03d}_{spec['size']}", spec["size"],
                          SPP["display_feature"], SPP["reference"], device=args.render_device, **kw))
        cams.append(camera_of(his[-1]))
    out = {"cameras": cams, "depths": [], "reference": [], "runs": {}}
    pipe = runner.pipe(spec["size"])
    for r in runner.rungs:
        views = {m: runner.view(spec["size"], m) for m in METHODS_SEQ if m != "upscaled"}
        for m in METHODS_SEQ:
            out["runs"].setdefault(r["name"], {})[m] = {"scores": [], "finals": []}
        for k in tqdm.trange(len(frames), desc=f"{name}: {r['name']}", unit="frame", **ngi_paths.progress_options()):
            low, hi = ngi.read_frame(str(lows[k])), ngi.read_frame(str(his[k]))
            ref = scoring.Reference(runner.device, pipe, hi)
            if r is runner.rungs[0]:
                out["depths"].append(np.asarray(hi.feature("depth")[0][0], np.float64))
                out["reference"].append(ref.final)
            lm = runner.lightmap(r, low)
            for m in METHODS_SEQ:
                s, disp = score(ref, display_lightmap(runner, views, m, low, hi, lm, cams[k][0]))
                out["runs"][r["name"]][m]["scores"].append(s)
                out["runs"][r["name"]][m]["finals"].append(disp)
    return out


def flicker(seq):
    masks = temporal.warp_masks(seq["depths"], seq["cameras"])
    ref_err, share = temporal.warp_error(seq["reference"], masks)
    rows = {}
    for rung, methods in seq["runs"].items():
        for m, run in methods.items():
            err, _ = temporal.warp_error(run["finals"], masks)
            rows.setdefault(rung, {})[m] = {
                "psnr": float(np.mean([s["psnr"] for s in run["scores"]])),
                "ssim": float(np.mean([s["ssim"] for s in run["scores"]])),
                "warp_error": err, "warp_ratio": err / ref_err,
                "psnr_per_frame": [s["psnr"] for s in run["scores"]]}
    return {"reference_warp_error": ref_err, "valid_share": share, "rows": rows}


def lag_frames(accumulated, plain, max_shift=8):
    """The shift k (frames) that best matches accumulated[t] with plain[t - k] (mean |difference| over t >= k)."""
    best, best_k = None, 0
    for k in range(0, min(max_shift, len(plain) - 2) + 1):
        d = float(np.mean([np.mean(np.abs(accumulated[t] - plain[t - k])) for t in range(k, len(plain))]))
        if best is None or d < best:
            best, best_k = d, k
    return best_k


# --------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------

def save(cache, work):
    p = work / "display_eval.json"
    p.write_text(json.dumps(cache, indent=1))


def summarize_static(rows, rungs):
    out = {}
    for r in rungs:
        per = [rows[k][r["name"]] for k in sorted(rows) if r["name"] in rows[k]]
        out[r["name"]] = {m: {"psnr": float(np.mean([p[m]["psnr"] for p in per])),
                              "ssim": float(np.mean([p[m]["ssim"] for p in per])),
                              "lightmap_psnr": float(np.mean([p[m]["lightmap_psnr"] for p in per])),
                              "frames": len(per)} for m in METHODS_STATIC}
        out[r["name"]]["jbu_minus_upscaled"] = {
            "psnr": out[r["name"]]["jbu"]["psnr"] - out[r["name"]]["upscaled"]["psnr"],
            "ssim": out[r["name"]]["jbu"]["ssim"] - out[r["name"]]["upscaled"]["ssim"],
            "frames_jbu_better_psnr": int(sum(p["jbu"]["psnr"] > p["upscaled"]["psnr"] for p in per))}
    return out


def tables(summary):
    lines = ["# Display resolution and temporal stability (issue 47)", "",
             f"Generated by `python3 -m ngi_train.generator.display_eval` on {summary['date']}. Engine inputs; N = 64.", ""]
    for section, (label, _) in STATIC_SECTIONS.items():
        if section not in summary:
            continue
        lines += [f"## Static frames at 512^2: frame 50 of {label} "
                  f"({next(iter(summary[section].values()))['jbu']['frames']} frames)", "",
                  "| rung | method | final PSNR | SSIM | lightmap PSNR |", "| --- | --- | --- | --- | --- |"]
        for rung, ms in summary[section].items():
            for m in METHODS_STATIC:
                v = ms[m]
                lines.append(f"| {rung} | {m} | {v['psnr']:.2f} | {v['ssim']:.4f} | {v['lightmap_psnr']:.2f} |")
        lines.append("")
    for name in ("moving", "sun"):
        if name not in summary:
            continue
        s = summary[name]
        lines += [f"## {s['label']}", "",
                  f"Reference's own warping error {s['reference_warp_error']:.5f} (share of pixels compared "
                  f"{s['valid_share']:.2f}).", "",
                  "| rung | method | final PSNR | SSIM | warping error | / reference's |" +
                  (" lag (frames) |" if name == "sun" else ""),
                  "| --- | --- | --- | --- | --- | --- |" + (" --- |" if name == "sun" else "")]
        for rung, ms in s["rows"].items():
            for m, v in ms.items():
                lag = f" {s['lag'].get(rung, {}).get(m, '')} |" if name == "sun" else ""
                lines.append(f"| {rung} | {m} | {v['psnr']:.2f} | {v['ssim']:.4f} | {v['warp_error']:.5f} | "
                             f"{v['warp_ratio']:.2f} |{lag}")
        lines.append("")
    return "\n".join(lines) + "\n"


def draw_strip(strip, out_png, rung_names):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    key, shown, ref = strip
    cols = [("direct_only", "jbu", "direct light")]
    for name in rung_names:
        if name != "direct_only":
            cols += [(name, "upscaled", f"{name}\nupscaled 64²"), (name, "jbu", f"{name}\nJBU 512²")]
    fig, axes = plt.subplots(1, len(cols) + 1, figsize=(3.2 * (len(cols) + 1), 3.6))
    for ax, (rung, m, title) in zip(axes, cols):
        ax.imshow(np.clip(np.transpose(shown[(rung, m)], (1, 2, 0)), 0, 1))
        ax.set_title(title, fontsize=8)
        ax.axis("off")
    axes[-1].imshow(np.clip(np.transpose(ref, (1, 2, 0)), 0, 1))
    axes[-1].set_title("reference 512²", fontsize=8)
    axes[-1].axis("off")
    fig.suptitle(f"{key} (engine inputs)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vox-dir", default="../shared/scenes/vox")
    ap.add_argument("--work", type=Path, default=Path("runs/display"))
    ap.add_argument("--out", type=Path, default=Path("docs/results/display"))
    ap.add_argument("--rungs", default=DEFAULT_RUNGS)
    ap.add_argument("--zoo", default="models/zoo.json")
    ap.add_argument("--stages", default="static,heldout,moving,sun")
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--render-device", default="pocl")
    ap.add_argument("--ngi", default=None)
    ap.add_argument("--strip-file", default="monu0")
    ap.add_argument("--heldout-strip-file", default="bleed_seed101")
    args = ap.parse_args(argv)
    stages = args.stages.split(",")
    args.work.mkdir(parents=True, exist_ok=True)
    args.out.mkdir(parents=True, exist_ok=True)
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    device = ngi.Device(args.device)
    rungs = engine_eval.resolve_rungs(args.rungs.split(","), args.zoo)
    runner = Runner(device, rungs)
    cache_path = args.work / "display_eval.json"
    cache = json.loads(cache_path.read_text()) if cache_path.is_file() else {}
    summary_path = args.out / "display.json"
    summary = json.loads(summary_path.read_text()) if summary_path.is_file() else {}
    summary["date"] = datetime.date.today().isoformat()
    summary["settings"] = {"n": N, "spp": SPP, "static": STATIC, "moving": MOVING,
                           "sun": {k: v for k, v in SUN.items()}, "rungs": [r["name"] for r in rungs],
                           "display_view_defaults": {"blend": 0.2, "clip_margin": 0.25, "sigma_spatial": 0.75,
                                                     "normal_power": 32, "sigma_plane": 0.1, "radius": 2}}
    summary["settings"]["heldout"] = HELDOUT
    for section, (_, strip_png) in STATIC_SECTIONS.items():
        if section not in stages:
            continue
        strip = static_stage(args, runner, cache, args.work, ngi_bin, section)
        summary[section] = summarize_static(cache[section], rungs)
        if strip:
            draw_strip(strip, args.out / strip_png, [r["name"] for r in rungs])
    if "moving" in stages:
        seq = sequence(args, runner, args.work, ngi_bin, "moving", MOVING,
                       [{"frame": f, "path_frames": MOVING["path_frames"]} for f in MOVING["frames"]])
        summary["moving"] = flicker(seq)
        summary["moving"]["label"] = (f"Moving camera: {MOVING['scene']}, path frames {MOVING['frames'][0]}-"
                                      f"{MOVING['frames'][-1]} of 100, display {MOVING['size']}^2")
    if "sun" in stages:
        seq = sequence(args, runner, args.work, ngi_bin, "sun", SUN,
                       [{"frame": SUN["frame"], "time": t} for t in SUN["times"]])
        summary["sun"] = flicker(seq)
        summary["sun"]["label"] = (f"Moving sun: {SUN['scene']}, fixed camera, {SUN['times'][0]:g}-"
                                   f"{SUN['times'][-1]:g} h, display {SUN['size']}^2")
        summary["sun"]["lag"] = {r: {"jbu_temporal": lag_frames(ms["jbu_temporal"]["finals"], ms["jbu"]["finals"])}
                                 for r, ms in seq["runs"].items()}
    summary_path.write_text(json.dumps(summary, indent=1))
    (args.out / "display_tables.md").write_text(tables(summary))
    log(f"display_eval: wrote {summary_path} and {args.out / 'display_tables.md'}")


if __name__ == "__main__":
    main()

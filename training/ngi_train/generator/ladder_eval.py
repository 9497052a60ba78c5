#!/usr/bin/python3
"""Evaluate the speed/accuracy ladder (training/ngi_train/generator/ladder.py) and write the model zoo manifest.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.ladder_eval --work runs/ladder \\
        --data 64=data/clean_n64 --data 32=data/clean_n32 --seq 64=data/seq_n64 --seq 32=data/seq_n32 \\
        --devices pocl,rusticl --out docs/results --zoo models/zoo.json

Every variant of every exported rung (the file as exported; the other batch-norm mode; F32 weights), the two
generators shipped before the ladder, and the direct-light-only rung are measured the same way:

1. held-out: every frame of the N = 64 dataset's test split (scenes in no training set) through ngi (Python
   bindings, the library's pipeline), scored with ngi.scoring against the converged reference; N = 32 rungs get
   the same frame rendered at N = 32 and their lightmap upsampled (ngi.scoring's doc).
2. temporal (ngi.temporal): a moving camera (the --seq datasets' room:seed=204, path frames 39-81, exact
   reprojection from scene.json's cameras) and a fixed camera under a moving sun (backlit:seed=201, 12-16 h,
   rendered here): per-frame quality, MABD and warping error, each beside the reference's own.
3. speed, per OpenCL device: the generator alone (ngi_bench generator, median of R runs after a warm-up: GFLOP,
   device memory) and the whole `ngi lightmap` command (median wall time over K test frames after a warm-up).
4. the per-frame switch: ngi.outside_light_share of every held-out frame; for each surround-aware rung and its
   single-view twin (same N and width), quality and time when frames below a threshold run the single view.

Results: WORK/ladder.json (all of it), OUT/ladder.json (summary), OUT/ladder_*.png, OUT/ladder_tables.md, and the
zoo manifest (--zoo). Each stage caches its results in WORK (keyed by the model files' digests), so a rerun or an
interrupted run only measures what is missing.
"""

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import tqdm

import ngi
import ngi.model_file as model_file
import ngi.scoring as scoring
import ngi.temporal as temporal
import ngi.zoo as zoo_mod

from ngi_train import ngi_paths
from ngi_train.generator import ladder as ladder_mod, ladder_report

REPO = ngi_paths.REPO
MOVING_CAMERA = {"scene": "room_seed204", "frames": list(range(39, 82))}
MOVING_SUN = {"spec": "backlit:seed=201", "frame": 0, "times": [12.0 + 0.25 * k for k in range(17)]}
LEGACY = [("shipped_surround_n64_ngf32", "models/surround.safetensors", "surround", 7),
          ("shipped_single_view_n64_ngf32", "models/single_view.safetensors", "single_view", 6)]


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def digest(path):
    return zoo_mod.sha256(path)


def read_json(path, default=None):
    return json.loads(Path(path).read_text()) if Path(path).is_file() else default


def write_json(path, obj):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(obj, indent=1) + "\n")
    tmp.replace(path)


def rel(path):
    """A path relative to the repository; outside it, only its last two components (no machine paths in the
    recorded results)."""
    try:
        return str(Path(path).resolve().relative_to(REPO))
    except ValueError:
        return str(Path("<outside the repository>", *Path(path).parts[-2:]))


# --------------------------------------------------------------------------
# Variants
# --------------------------------------------------------------------------

def variants(ladder, work):
    """Every measured variant: {name, kind, file, bn_mode, weights, layout, n, ngf, num_downs, ...}."""
    out = [{"name": "direct_only", "kind": "direct", "layout": "none", "n": 64, "ngf": 0, "file": None,
            "bn_mode": None, "weights": None, "digest": "direct"}]
    for rung in ladder["rungs"]:
        half, fp32 = ladder_mod.export_paths(rung, work)
        if not half.is_file():
            log(f"ladder_eval: {rung['name']} is not exported yet: skipped")
            continue
        file_bn = model_file.read_config(str(half))["bn_mode"]
        other = "running" if file_bn == "per_image" else "per_image"
        base = {"rung": rung["name"], "layout": rung["layout"], "n": rung["n"], "ngf": rung["ngf"],
                "num_downs": rung["num_downs"], "seed": rung.get("seed", ladder["recipe"]["seed"]),
                "shipped": bool(rung.get("ship"))}
        out.append({**base, "name": rung["name"], "kind": "rung", "file": half, "bn_mode": file_bn, "weights": "f16"})
        out.append({**base, "name": f"{rung['name']}@{other}", "kind": "bn_variant", "file": half, "bn_mode": other,
                    "weights": "f16"})
        if fp32.is_file():
            out.append({**base, "name": f"{rung['name']}@f32", "kind": "f32_variant", "file": fp32,
                        "bn_mode": file_bn, "weights": "f32", "shipped": False})
    for name, path, layout, downs in LEGACY:
        path = REPO / path
        if path.is_file():
            out.append({"name": name, "kind": "legacy", "rung": name, "layout": layout, "n": 64, "ngf": 32,
                        "num_downs": downs, "seed": 1, "shipped": True, "file": path,
                        "bn_mode": model_file.read_config(str(path))["bn_mode"], "weights": "f16"})
    for v in out:
        if v["file"] is not None:
            v["digest"] = digest(v["file"])[:16] + ("" if v["kind"] != "bn_variant" else "-" + v["bn_mode"])
    return out


class Runner:
    """Models and pipelines on one device, loaded once."""

    def __init__(self, device):
        self.device = device
        self.models, self.pipes = {}, {}

    def pipe(self, n):
        if n not in self.pipes:
            self.pipes[n] = ngi.Pipeline(self.device, n)
        return self.pipes[n]

    def lightmap(self, v, frames_by_n, want_final=False):
        """The variant's front lightmap [3, n, n] for one frame (frames_by_n: face size -> ngi.Frame)."""
        if v["kind"] == "direct":
            return frames_by_n[v["n"]].feature("direct")[0], None
        if v["name"] not in self.models:
            self.models[v["name"]] = ngi.Model(self.device, str(v["file"]), bn_mode=v["bn_mode"])
        outputs = ("lightmap", "final") if want_final else ("lightmap",)
        out = self.pipe(v["n"]).run(self.models[v["name"]], frames_by_n[v["n"]], outputs=outputs)
        return out["lightmap"], out.get("final")


def frame_pair(data, rel_dir, ns):
    """The frame at every face size in ns (data: N -> dataset folder)."""
    return {n: ngi.read_frame(str(data[n] / rel_dir)) for n in ns}


# --------------------------------------------------------------------------
# 1. Held-out
# --------------------------------------------------------------------------

def test_frames(dataset):
    out = []
    for scene in sorted((dataset / "test").iterdir()):
        if scene.is_dir():
            out += [f"test/{scene.name}/{f.name}" for f in sorted(scene.iterdir()) if (f / "camera.json").is_file()]
    return out


def family(rel_dir):
    return rel_dir.split("/")[1].split("_seed")[0]


def heldout(args, runner, vs, work):
    cache_path = work / "heldout.json"
    cache = read_json(cache_path, {})
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]]
    frames = test_frames(args.data[64])
    if args.max_frames:
        frames = frames[:args.max_frames]
    if todo:
        ns = sorted({v["n"] for v in todo} | {64})
        rows = {v["name"]: [] for v in todo}
        checked = False
        for rel_dir in tqdm.tqdm(frames, desc=f"held-out ({len(todo)} variants)", unit="frame",
                                 **ngi_paths.progress_options()):
            fr = frame_pair(args.data, rel_dir, ns)
            ref = scoring.Reference(runner.device, runner.pipe(64), fr[64])
            share = ngi.outside_light_share(fr[64])
            for v in todo:
                want_final = not checked and v["n"] == 64 and v["kind"] != "direct"
                lm, final = runner.lightmap(v, fr, want_final)
                if want_final:  # scoring's composition is the pipeline's
                    mine = scoring.compose(fr[64], lm)
                    err = float(np.max(np.abs(mine - final) / (1e-3 + np.abs(final))))
                    if err > 1e-5:
                        raise RuntimeError(f"scoring.compose differs from the pipeline's final image by {err}")
                    checked = True
                s = ref.score(lm)
                rows[v["name"]].append({"frame": rel_dir, "family": family(rel_dir), "outside_light_share": share,
                                        "final": s["final"], "lightmap": s["lightmap"]})
        for v in todo:
            cache[v["name"]] = {"digest": v["digest"], "frames": rows[v["name"]]}
        write_json(cache_path, cache)
    return {v["name"]: cache[v["name"]]["frames"] for v in vs}


def summarize_frames(rows):
    mean = lambda key, m: float(np.mean([r[key][m] for r in rows]))
    out = {"frames": len(rows),
           "final": {m: mean("final", m) for m in ("ssim", "psnr", "mse")},
           "lightmap": {m: mean("lightmap", m) for m in ("ssim", "psnr", "mse")}, "families": {}}
    for fam in sorted({r["family"] for r in rows}):
        sub = [r for r in rows if r["family"] == fam]
        out["families"][fam] = {"frames": len(sub), "ssim": float(np.mean([r["final"]["ssim"] for r in sub])),
                                "psnr": float(np.mean([r["final"]["psnr"] for r in sub]))}
    return out


# --------------------------------------------------------------------------
# 2. Temporal sequences
# --------------------------------------------------------------------------

def render_sun_sequence(args, work):
    """The fixed-camera, moving-sun sequence at N = 64 (with converged references) and 32 (features only)."""
    ngi_bin = ngi_paths.find_ngi(args.ngi)
    spp = read_json(args.data[64] / "dataset.json")
    ref_spp = spp.get("test_reference_spp") or spp["reference_spp"]
    dirs = {64: [], 32: []}
    for n in (64, 32):
        for k, t in enumerate(MOVING_SUN["times"]):
            d = work / f"sun_n{n}" / f"{k:04d}"
            dirs[n].append(d)
            if (d / "camera.json").is_file():
                continue
            d.parent.mkdir(parents=True, exist_ok=True)
            cmd = [ngi_bin, "render", "--scene", MOVING_SUN["spec"], "--frame", MOVING_SUN["frame"], "--time", t,
                   "--face", n, "--spp", ref_spp, "--feature-spp", spp["feature_spp"], "--bounces",
                   spp["max_bounces"], "--out", d, "--device", args.render_device]
            if n != 64:
                cmd.append("--no-reference")
            ngi_paths.run(cmd)
    return dirs


def sequence_frames(args, work):
    """{sequence: {"frames": {n: [ngi.Frame]}, "cameras": [(position, look, up)], "label": ...}}"""
    seqs = {}
    info = read_json(args.seq[64] / "test" / MOVING_CAMERA["scene"] / "scene.json")
    cams, frames = [], {64: [], 32: []}
    for f in MOVING_CAMERA["frames"]:
        fi = info["frame_info"][f]
        cams.append((fi["position"], fi["look"], fi["up"]))
        for n in (64, 32):
            if n in args.seq:
                frames[n].append(ngi.read_frame(str(args.seq[n] / "test" / MOVING_CAMERA["scene"] / f"{f:04d}")))
    seqs["moving_camera"] = {"frames": frames, "cameras": cams,
                             "label": f"room:seed=204, path frames {MOVING_CAMERA['frames'][0]}-"
                                      f"{MOVING_CAMERA['frames'][-1]} of 100, 11.02 h, moving camera"}
    dirs = render_sun_sequence(args, work)
    frames = {n: [ngi.read_frame(str(d)) for d in dirs[n]] for n in dirs}
    f0 = frames[64][0]
    seqs["moving_sun"] = {"frames": frames, "cameras": [((0.0, 0.0, 0.0), f0.look, f0.up)] * len(frames[64]),
                          "label": f"{MOVING_SUN['spec']}, path frame 0, {MOVING_SUN['times'][0]:g}-"
                                   f"{MOVING_SUN['times'][-1]:g} h, fixed camera"}
    return seqs


def temporal_stage(args, runner, vs, work):
    cache_path = work / "temporal.json"
    cache = read_json(cache_path, {})
    todo = [v for v in vs if cache.get(v["name"], {}).get("digest") != v["digest"]]
    if not todo:
        return {v["name"]: cache[v["name"]]["sequences"] for v in vs}
    seqs = sequence_frames(args, work)
    results = {v["name"]: {} for v in todo}
    for sname, seq in seqs.items():
        refs = [scoring.Reference(runner.device, runner.pipe(64), f) for f in seq["frames"][64]]
        depths = [f.feature("depth")[0][0] for f in seq["frames"][64]]
        masks = temporal.warp_masks(depths, seq["cameras"])
        ref_disp = [r.final for r in refs]
        ref_t = {"mabd": temporal.mabd(ref_disp), "warp": temporal.warp_error(ref_disp, masks)[0],
                 "brightness": [float(np.mean(d)) for d in ref_disp],
                 "outside_light_share": [ngi.outside_light_share(f) for f in seq["frames"][64]]}
        for v in tqdm.tqdm(todo, desc=f"temporal {sname}", unit="variant", **ngi_paths.progress_options()):
            shown, per = [], []
            for k in range(len(refs)):
                lm, _ = runner.lightmap(v, {n: seq["frames"][n][k] for n in seq["frames"] if seq["frames"][n]})
                s = refs[k].score(lm)
                shown.append(s["display"])
                per.append({"ssim": s["final"]["ssim"], "psnr": s["final"]["psnr"]})
            warp, valid = temporal.warp_error(shown, masks)
            results[v["name"]][sname] = {
                "label": seq["label"], "frames": len(refs),
                "ssim": float(np.mean([p["ssim"] for p in per])), "psnr": float(np.mean([p["psnr"] for p in per])),
                "mabd": temporal.mabd(shown), "mabd_reference": ref_t["mabd"],
                "warp_error": warp, "warp_error_reference": ref_t["warp"], "warp_valid_share": valid,
                "brightness": [float(np.mean(d)) for d in shown], "brightness_reference": ref_t["brightness"],
                "outside_light_share": ref_t["outside_light_share"], "per_frame": per}
    for v in todo:
        cache[v["name"]] = {"digest": v["digest"], "sequences": results[v["name"]]}
    write_json(cache_path, cache)
    return {v["name"]: cache[v["name"]]["sequences"] for v in vs}


# --------------------------------------------------------------------------
# 3. Speed
# --------------------------------------------------------------------------

def device_env(device):
    env = ngi_paths.ngi_env()
    if device == "rusticl":
        env["RUSTICL_ENABLE"] = "llvmpipe"
    return env


def run_timed(cmd, env):
    t0 = time.monotonic()
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
    return proc, (time.monotonic() - t0) * 1e3


def speed_stage(args, vs, work):
    """Per device: generator alone and the whole ngi lightmap command, for every variant that can differ in
    speed (F32 weights run as F32 like F16 ones do: the loader widens F16 at load; not timed separately)."""
    cache_path = work / "speed.json"
    cache = read_json(cache_path, {})
    ngi_bin, bench = ngi_paths.find_ngi(args.ngi), str(Path(ngi_paths.find_ngi(args.ngi)).parent / "perf" / "ngi_bench")
    timed = [v for v in vs if v["kind"] in ("rung", "bn_variant", "legacy") and v.get("shipped")]
    for device in args.devices:
        env = device_env(device)
        # Mesa rusticl on llvmpipe runs the single-view N = 64 generator in ~11.6 s (PoCL: ~7 ms on the same CPU):
        # there only the rungs as exported, one timed run after the warm-up, one ngi lightmap frame.
        slow = device == "rusticl"
        repeats, walls_n = (args.repeats, args.lightmap_frames) if not slow else (1, 1)
        per = cache.setdefault(device, {})
        todo = [v for v in timed if per.get(v["name"], {}).get("digest") != v["digest"]
                and (not slow or v["kind"] == "rung")]
        for v in tqdm.tqdm(todo, desc=f"speed on {device}", unit="variant", **ngi_paths.progress_options()):
            n = v["n"]
            w, h = (4 * n, 2 * n) if v["layout"] == "surround" else (n, n)
            b = json.loads(run_timed([bench, "generator", "--model", v["file"], "--width", w, "--height", h,
                                      "--repeats", repeats, "--device", device, "--bn-mode", v["bn_mode"]],
                                     env)[0].stdout)
            data_n = args.data[n]
            frames = test_frames(data_n)[::37][:walls_n]
            tmp = work / "speed_tmp"
            shutil.rmtree(tmp, ignore_errors=True)
            lm = lambda f, out: run_timed([ngi_bin, "lightmap", "--frame", data_n / f, "--model", v["file"],
                                           "--bn-mode", v["bn_mode"], "--out", out, "--device", device], env)[1]
            if not slow:  # (on rusticl the generator benchmark has just compiled and cached every kernel)
                lm(frames[0], tmp / "warmup")
            walls = [lm(f, tmp / str(k)) for k, f in enumerate(frames)]
            shutil.rmtree(tmp, ignore_errors=True)
            per[v["name"]] = {"digest": v["digest"], "device": b["device"], "input": [1, 12 if v["layout"] ==
                              "surround" else 10, h, w], "generator_ms": b["ms_median"], "generator_ms_all": b["ms_all"],
                              "gflop": b["gflop_total"], "memory_mib": b["memory_mib"], "repeats": repeats,
                              "lightmap_ms": float(np.median(walls)), "lightmap_ms_all": walls,
                              "loadavg": os.getloadavg(),
                              "measured": datetime.datetime.now().isoformat(timespec="seconds")}
            write_json(cache_path, cache)
    return {d: cache.get(d, {}) for d in args.devices}


# --------------------------------------------------------------------------
# 4. The per-frame switch
# --------------------------------------------------------------------------

OUTSIDE = 0.9  # frames with at least this outside light share count as lit from outside the front view
SWITCH_THRESHOLDS = [0.0, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 1.01]
SWITCH_TOLERANCE = {"ssim": 0.002, "psnr": 0.05}  # quality a switch may cost on the held-out frames


def switch_on_sequences(temp, sv, tw, t):
    """The switch at threshold t on the temporal sequences: mean SSIM / PSNR with and without it, frames switched."""
    out = {}
    for seq in ("moving_camera", "moving_sun"):
        a, b = (temp.get(sv) or {}).get(seq), (temp.get(tw) or {}).get(seq)
        if not a or not b:
            continue
        use = [x < t for x in a["outside_light_share"]]
        pick = [pb if u else pa for pa, pb, u in zip(a["per_frame"], b["per_frame"], use)]
        out[seq] = {"frames": len(use), "switched": int(sum(use)),
                    "ssim": float(np.mean([p["ssim"] for p in pick])), "psnr": float(np.mean([p["psnr"] for p in pick])),
                    "ssim_surround_only": a["ssim"], "psnr_surround_only": a["psnr"]}
    return out


def switch_stage(vs, held, speed, temp=None):
    """For each shipped surround rung with a single-view twin (same N and width): quality, and mean ms per device,
    when held-out frames whose outside light share is below t run the twin. The chosen t is the largest whose mean
    SSIM and PSNR stay within SWITCH_TOLERANCE of the surround rung alone (quality only, so one t for all
    devices)."""
    by = {(v["layout"], v["n"], v["ngf"]): v for v in vs if v["kind"] == "rung" and v.get("shipped")}
    out = []
    for (layout, n, ngf), sv in sorted(by.items()):
        if layout != "surround" or ("single_view", n, ngf) not in by or sv["name"] not in held:
            continue
        tw = by[("single_view", n, ngf)]
        rs, rt = held[sv["name"]], held[tw["name"]]
        rows = []
        for t in SWITCH_THRESHOLDS:
            use_twin = [a["outside_light_share"] < t for a in rs]
            pick = [b if u else a for a, b, u in zip(rs, rt, use_twin)]
            row = {"below": t, "switched_frames": int(sum(use_twin)),
                   "ssim": float(np.mean([p["final"]["ssim"] for p in pick])),
                   "psnr": float(np.mean([p["final"]["psnr"] for p in pick])), "ms": {}}
            for d, per in speed.items():
                if sv["name"] in per and tw["name"] in per:
                    row["ms"][d] = {k: float(np.mean([per[tw["name"]][k] if u else per[sv["name"]][k]
                                                      for u in use_twin])) for k in ("generator_ms", "lightmap_ms")}
            rows.append(row)
        base = rows[0]
        ok = [r for r in rows if r["ssim"] >= base["ssim"] - SWITCH_TOLERANCE["ssim"]
              and r["psnr"] >= base["psnr"] - SWITCH_TOLERANCE["psnr"]]
        best = max(ok, key=lambda r: r["below"])
        out.append({"surround": sv["name"], "single_view": tw["name"], "frames": len(rs), "thresholds": rows,
                    "tolerance": SWITCH_TOLERANCE,
                    "chosen": {"surround": sv["name"], "single_view": tw["name"], "below_outside_light_share":
                               best["below"], "switched_frames": best["switched_frames"], "frames": len(rs),
                               "ssim_change": best["ssim"] - base["ssim"], "psnr_change": best["psnr"] - base["psnr"],
                               "ms": best["ms"], "ms_surround_only": base["ms"]},
                    "sequences": switch_on_sequences(temp or {}, sv["name"], tw["name"], best["below"])})
    return out


def share_cost_ms(runner, data):
    """Host time of outside_light_share on one held-out frame (median of 20)."""
    fr = ngi.read_frame(str(data / test_frames(data)[0]))
    ts = []
    for _ in range(20):
        t0 = time.perf_counter()
        ngi.outside_light_share(fr)
        ts.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(ts))


# --------------------------------------------------------------------------
# Summary, Pareto front, zoo
# --------------------------------------------------------------------------

def paired(held, a, b):
    """Per-frame SSIM and PSNR differences a - b on the same frames: mean, and how many frames a wins."""
    da = [x["final"]["ssim"] - y["final"]["ssim"] for x, y in zip(held[a], held[b])]
    dp = [x["final"]["psnr"] - y["final"]["psnr"] for x, y in zip(held[a], held[b])]
    return {"ssim": float(np.mean(da)), "psnr": float(np.mean(dp)), "frames": len(da),
            "a_higher_ssim": int(sum(d > 0 for d in da))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ladder", type=Path, default=ladder_mod.LADDER)
    ap.add_argument("--work", type=Path, required=True, help="the ladder's work folder (ngi_train.generator.ladder --work)")
    ap.add_argument("--data", action="append", default=[], help="N=DIR (64 and 32)")
    ap.add_argument("--seq", action="append", default=[], help="N=DIR: the moving-camera sequence datasets")
    ap.add_argument("--devices", default="pocl", help="comma-separated ngi device specs to time on")
    ap.add_argument("--device", default="pocl", help="the device the quality is measured on")
    ap.add_argument("--render-device", default="pocl")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--lightmap-frames", type=int, default=5)
    ap.add_argument("--max-frames", type=int, default=0, help="held-out frames (0 = all; for a quick check)")
    ap.add_argument("--skip", default="", help="comma-separated stages to skip: heldout,temporal,speed")
    ap.add_argument("--ngi", default=None)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--zoo", type=Path, help="write the zoo manifest here (models/zoo.json)")
    args = ap.parse_args(argv)
    args.data = ladder_mod.parse_data(args.data)
    args.seq = ladder_mod.parse_data(args.seq)
    args.devices = [d for d in args.devices.split(",") if d]
    skip = set(args.skip.split(",")) - {""}
    ladder = ladder_mod.load_ladder(args.ladder)
    args.work.mkdir(parents=True, exist_ok=True)
    vs = variants(ladder, args.work)
    dev = ngi.Device(args.device)
    runner = Runner(dev)
    held = heldout(args, runner, vs, args.work) if "heldout" not in skip else {}
    temp = temporal_stage(args, runner, vs, args.work) if "temporal" not in skip else {}
    speed = speed_stage(args, vs, args.work) if "speed" not in skip else {}
    noise = {n: read_json(args.data[n] / "noise_floor.json") for n in args.data}

    summary = {"generated": datetime.datetime.now().isoformat(timespec="seconds"),
               "datasets": {str(n): rel(p) for n, p in args.data.items()},
               "dataset_configs": {str(n): read_json(p / "dataset.json") for n, p in args.data.items()},
               "noise_floor": {str(n): ({k: v[k] for k in ("reference_spp", "frames", "final_ldr", "lightmap_linear")}
                                        if v else None) for n, v in noise.items()},
               "recipe": ladder["recipe"], "variants": {}, "speed_devices": {}, "switch": [], "pairs": {}}
    for v in vs:
        entry = {k: (rel(v[k]) if k == "file" and v[k] else v[k]) for k in v}
        if v["name"] in held:
            entry["heldout"] = summarize_frames(held[v["name"]])
        if v["name"] in temp:
            entry["temporal"] = {s: {k: x[k] for k in x if k not in ("per_frame", "brightness",
                                                                      "brightness_reference",
                                                                      "outside_light_share")}
                                 for s, x in temp[v["name"]].items()}
        entry["speed"] = {d: {k: speed[d][v["name"]][k] for k in ("generator_ms", "lightmap_ms", "gflop",
                                                                 "memory_mib", "input")}
                          for d in speed if v["name"] in speed[d]}
        summary["variants"][v["name"]] = entry
    for d in speed:
        any_entry = next(iter(speed[d].values()), None)
        summary["speed_devices"][d] = any_entry["device"] if any_entry else None
    if held:
        summary["switch"] = switch_stage(vs, held, speed, temp)
        summary["share_cost_ms"] = share_cost_ms(runner, args.data[64])
    if held:
        for s_name, v_name in (("surround_n64_ngf32", "single_view_n64_ngf32"),
                               ("surround_n64_ngf32_seed2", "single_view_n64_ngf32_seed2"),
                               ("surround_n64_ngf16", "single_view_n64_ngf16"),
                               ("surround_n64_ngf8", "single_view_n64_ngf8"),
                               ("surround_n32_ngf32", "single_view_n32_ngf32"),
                               ("shipped_surround_n64_ngf32", "shipped_single_view_n64_ngf32")):
            if s_name in held and v_name in held:
                summary["pairs"][f"{s_name} - {v_name}"] = paired(held, s_name, v_name)
                # "Light from outside the front view": at least OUTSIDE of the frame's lumination on the other faces.
                for label, keep in ((f">= {OUTSIDE}", lambda x: x >= OUTSIDE), (f"< {OUTSIDE}", lambda x: x < OUTSIDE)):
                    idx = [k for k, r in enumerate(held[s_name]) if keep(r["outside_light_share"])]
                    if idx:
                        sub = {k: [held[k][i] for i in idx] for k in (s_name, v_name)}
                        summary["pairs"][f"{s_name} - {v_name} (outside light share {label})"] = paired(sub, s_name,
                                                                                                       v_name)
    write_json(args.work / "ladder.json", {"summary": summary, "heldout": held, "temporal": temp, "speed": speed})
    write_json(args.out / "ladder.json", summary)
    ladder_report.write(summary, {k: temp.get(k) for k in temp}, args.out)
    if args.zoo:
        manifest = zoo_mod.build(summary, args.zoo, REPO)
        write_json(args.zoo, manifest)
        zoo_mod.load(args.zoo)  # what was written must load
        (args.zoo.parent / "ladder").mkdir(parents=True, exist_ok=True)
        (args.zoo.parent / "ladder" / "README.md").write_text(ladder_report.cards(manifest))
        log(f"ladder_eval: wrote {args.zoo} ({len(manifest['rungs'])} rungs)")
    log(f"ladder_eval: wrote {args.out / 'ladder.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

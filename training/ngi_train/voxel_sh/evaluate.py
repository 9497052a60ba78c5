#!/usr/bin/python3
"""Seed 004 evaluation at the voxel level: every method's SH field (or per-voxel lighting) against the path-traced
ground truth of the test scenes, in the units of seed 004's Table 1 and in lighting units.

Methods
  <model stem>     a trained voxel_sh model, run by ngi (Python bindings) on the device
  mean_position    baseline: per test voxel the mean training SH at the same cell (voxel id) over the training
                   scenes that have a surface voxel there, else over the 8 nearest training voxels (centres)
  pt_sh_second     a second, independent path-traced estimate of the test scene's SH (the noise floor), if the
                   scene folder has sh_second.npy (ngi voxel-data --noise)
  ltf_* (optional) per-voxel lighting of the LTF variants from `ngi probe-gi`'s field_ltf_*.npy (--ltf DIR)

Metrics per test scene
  sh_mse_std        mean squared error of the 27 coefficients standardized by the TRAINING statistics (per
                    coefficient mean and std): seed 004's Table 1 "MSE" in comparable units
  face_rel_mse      sum over exposed faces toward the grid's interior of (E_pred - E_true)^2 / sum E_true^2, lighting units (irradiance / pi);
                    E_pred from the SH at the face normal (cosine lobe), or the per-voxel lighting for the LTF;
                    E_true = the path-traced lighting of that face (face_lighting.npy)
  probe_rel_mse     the same at the probe point, toward the voxel's shading normal, against lighting.npy
  ms_per_scene      median wall time of Model.run on the scene, per OpenCL device (after a warm-up run)

Writes one JSON file (--out) and prints a table.
"""
import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from ngi_train.voxel_sh import data

# Real SH bands 0-2 with the Condon-Shortley phase (docs/CONVENTIONS.md section 14) and the cosine lobe A_l.
LOBE = np.array([np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)
FACE_NORMALS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64)


def sh9(d):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([np.full_like(x, 0.28209479177387814), -0.48860251190291992 * y, 0.48860251190291992 * z,
                     -0.48860251190291992 * x, 1.0925484305920792 * x * y, -1.0925484305920792 * y * z,
                     0.31539156525252005 * (3 * z * z - 1), -1.0925484305920792 * x * z,
                     0.54627421529603959 * (x * x - y * y)], -1)


def sh_lighting(sh, normals):
    """Lighting (irradiance / pi) [V, 3] of SH [V, 27] toward unit normals [V, 3]."""
    c = sh.reshape(-1, 3, 9).astype(np.float64)
    return np.maximum((c * (LOBE * sh9(normals))[:, None, :]).sum(-1), 0) / np.pi


def rel_mse(pred, true):
    den = float((true ** 2).sum())
    return float(((pred - true) ** 2).sum()) / den if den > 0 else float("nan")


def face_lighting_of(method_sh, method_lighting, exposed):
    """[V, 6, 3] per-face lighting predicted by a field: SH at each face normal, or the per-voxel lighting."""
    V = len(exposed)
    out = np.zeros((V, 6, 3))
    for f in range(6):
        if method_sh is not None:
            out[:, f] = sh_lighting(method_sh, np.repeat(FACE_NORMALS[f][None], V, 0))
        else:
            out[:, f] = method_lighting
    return out


def mean_position_baseline(train_scenes, test_attr):
    by_id = {}
    for s in train_scenes:
        for i, vid in enumerate(s.attributes[:, data.ID_CHANNEL].astype(np.int64)):
            by_id.setdefault(int(vid), []).append(s.sh[i])
    centres = np.concatenate([s.attributes[:, :3] for s in train_scenes])
    all_sh = np.concatenate([s.sh for s in train_scenes])
    out = np.zeros((len(test_attr), 27), np.float32)
    hits = 0
    for i, a in enumerate(test_attr):
        vid = int(a[data.ID_CHANNEL])
        if vid in by_id:
            out[i] = np.mean(by_id[vid], 0)
            hits += 1
        else:
            d = ((centres - a[:3]) ** 2).sum(1)
            out[i] = all_sh[np.argpartition(d, 8)[:8]].mean(0)
    return out, hits


def time_model(device_spec, path, attributes, repeats=5):
    import ngi
    with ngi.Device(device_spec) as dev:
        m = ngi.Model(dev, path)
        pred = m.run(attributes)  # warm-up: builds the programs and the graph
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            m.run(attributes)
            times.append((time.perf_counter() - t0) * 1e3)
    return np.asarray(pred, np.float32), statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="+", required=True, help="training scene folders (standardization, baseline)")
    ap.add_argument("--test", nargs="+", required=True, help="test scene folders")
    ap.add_argument("--models", nargs="*", default=[], help="voxel_sh model files")
    ap.add_argument("--ltf", nargs="*", default=[],
                    help="per test scene (same order), an ngi probe-gi output folder with field_ltf_*.npy, or '-'")
    ap.add_argument("--devices", nargs="+", default=["pocl"], help="OpenCL devices to time the models on")
    ap.add_argument("--out", required=True)
    ap.add_argument("--baselines", help="also write each test scene's mean_position SH here as "
                                        "mean_position_<scene folder>.npy (for ngi probe-gi --sh)")
    args = ap.parse_args(argv)

    train = data.load_scenes(args.train)
    all_sh = np.concatenate([s.sh for s in train]).astype(np.float64)
    stats = data.Stats.from_scenes(train)  # the models' own standardization
    mean, std = stats.output_mean, stats.output_std
    std_mse = lambda p, t: float((((p - mean) / std - (t - mean) / std) ** 2).mean())  # noqa: E731
    train_spread = float((((all_sh - mean) / std) ** 2).mean())  # 1 by construction: the "predict the mean" MSE

    results = {"train": args.train, "standardization": "per-coefficient mean and std of the training SH",
               "scenes": {}}
    for k, folder in enumerate(args.test):
        folder = Path(folder)
        scene = data.load_scene(folder)
        exposed = np.load(folder / "exposed.npy").astype(np.int64)
        face_true = np.load(folder / "face_lighting.npy").astype(np.float64)
        probe_true = np.load(folder / "lighting.npy").astype(np.float64)
        probe_pts = np.load(folder / "probe.npy").astype(np.float64)
        centres = scene.attributes[:, :3].astype(np.float64)
        shading_normal = probe_pts - centres
        shading_normal /= np.linalg.norm(shading_normal, axis=1, keepdims=True)
        # Faces toward the grid's interior only: a one-block wall on the border (the Cornell boxes fill the grid)
        # also has an outer face, lit by the sky outside, which its probe (on the inner side) does not represent and
        # no camera inside the grid sees.
        cells = np.floor(centres).astype(np.int64)
        grid = np.array(scene.grid)
        inward = np.stack([cells[:, f // 2] + (1 - 2 * (f % 2)) for f in range(6)], 1)
        inside = (inward >= 0) & (inward < grid[np.arange(6) // 2])
        mask = np.stack([(exposed >> f) & 1 for f in range(6)], 1).astype(bool) & inside
        true_sh = scene.sh.astype(np.float64)
        methods = {}

        def add(name, sh=None, lighting=None, extra=None):
            r = {}
            if sh is not None:
                r["sh_mse_std"] = std_mse(sh.astype(np.float64), true_sh)
                probe_pred = sh_lighting(sh, shading_normal)
            else:
                probe_pred = lighting
            faces = face_lighting_of(sh, lighting, exposed)
            r["face_rel_mse"] = rel_mse(faces[mask], face_true[mask])
            r["probe_rel_mse"] = rel_mse(probe_pred, probe_true)
            r.update(extra or {})
            methods[name] = r

        add("pt_sh", true_sh, extra={"note": "the ground truth's own SH: the face/probe error of SH-27 itself "
                                             "(band-2 truncation, one probe per voxel, and its noise)"})
        if (folder / "sh_second.npy").is_file():
            add("pt_sh_second", np.load(folder / "sh_second.npy"),
                extra={"note": "a second independent estimate: sh_mse_std / 2 is the noise of one estimate"})
        base, hits = mean_position_baseline(train, scene.attributes)
        add("mean_position", base, extra={"voxels_with_same_cell_in_training": hits})
        if args.baselines:
            Path(args.baselines).mkdir(parents=True, exist_ok=True)
            np.save(Path(args.baselines) / f"mean_position_{folder.name}.npy", base.astype(np.float32))
        for path in args.models:
            times = {}
            pred = None
            for dev in args.devices:
                pred, ms = time_model(dev, path, scene.attributes)
                times[dev] = ms
            add(Path(path).stem, pred, extra={"ms_per_scene": times, "model": path})
        if k < len(args.ltf) and args.ltf[k] != "-":
            for f in sorted(Path(args.ltf[k]).glob("field_ltf_*.npy")):
                add(f.stem[len("field_"):], lighting=np.load(f).astype(np.float64), extra={"from": str(f)})
        results["scenes"][scene.name] = {"voxels": scene.voxels, "methods": methods,
                                         "predict_training_mean_sh_mse_std": std_mse(
                                             np.repeat(mean[None], scene.voxels, 0), true_sh),
                                         "training_spread": train_spread}
        print(f"\n{scene.name} ({scene.voxels} voxels)")
        print(f"  {'method':24s} {'SH MSE (std)':>13s} {'face rel MSE':>13s} {'probe rel MSE':>14s}  ms/scene")
        for name, r in methods.items():
            sh_m = r.get("sh_mse_std")
            print(f"  {name:24s} {sh_m if sh_m is not None else float('nan'):13.4f} {r['face_rel_mse']:13.4f} "
                  f"{r['probe_rel_mse']:14.4f}  {r.get('ms_per_scene', '')}")
    Path(args.out).write_text(json.dumps(results, indent=2) + "\n")
    print(f"\nwritten {args.out}")


if __name__ == "__main__":
    main()

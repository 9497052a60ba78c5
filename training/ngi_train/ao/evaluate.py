#!/usr/bin/python3
"""Evaluate seed 001's AO networks (run by ngi) and the baselines a careful user would try first, on the held-out
views of each object, against the ray-traced reference (docs/RESULTS_AO.md).

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.ao.evaluate \\
        --object sculpture=DATA1 --object trefoil=DATA2 \\
        --models models --out docs/ao [--ngi build/ngi]

Methods, each evaluated on every held-out view (`ngi ao-data`'s "heldout" orbit):
  mlp XxY ring    the network with the real neighbourhood (training-consistent), run by `ngi ao`
  mlp XxY r=0     the seed's inference: all 16 inputs = the pixel's own normal (`ngi ao --radius 0`)
  constant        the mean AO of the training samples
  sh2             an order-2 SH fit (9 coefficients, least squares on the training samples) of AO against the
                  pixel's smooth normal: the best any function of the normal alone can do up to band 2
  baked           baked AO, what vertex/face colours store: on blocks per voxel face (the mean reference AO of
                  every training-view pixel on that face); on triangles per vertex (each training pixel adds its
                  AO with its barycentric weight to the triangle's three vertices; a pixel gets the weighted
                  mean of its vertices' bakes, i.e. the interpolated vertex colour); faces and vertices no
                  training view saw get the constant
  ssao            screen-space AO from the view's depth and normals (16 hemisphere samples, range check), its
                  radius picked on 8 training views from {0.5, 1, 2, 4} m
Metrics over the object's pixels: SSIM (Wang: Gaussian 11x11 window, sigma 1.5, K1 0.01, K2 0.03, population
covariances, data range 1, i.e. skimage's structural_similarity(gaussian_weights=True, sigma=1.5,
use_sample_covariance=False)), its map averaged over the object's pixels only (background masked), MSE and PSNR.
--ablation LABEL=PATH adds other AO models (e.g. trained on face normals) as more rows.
Writes OUT/results.json, OUT/<object>_compare.png (network | reference | |difference| for one view) and prints
Markdown tables. Resumable per (object, model, mode, view): ngi outputs are kept under OUT/.runs.
"""

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from skimage.metrics import structural_similarity
from tqdm import tqdm

from ngi_train import ngi_paths
from ngi_train.ao import sampling

SIZES = ("16x8", "32x16", "64x32")


def masked_metrics(pred, ref, mask):
    _, smap = structural_similarity(ref, pred, data_range=1.0, gaussian_weights=True, sigma=1.5,
                                    use_sample_covariance=False, full=True)
    d = (pred - ref)[mask]
    mse = float(np.mean(d * d))
    return {"ssim": float(smap[mask].mean()), "mse": mse, "psnr": 10 * math.log10(1 / mse) if mse > 0 else None}


def sh9(n):
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    return np.stack([np.ones_like(x), y, z, x, x * y, y * z, 3 * z * z - 1, x * z, x * x - y * y], -1)


def surface_cells(v):
    """Per object pixel: the solid block's linear key and the face id (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z)."""
    n = v["normal"].shape[1]
    d, look, _, _ = sampling.camera_rays(v["view"], n)
    depth = v["depth"][0].astype(np.float64)
    t = depth / np.einsum("chw,c->hw", d, look)
    p = np.asarray(v["view"]["position"])[:, None, None] + d * t[None]
    nf = v["face_normal"].astype(np.float64)
    cell = np.floor(p - 0.5 * nf).astype(np.int64)
    axis = np.argmax(np.abs(nf), 0)
    face = 2 * axis + (np.take_along_axis(nf, axis[None], 0)[0] < 0)
    key = ((cell[0] * 4096 + cell[1]) * 4096 + cell[2]) * 6 + face
    return key[v["mask"]]


class VertexBake:
    """AO baked per mesh vertex from training views (surface.npy): sum of w * ao and of w per vertex index."""

    def __init__(self):
        self.sums = np.zeros(0)
        self.weights = np.zeros(0)

    @staticmethod
    def _pixels(v):
        s = v["surface"][:, v["mask"]]  # [6, P]
        idx = s[:3].astype(np.int64)
        return idx, s[3:].astype(np.float64), idx[0] >= 0

    def add(self, v):
        idx, w, tri = self._pixels(v)
        ao = v["ao"][0][v["mask"]].astype(np.float64)
        size = max(len(self.sums), int(idx.max()) + 1 if tri.any() else 0)
        self.sums = np.pad(self.sums, (0, size - len(self.sums)))
        self.weights = np.pad(self.weights, (0, size - len(self.weights)))
        for k in range(3):
            self.sums += np.bincount(idx[k][tri], weights=(w[k] * ao)[tri], minlength=size)
            self.weights += np.bincount(idx[k][tri], weights=w[k][tri], minlength=size)

    def predict(self, v, fallback):
        """Per object pixel: the interpolated bake, NaN where the pixel is not on a triangle; vertices no training
        pixel touched take `fallback`."""
        idx, w, tri = self._pixels(v)
        out = np.full(idx.shape[1], np.nan)
        safe = np.clip(idx, 0, max(len(self.sums) - 1, 0))
        known = (safe < len(self.sums)) & (idx >= 0)
        vals = np.where(known & (self.weights[safe] > 0), self.sums[safe] / np.maximum(self.weights[safe], 1e-30), fallback)
        out[tri] = (w * vals).sum(0)[tri] / np.maximum(w.sum(0)[tri], 1e-30)
        return out

    def vertices(self):
        return int((self.weights > 0).sum())


def ssao(v, radius, samples=16, seed=7):
    """Normal-oriented hemisphere SSAO (Crytek/LearnOpenGL style) with a range check."""
    n = v["normal"].shape[1]
    d, look, right, up = sampling.camera_rays(v["view"], n)
    depth = v["depth"][0].astype(np.float64)
    mask = v["mask"]
    t = depth / np.einsum("chw,c->hw", d, look)
    pos = np.asarray(v["view"]["position"], np.float64)
    p = (pos[:, None, None] + d * t[None])[:, mask].T  # [P, 3]
    nrm = v["normal"][:, mask].T.astype(np.float64)
    rng = np.random.default_rng(seed)
    k = rng.normal(size=(samples, 3))
    k /= np.linalg.norm(k, axis=1, keepdims=True)
    k *= (0.1 + 0.9 * (np.arange(1, samples + 1) / samples) ** 2)[:, None]  # more samples close to the point
    occluded = np.zeros(len(p))
    for s in k:
        s = s[None, :] * np.sign(np.sum(s[None, :] * nrm, 1, keepdims=True) + 1e-12)  # flip into the hemisphere
        q = p + radius * s + 0.02 * nrm
        rel = q - pos
        z = rel @ look
        x, y = (rel @ right) / z, (rel @ up) / z
        col = np.clip(np.round((x + 1) * 0.5 * n - 0.5).astype(int), 0, n - 1)
        row = np.clip(np.round((1 - y) * 0.5 * n - 0.5).astype(int), 0, n - 1)
        scene_z = depth[row, col]
        in_range = np.abs(z - scene_z) < radius
        occluded += (scene_z < z - 0.02) & in_range
    out = np.ones((n, n), np.float32)
    out[mask] = 1.0 - occluded / samples
    return out


def run_ngi(ngi, env, frame, model, out, radius):
    if (out / "ao.npy").exists():
        return np.load(out / "ao.npy")[0]
    cmd = [ngi, "ao", "--frame", str(frame), "--model", str(model), "--out", str(out)]
    if radius is not None:
        cmd += ["--radius", str(radius)]
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    return np.load(out / "ao.npy")[0]


def evaluate_object(name, data, models_dir, out_dir, ngi, env, ablations=()):
    X, y, _ = sampling.sample(data, 3.0)
    mean_ao = float(y.mean())
    coef, *_ = np.linalg.lstsq(sh9(X[:, :3].astype(np.float64)), y.astype(np.float64), rcond=None)
    # Bake per face (blocks) and per vertex (triangles) from every training view.
    sums, counts = {}, {}
    vertex_bake = VertexBake()
    train = sampling.views(data, "orbit")
    for folder in train:
        v = sampling.load_view(folder)
        if "surface" in v:
            vertex_bake.add(v)
        keys = surface_cells(v)
        ao = v["ao"][0][v["mask"]]
        if "surface" in v:  # the per-face table holds block pixels only
            blocks = v["surface"][0][v["mask"]] < 0
            keys, ao = keys[blocks], ao[blocks]
        uk, inv = np.unique(keys, return_inverse=True)
        s = np.bincount(inv, weights=ao)
        c = np.bincount(inv)
        for kk, ss, cc in zip(uk, s, c):
            sums[kk] = sums.get(kk, 0.0) + ss
            counts[kk] = counts.get(kk, 0) + cc
    baked_table = {k: sums[k] / counts[k] for k in sums}
    # SSAO radius chosen on training views.
    best_r, best_mse = None, float("inf")
    for r in (0.5, 1.0, 2.0, 4.0):
        errs = []
        for folder in train[::16]:
            v = sampling.load_view(folder)
            errs.append(np.mean((ssao(v, r) - v["ao"][0])[v["mask"]] ** 2))
        if np.mean(errs) < best_mse:
            best_r, best_mse = r, float(np.mean(errs))

    held = sampling.views(data, "heldout")
    methods = [f"mlp {s} ring" for s in SIZES] + [f"mlp {s} r=0" for s in SIZES] + ["constant", "sh2", "baked", "ssao"]
    methods += [label for label, _ in ablations]
    scores = {m: [] for m in methods}
    bar = tqdm(total=len(held), desc=f"eval {name}", unit="view", **ngi_paths.progress_options())
    example = None
    for i, folder in enumerate(held):
        v = sampling.load_view(folder)
        ref, mask = v["ao"][0], v["mask"]
        preds = {}
        for s in SIZES:
            model = Path(models_dir) / f"ao_{name}_{s}.safetensors"
            preds[f"mlp {s} ring"] = run_ngi(ngi, env, folder, model, Path(out_dir) / ".runs" / name / s / "ring" / folder.name, None)
            preds[f"mlp {s} r=0"] = run_ngi(ngi, env, folder, model, Path(out_dir) / ".runs" / name / s / "r0" / folder.name, 0)
        for label, template in ablations:
            preds[label] = run_ngi(ngi, env, folder, Path(template.format(object=name)),
                                   Path(out_dir) / ".runs" / name / label.replace(" ", "_") / folder.name, None)
        const = np.ones_like(ref)
        const[mask] = mean_ao
        preds["constant"] = const
        sh = np.ones_like(ref)
        sh[mask] = np.clip(sh9(v["normal"][:, mask].T.astype(np.float64)) @ coef, 0, 1)
        preds["sh2"] = sh
        baked = np.ones_like(ref)
        baked[mask] = [baked_table.get(k, mean_ao) for k in surface_cells(v)]
        if "surface" in v:  # triangle pixels: the per-vertex bake (block pixels keep the per-face one)
            per_vertex = vertex_bake.predict(v, mean_ao)
            on_tri = ~np.isnan(per_vertex)
            baked[mask] = np.where(on_tri, per_vertex, baked[mask])
        preds["baked"] = baked
        preds["ssao"] = ssao(v, best_r)
        for m in methods:
            scores[m].append(masked_metrics(preds[m].astype(np.float64), ref.astype(np.float64), mask))
        if i == 0:
            example = (preds, ref, mask)
        bar.update(1)
    bar.close()
    summary = {m: {"ssim": float(np.mean([s["ssim"] for s in scores[m]])),
                   "mse": float(np.mean([s["mse"] for s in scores[m]])),
                   "psnr_of_mean_mse": 10 * math.log10(1 / float(np.mean([s["mse"] for s in scores[m]])))}
               for m in methods}
    save_compare(Path(out_dir) / f"{name}_compare.png", example)
    return {"views": len(held), "training_samples": int(len(y)), "constant": mean_ao, "ssao_radius": best_r,
            "baked_faces": len(baked_table), "baked_vertices": vertex_bake.vertices(), "methods": summary}


def save_compare(path, example):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    preds, ref, mask = example
    cols = [("mlp 16x8 ring", "network 16x8 (ring)"), ("mlp 64x32 ring", "network 64x32 (ring)"),
            ("mlp 16x8 r=0", "network 16x8 (r = 0)"), (None, "ray-traced reference"),
            ("diff", "|16x8 ring - reference|"), ("sh2", "SH-2 fit"), ("baked", "baked per face / vertex"), ("ssao", "SSAO")]
    fig, axes = plt.subplots(2, 4, figsize=(13, 6.8))
    for ax, (key, title) in zip(axes.ravel(), cols):
        if key is None:
            img = ref
        elif key == "diff":
            img = np.abs(preds["mlp 16x8 ring"] - ref) * mask
        else:
            img = preds[key]
        ax.imshow(img, cmap="gray" if key != "diff" else "magma", vmin=0, vmax=1 if key != "diff" else 0.5)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--object", action="append", required=True, help="NAME=DATA (an ngi ao-data folder)")
    ap.add_argument("--models", default=str(ngi_paths.REPO / "models"))
    ap.add_argument("--out", required=True)
    ap.add_argument("--ngi", default=None)
    ap.add_argument("--ablation", action="append", default=[],
                    help="LABEL=PATH: another AO model per object, {object} in PATH is the object's name")
    a = ap.parse_args()
    ngi = ngi_paths.find_ngi(a.ngi)
    env = ngi_paths.ngi_env()
    os.makedirs(a.out, exist_ok=True)
    results = {}
    for spec in a.object:
        name, data = spec.split("=", 1)
        results[name] = evaluate_object(name, data, a.models, a.out, ngi, env,
                                        [tuple(x.split("=", 1)) for x in a.ablation])
        results[name]["data"] = json.loads((Path(data) / "ao_data.json").read_text())
    (Path(a.out) / "results.json").write_text(json.dumps(results, indent=2) + "\n")
    for name, r in results.items():
        print(f"\n### {name}: {r['views']} held-out views\n")
        print("| method | SSIM (object pixels) | MSE | PSNR dB |\n|---|---|---|---|")
        for m, s in r["methods"].items():
            print(f"| {m} | {s['ssim']:.4f} | {s['mse']:.5f} | {s['psnr_of_mean_mse']:.2f} |")


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Score a trained seed 002 model (train.py's file) on a scene's held-out frames, against the direct-light baseline.

    PYTHONPATH=training:build/python nice -n 10 /usr/bin/python3 -m ngi_train.neural_gi.evaluate \\
        --dataset data/neural_gi_bleed \\
        --model models/neural_gi_bleed.safetensors --out results/neural_gi_bleed.json [--engine ngi]

The held-out frames are chosen as train.py chooses them (--test-frames / --test-split, the same defaults). Per frame
the lighting (direct + indirect, no albedo; 0 on sky pixels, as the reference is) is scored against reference.exr
exactly as `ngi lightmap` scores a lightmap (ngi.scoring.Reference): "final" = the tone-mapped final image
(lighting x albedo + emission + env, ACES, sRGB, data range 1) and "lighting" = the linear lighting (data range = the
reference's maximum), each MSE / PSNR / SSIM from ngi.compare_images plus the mean absolute error; "log_l1" is the
training loss (Eq. 6 over the surface pixels). Methods: "model" and "direct_only" (the lighting is the direct
feature alone, i.e. no indirect light). --engine torch runs the file's weights in PyTorch (float32; F16 weights
widened), --engine ngi runs the file in ngi (ngi.Model on --device). The JSON holds the means over frames (PSNR:
over frames where it is finite) and every frame's numbers.

--path-traced SPLIT [SPLIT ...] adds one method per split, "path_traced_<S>" (S: the split name's "_pt<S>" suffix,
else the split name): the lighting is the reference.exr of the same-named frame in DATASET/SPLIT/<scene> (a render
of the same view and light at S samples per pixel with another seed: path tracing at equal time, sequences.py).
--temporal scores the held-out frames as one sequence in frame order (a moving camera or a moving light,
sequences.py): MABD_t = mean over pixels of |Y_t - Y_t-1|, Y the luminance (Rec. 709
weights) of the tone-mapped final image, for the reference and every method; "mabd" is its mean over t and
"mabd_error" the mean over t of |MABD_t(method) - MABD_t(reference)| (0: the method flickers exactly as much as the
reference; the reference's own MABD includes its Monte Carlo noise).
"""

import argparse
import json
import math
import re
import sys
import time
from pathlib import Path

import numpy as np
import torch

from ngi_train.neural_gi import data
import ngi
import ngi.model_file as model_file
from ngi import _constants
import ngi.scoring as scoring
from ngi.neural_gi import NeuralGI, decode_indirect, sanitize_radiance

METRICS = ("mae", "mse", "psnr", "ssim")
REC709 = np.array(_constants.REC709_LUMA, np.float64)


def load_torch_model(path):
    tensors, config = model_file.read_model(str(path))
    net = NeuralGI.from_config(config["training"])
    state = {k: torch.from_numpy(np.asarray(v, np.float32)) for k, v in tensors.items()}
    missing, unexpected = net.load_state_dict(state, strict=False)
    missing = [k for k in missing if not k.endswith("num_batches_tracked")]
    if missing or unexpected:
        raise ValueError(f"{path}: tensors do not match the config: missing {missing[:3]}, unexpected {unexpected[:3]}")
    return net, config


def model_box(config):
    """neural_gi.scene_box (the format's field), else training.scene_box (train.py with an older ngi.neural_gi)."""
    box = config.get("neural_gi", {}).get("scene_box") or config.get("training", {}).get("scene_box")
    if not box:
        raise ValueError("the model file has no scene box (write it with training/ngi_train/neural_gi/train.py)")
    return box["min"], box["max"]


class Predictor:
    """inputs [1, 18, N, N] (float32 tensor) -> indirect [1, 3, N, N] numpy, in PyTorch or in ngi."""

    def __init__(self, path, engine, device):
        self.engine = engine
        if engine == "torch":
            self.net, self.config = load_torch_model(path)
            self.net.train()  # per-image BatchNorm (bn_mode per_image) ...
            for m in self.net.modules():  # ... without touching the running statistics
                if isinstance(m, torch.nn.modules.batchnorm._BatchNorm):
                    m.track_running_stats = False
        else:
            self.config = model_file.read_config(str(path))
            self.model = ngi.Model(device, str(path))

    def __call__(self, inputs):
        if self.engine == "torch":
            with torch.no_grad():
                return decode_indirect(self.net.raw_output(inputs)).numpy()
        return np.asarray(self.model.run(np.ascontiguousarray(inputs.numpy(), np.float32)), np.float32)


def scores(ref, frame, lighting):
    """({final: {mae, mse, psnr, ssim}, lighting: {...}}, the tone-mapped final image) of a [3, N, N] lighting
    against the frame's reference."""
    s = ref.score(lighting)
    shown = s["display"]
    lm = np.minimum(scoring._clean_light(lighting), max(scoring.LIGHT_MAX, ref.peak))
    out = {"final": dict(s["final"], mae=float(np.mean(np.abs(shown - ref.final)))),
           "lighting": dict(s["lightmap"], mae=float(np.mean(np.abs(lm - frame.reference))))}
    for v in out.values():
        for k in ("psnr", "ssim"):
            if v[k] is not None and not math.isfinite(v[k]):
                v[k] = None
    return out, shown


def luminance(display):
    """[3, N, N] tone-mapped sRGB image -> [N, N] float64 luminance (Rec. 709 weights on the displayed values)."""
    return np.tensordot(REC709, np.asarray(display, np.float64), axes=1)


def temporal(lum):
    """{method: [N, N] luminance per frame (in order)} -> {method: {mabd, mabd_per_step, mabd_error}}."""
    steps = {m: [float(np.mean(np.abs(b - a))) for a, b in zip(seq, seq[1:])] for m, seq in lum.items()}
    ref = steps["reference"]
    return {m: {"mabd": float(np.mean(v)) if v else None, "mabd_per_step": v,
                "mabd_error": float(np.mean(np.abs(np.subtract(v, ref)))) if v else None} for m, v in steps.items()}


def path_traced_method(split):
    """The method name of a --path-traced split: moving_camera_pt16 -> path_traced_16."""
    m = re.search(r"_pt(\d+)$", split)
    return "path_traced_" + (m.group(1) if m else split)


def mean_of(rows, method, part, metric):
    vals = [r[method][part][metric] for r in rows if r[method][part][metric] is not None]
    return float(np.mean(vals)) if vals else None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, type=Path)
    ap.add_argument("--scene")
    ap.add_argument("--split", default="train")
    ap.add_argument("--test-frames", type=int, default=100)
    ap.add_argument("--test-split")
    ap.add_argument("--max-frames", type=int, default=0, help="score only this many held-out frames (0: all)")
    ap.add_argument("--model", required=True, type=Path)
    ap.add_argument("--engine", choices=("torch", "ngi"), default="torch")
    ap.add_argument("--device", default="cpu", help="OpenCL device of the metrics (and of --engine ngi)")
    ap.add_argument("--cache", type=Path, help="decoded frames (default: next to --out)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--path-traced", metavar="SPLIT", nargs="+", default=[],
                    help="add path tracing at equal time: the reference.exr of the same frames in DATASET/SPLIT/<scene>")
    ap.add_argument("--temporal", action="store_true", help="the held-out frames are a sequence: add MABD")
    ap.add_argument("--out", required=True, type=Path, help="JSON results")
    a = ap.parse_args(argv)
    torch.set_num_threads(a.threads)
    t0 = time.monotonic()
    scene_dir, _, test_frames = data.split_frames(a.dataset, a.scene, a.test_frames, a.split, a.test_split)
    if a.max_frames:
        test_frames = test_frames[: a.max_frames]
    if not test_frames:
        raise SystemExit("no held-out frames to score")
    device = ngi.Device(a.device)
    predict = Predictor(a.model, a.engine, device)
    bbox_min, bbox_max = model_box(predict.config)
    scene_min, scene_max = data.scene_box(scene_dir)
    if not (np.allclose(bbox_min, scene_min) and np.allclose(bbox_max, scene_max)):
        raise SystemExit(f"the model's scene box {bbox_min}..{bbox_max} is not this scene's {scene_min}..{scene_max}"
                         f" ({scene_dir}): a model of another scene?")
    cache = a.cache or a.out.parent / (a.out.stem + "_cache")
    rows = []
    pipeline = None
    traced = {path_traced_method(split): split for split in a.path_traced}
    methods = ["model", "direct_only"] + list(traced)
    lum = {m: [] for m in ["reference"] + methods}
    for f in test_frames:
        arr = data.cached_frame(f, cache / scene_dir.parent.name / scene_dir.name, f.name)
        inputs, direct, ref_t, mask = data.to_tensors(arr, bbox_min, bbox_max)
        indirect = predict(inputs)
        m = mask[0].numpy()
        direct_np = sanitize_radiance(direct)[0].numpy()
        lighting = (direct_np + indirect[0]) * m
        frame = ngi.read_frame(str(f))
        if pipeline is None:
            pipeline = ngi.Pipeline(device, frame.n)
        ref = scoring.Reference(device, pipeline, frame)
        loss = lambda light: float(data.masked_log_l1(torch.from_numpy(light)[None], ref_t, mask))
        lightings = {"model": lighting, "direct_only": direct_np * m}
        for method, split in traced.items():
            pt_dir = Path(a.dataset) / split / scene_dir.name / f.name
            if not (pt_dir / "reference.exr").is_file():
                raise SystemExit(f"--path-traced: {pt_dir}/reference.exr is missing")
            lightings[method] = np.asarray(ngi.read_frame(str(pt_dir)).reference, np.float32) * m
        row = {"frame": f"{f.parent.name}/{f.name}", "surface_fraction": float(m.mean())}
        for method, light in lightings.items():
            numbers, shown = scores(ref, frame, light)
            row[method] = dict(numbers, log_l1=loss(light))
            if a.temporal:
                lum[method].append(luminance(shown))
        if a.temporal:
            lum["reference"].append(luminance(ref.final))
        rows.append(row)
    summary = {}
    for method in methods:
        summary[method] = {part: {k: mean_of(rows, method, part, k) for k in METRICS} for part in ("final", "lighting")}
        summary[method]["log_l1"] = float(np.mean([r[method]["log_l1"] for r in rows]))
    result = {"dataset": str(a.dataset), "scene": scene_dir.name, "model": str(a.model), "engine": a.engine,
              "frames": len(rows), "n": int(rows and ngi.read_frame(str(test_frames[0])).n),
              "metrics": "final: tone-mapped (ACES, sRGB) final image, data range 1; lighting: linear, data range = "
                         "the reference's maximum; mae/mse over all pixels and channels; log_l1: Eq. 6 on surface "
                         "pixels",
              "summary": summary, "temporal": temporal(lum) if a.temporal and len(rows) > 1 else None,
              "seconds": round(time.monotonic() - t0, 2), "per_frame": rows}
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    for method, s in summary.items():
        f = s["final"]
        print(f"{method:16s} final PSNR {f['psnr'] if f['psnr'] is not None else float('nan'):.2f} dB, "
              f"SSIM {f['ssim'] if f['ssim'] is not None else float('nan'):.4f}, MAE {f['mae']:.5f}; "
              f"log-L1 {s['log_l1']:.4f}" + (f"; MABD {result['temporal'][method]['mabd']:.5f} (reference "
                                             f"{result['temporal']['reference']['mabd']:.5f})"
                                             if result["temporal"] else ""), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Smoke test of the training pipeline against the real ngi binary (ctest: training_smoke, < 1 min on 2 cores).

    PYTHONPATH=training:build/python /usr/bin/python3 training/tests/test_training.py --ngi build/ngi \
        --work build/training_smoke

1. renders a tiny dataset with `ngi dataset` (N = 32: 2 train frames, 1 test frame, few samples);
2. the loader (data.py, surround and single view) yields exactly, bit for bit, what a fresh `ngi merge` writes
   (input.npy and target.npy), with the C++ channel names; the single-view input is the surround input's
   front crop, the targets agree; a rerun reuses the cache and a touched frame is merged again;
3. trains a tiny surround generator (ngf 4) for 40 steps: the L1 term falls (mean of the last 5 steps < 0.9 x
   mean of the first 5, fixed seed);
4. interrupts a run with SIGINT, resumes it, and gets the same weights and losses as an uninterrupted run;
5. exports (bn_mode auto), runs `ngi generate` on the same input and compares with PyTorch (max |diff| < 1e-4),
   runs `ngi lightmap` on the test frame and evaluate.py on the test split;
6. the same for a single-view model (10 input channels);
6b. the indirect output mode (issue 25): lightmap_loss.py's decode / tone map / compose equal the pipeline's
   kernels; a tiny surround generator trained with output_mode indirect, the final-image term and no GAN: its
   loss falls, the export records the mode, and ngi's lightmap of a frame is the frame's direct light plus the
   decoded output of the same network in PyTorch (max relative |diff| < 1e-4);
6c. layout ssgi_residual (issue 45): a tiny network that corrects the SSGI rung trains (its L1 falls), exports with
   output_mode ssgi_residual and the rung's gather settings, its training input is the pipeline's bit for bit, and
   ngi's lightmap is direct + decode(PyTorch output + the input's SSGI channels) (max relative |diff| < 1e-4);
7. seed 001's AO: `ngi ao-data` (6 + 1 views at 48 px), ngi_train.ao.train for 40 iterations, and `ngi ao` equal to
   the exported network evaluated in PyTorch on ngi_train.ao.sampling's ring inputs (max |diff| < 1e-4, background 1).
Exit code 77 (ctest: skipped) when torch or numpy is missing.
"""

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

try:
    import numpy as np
    import torch
except ImportError as e:  # pragma: no cover
    # Not a skip: tools/install-deps.sh installs numpy and torch, so their absence is a broken machine.
    print(f"training_smoke: FAILED: cannot import numpy/torch ({e}); run tools/install-deps.sh")
    sys.exit(1)

import ngi.model_file as model_file  # noqa: E402
import ngi.reference_models as reference_models  # noqa: E402

from ngi_train import ngi_paths  # noqa: E402
from ngi_train.ao import sampling  # noqa: E402
from ngi_train.generator import data, lightmap_loss  # noqa: E402
from ngi_train.ngi_paths import run  # noqa: E402  (a failed command raises RuntimeError with its output)

# The commands under test (modules of the package ngi_train, run with python3 -m).
TRAIN_MODULE, EXPORT_MODULE = "ngi_train.generator.train", "ngi_train.generator.export"
EVALUATE_MODULE, AO_TRAIN_MODULE = "ngi_train.generator.evaluate", "ngi_train.ao.train"

# Output tolerance of `ngi generate` against the float64 PyTorch reference. ngi computes in float32 with
# another summation order (im2col + GEMM); the rounding differences (~1e-7 relative per layer) are amplified
# by the per-image BatchNorms at the innermost levels, where a channel has only 2-8 values to normalize by,
# and then squashed by the final Tanh. Measured: ~3e-7; 1e-4 leaves room for other devices without
# letting a real error (a wrong layer gives differences of order 0.1) through.
GENERATE_TOL = 1e-4

DATASET = {
    "comment": "training_smoke: 2 train frames + 1 test frame at N = 32",
    "n": 32, "feature_spp": 1, "reference_spp": 4, "max_bounces": 2, "frames_per_scene": 2,
    "keyframe_interval": 25,
    "train": [{"family": "room", "seeds": [1], "time": 11}],
    "test": [{"family": "bleed", "seeds": [101], "frames": 1}],
}
TRAIN = {"ngf": 4, "num_downs": 5, "ndf": 8, "d_layers": 3, "steps": 40, "checkpoint_every": 10,
         "keep_every": 20, "seed": 7, "threads": 1, "eval_every": 20, "eval_frames": 1}


def check(cond, message):
    if not cond:
        raise SystemExit(f"FAILED: {message}")
    print(f"ok: {message}", flush=True)


def read_log(run_dir):
    lines = [json.loads(s) for s in (Path(run_dir) / "log.jsonl").read_text().splitlines() if s.strip()]
    return [e for e in lines if "eval" not in e]


def train(cfg_path, dataset, run_dir, ngi, *extra):
    return run([sys.executable, "-m", TRAIN_MODULE, "--config", cfg_path, "--dataset", dataset, "--run", run_dir,
                "--ngi", ngi, *extra])


def test_loader(ngi, dataset, work):
    """The loader against fresh `ngi merge` outputs, bit for bit."""
    loaded = {}
    # (ssgi_residual's input is checked in 6c against a model file of that mode, which `ngi merge --model` reads.)
    for layout in ("surround", "single_view"):
        for split in ("train", "test"):
            cache_dir = data.default_cache_dir(dataset, layout)
            ds, n, stats = data.load_split(dataset, split, layout, cache_dir)
            check(stats["merged"] == len(ds) and stats["reused"] == 0, f"{layout}/{split}: {len(ds)} frames merged")
            for i in range(len(ds)):
                x, y, name = ds[i]
                fresh = work / "check" / layout / name
                cmd = [ngi, "merge", "--frame", dataset / name, "--out", fresh]
                proc, _ = run(cmd + (["--single-view"] if layout == "single_view" else []))
                want_x, want_y = np.load(fresh / "input.npy"), np.load(fresh / "target.npy")
                h, w = data.input_hw(n, layout)
                check(want_x.dtype == np.float32 and want_x.shape == (1, data.input_nc(layout), h, w)
                      and want_y.shape == (1, 3, n, n), f"{layout} {name}: ngi merge shapes {want_x.shape} {want_y.shape}")
                check(x.dtype == torch.float32 and np.array_equal(x.numpy(), want_x[0])
                      and np.array_equal(y.numpy(), want_y[0]),
                      f"{layout} {name}: loader input and target == ngi merge's, bit for bit")
                printed = [ln.split("channels:")[1].split() for ln in proc.stdout.splitlines() if "channels:" in ln]
                check(printed == [data.channels(layout)], f"{layout}: C++ channel names == data.channels()")
                check(-1 <= want_y.min() and want_y.max() <= 1, f"{name}: target in the output range [-1, 1]")
                loaded[(layout, name)] = (x.numpy(), y.numpy())
            again = data.load_split(dataset, split, layout, cache_dir)[2]
            check(again == {"merged": 0, "reused": len(ds)}, f"{layout}/{split}: rerun reuses the cache")
    n = DATASET["n"]
    rows, cols = data.front_region(n)
    for (layout, name), (x, y) in loaded.items():
        if layout == "surround":
            xs, ys = loaded[("single_view", name)]
            check(np.array_equal(x[:10, rows, cols], xs) and np.array_equal(y, ys),
                  f"{name}: single-view input == surround front crop, same target")
    # A re-rendered (here: touched) frame is merged again.
    frame = dataset / data.list_frames(dataset, "train")[0]
    st = os.stat(frame / "reference.exr")
    os.utime(frame / "reference.exr", ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000_000))
    stats = data.load_split(dataset, "train", "surround", data.default_cache_dir(dataset, "surround"))[2]
    check(stats == {"merged": 1, "reused": 1}, "a changed frame is merged again, the other reused")


def reference_output(model_path, x):
    tensors, cfg = model_file.read_model(str(model_path))
    g = reference_models.load_generator(tensors, cfg)
    return reference_models.run_reference(g, torch.from_numpy(x), cfg["bn_mode"]).numpy(), cfg


def test_export_and_run(ngi, dataset, work, run_dir, layout):
    model = work / f"{layout}.safetensors"
    proc, _ = run([sys.executable, "-m", EXPORT_MODULE, "--run", run_dir, "--out", model])
    print(proc.stderr.strip())
    tensors, cfg = model_file.read_model(str(model))
    check(cfg["input_layout"] == data.channels(layout) and cfg["bn_mode"] in ("per_image", "running")
          and cfg["training"]["steps"] > 0 and cfg["training"]["bn_mode_selection"]["chosen"] == cfg["bn_mode"]
          and cfg["training"]["dataset_config"]["n"] == DATASET["n"],
          f"{layout}: exported config (input_layout, bn_mode {cfg['bn_mode']}, training metadata)")
    worst = 0.0
    for split in ("train", "test"):
        for name in data.list_frames(dataset, split):
            x_path = data.default_cache_dir(dataset, layout) / name / "input.npy"
            out = work / "generate" / layout / name / "y.npy"
            out.parent.mkdir(parents=True, exist_ok=True)
            run([ngi, "generate", "--model", model, "--input", x_path, "--output", out])
            got = np.load(out)
            want, _ = reference_output(model, np.load(x_path))
            check(got.shape == want.shape, f"{layout} {name}: ngi generate shape {got.shape}")
            worst = max(worst, float(np.abs(got - want).max()))
    check(worst < GENERATE_TOL, f"{layout}: ngi generate == PyTorch, max |diff| {worst:.3g} < {GENERATE_TOL}")
    test_frame = dataset / data.list_frames(dataset, "test")[0]
    out = work / "lightmap" / layout
    run([ngi, "lightmap", "--frame", test_frame, "--model", model, "--out", out])
    metrics = json.loads((out / "metrics.json").read_text())
    check((out / "lightmap.exr").is_file() and (out / "compare.png").is_file()
          and np.isfinite(metrics["network"]["lightmap_linear"]["mse"]),
          f"{layout}: ngi lightmap on a test frame (final_ldr SSIM {metrics['network']['final_ldr']['ssim']:.3f})")
    return model, worst


def test_indirect_mode(ngi, dataset, work):
    """The indirect output mode end to end (docs/CONVENTIONS.md section 8, training/ngi_train/generator/lightmap_loss.py)."""
    import ngi as ngi_py
    dev = ngi_py.Device("")
    rel = data.list_frames(dataset, "test")[0]
    frame = ngi_py.read_frame(str(dataset / rel))
    n = frame.n
    pipe = ngi_py.Pipeline(dev, n)
    # front.npy holds the frame's front planes as the frame folder has them.
    front = data.FrameDataset(data.MergeCache(data.default_cache_dir(dataset, "surround"), "surround"), [rel]).front(0)
    check(np.array_equal(front[data.FRONT["direct"]].numpy(), frame.feature("direct")[0])
          and np.array_equal(front[data.FRONT["reference"]].numpy(), frame.reference),
          "front.npy: the frame's front direct light and reference, bit for bit")
    # The PyTorch output side equals the kernels (float32 rounding apart).
    rng = np.random.default_rng(3)
    light = (rng.random((3, n, n)) * 4.0).astype(np.float32)
    light[0, 0, :4] = [0.0, 1e-4, 65504.0, 2e5]
    want = pipe.tonemap(scoring_compose(frame, light))
    got = lightmap_loss.display_final(torch.from_numpy(light)[None], front[None])[0].numpy()
    tm_err = float(np.abs(got - want).max())
    check(tm_err < 1e-5, f"lightmap_loss compose + ACES + sRGB == the pipeline's: max |diff| {tm_err:.2g}")
    v = np.clip(rng.normal(0, 0.6, (1, 3, n, n)), -1, 1).astype(np.float32)
    v[0, 0, 0, :3] = [-1.0, 1.0, 0.999999]
    surround = ngi_py.Model(dev, str(work / "surround.safetensors"))
    want = pipe.front_lightmap(v, surround)
    # In float32, as training runs it: near v = 1 the decoding x = y / (1 - y) amplifies any rounding of y, so the
    # same arithmetic in float64 differs from the kernel by up to ~eps / (1 - y) relative (2.8e-5 measured here).
    got = lightmap_loss.decode(torch.from_numpy(v))[0].numpy()
    dec_err = float(np.max(np.abs(got - want) / (1e-3 + np.abs(want))))
    check(dec_err < 1e-6, f"lightmap_loss.decode == decode_lightmap (float32): max relative |diff| {dec_err:.2g}")

    cfg_path = work / "indirect.json"
    cfg_path.write_text(json.dumps(dict(TRAIN, layout="surround", steps=30, output_mode="indirect", lambda_final=100,
                                        lambda_gan=0, eval_every=30)))
    train(cfg_path, dataset, work / "run_ind", ngi)
    log = read_log(work / "run_ind")
    l1 = [e["G_L1"] for e in log]
    check(np.mean(l1[-5:]) < np.mean(l1[:5]) and all(e["G_GAN"] == 0 and e["G_final"] > 0 for e in log),
          f"indirect mode: L1 {np.mean(l1[:5]):.4f} -> {np.mean(l1[-5:]):.4f}; no GAN term, final-image term on")
    model_path = work / "indirect.safetensors"
    run([sys.executable, "-m", EXPORT_MODULE, "--run", work / "run_ind", "--out", model_path])
    _, cfg = model_file.read_model(str(model_path))
    check(cfg["output_mode"] == "indirect", "export: output_mode indirect in the model file")
    model = ngi_py.Model(dev, str(model_path))
    check(model.output_mode == "indirect", "ngi.Model reads the mode")
    got = pipe.run(model, frame, outputs=("lightmap",))["lightmap"]
    x = pipe.network_input(frame, model)
    out, _ = reference_output(model_path, x)
    want = (lightmap_loss.clean_light(torch.from_numpy(frame.feature("direct")[0]).double())
            + lightmap_loss.decode(data.crop_front(torch.from_numpy(out).double(), n, "surround"))[0]).numpy()
    err = float(np.max(np.abs(got - want) / (1e-3 + np.abs(want))))
    check(err < 1e-4, f"indirect mode: ngi lightmap == direct + decoded PyTorch output, max relative |diff| {err:.2g}")


def test_ssgi_residual_mode(ngi, dataset, work):
    """Layout ssgi_residual (issue 45; docs/CONVENTIONS.md section 8): a network that corrects the SSGI rung."""
    import ngi as ngi_py
    dev = ngi_py.Device("")
    cfg_path = work / "residual.json"
    cfg_path.write_text(json.dumps(dict(TRAIN, layout="ssgi_residual", steps=20, output_mode="indirect",
                                        lambda_final=100, lambda_gan=0, eval_every=0)))
    train(cfg_path, dataset, work / "run_res", ngi)
    l1 = [e["G_L1"] for e in read_log(work / "run_res")]
    check(np.mean(l1[-5:]) < np.mean(l1[:5]), f"ssgi_residual: L1 {np.mean(l1[:5]):.4f} -> {np.mean(l1[-5:]):.4f}")
    model_path = work / "residual.safetensors"
    run([sys.executable, "-m", EXPORT_MODULE, "--run", work / "run_res", "--out", model_path])
    _, cfg = model_file.read_model(str(model_path))
    base = ngi_py.Model(dev, data.SSGI_BASES["ssgi_residual"]).config["metadata"]
    check(cfg["output_mode"] == "ssgi_residual" and cfg["input_layout"] == data.SSGI_RESIDUAL_CHANNELS
          and all(cfg["ssgi"][k] == base[k] for k in cfg["ssgi"]),
          f"export: output_mode ssgi_residual, 13 input channels, the gather of ssgi_surround: {cfg['ssgi']}")
    model = ngi_py.Model(dev, str(model_path))
    worst = 0.0
    train_frames = data.list_frames(dataset, "train")
    for rel in train_frames + data.list_frames(dataset, "test"):
        frame = ngi_py.read_frame(str(dataset / rel))
        pipe = ngi_py.Pipeline(dev, frame.n)
        x = pipe.network_input(frame, model)
        if rel in train_frames:  # what training read (the merge cache) is what the model gets in ngi
            cached = np.load(data.default_cache_dir(dataset, "ssgi_residual") / rel / "input.npy")
            check(np.array_equal(x, cached), f"{rel}: the training input is the pipeline's, bit for bit")
        got = pipe.run(model, frame, outputs=("lightmap",))["lightmap"]
        out, _ = reference_output(model_path, x)
        v = torch.from_numpy(out).double() + torch.from_numpy(x[:, data.SSGI_CHANNELS]).double()
        want = (lightmap_loss.clean_light(torch.from_numpy(frame.feature("direct")[0]).double())
                + lightmap_loss.decode(v)[0]).numpy()
        worst = max(worst, float(np.max(np.abs(got - want) / (1e-3 + np.abs(want)))))
    check(worst < 1e-4, f"ssgi_residual: ngi lightmap == direct + decode(PyTorch output + SSGI channels), max relative "
                        f"|diff| {worst:.2g}")


def scoring_compose(frame, light):
    import ngi.scoring as scoring
    return scoring.compose(frame, light)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ngi", help="ngi binary (default: $NGI_BIN or build*/ngi)")
    ap.add_argument("--work", default="/tmp/ngi_training_smoke", help="scratch folder (emptied first)")
    args = ap.parse_args()
    t_start = time.monotonic()
    ngi = ngi_paths.find_ngi(args.ngi)
    work = Path(args.work).resolve()
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)

    # 1. Dataset.
    (work / "dataset.json").write_text(json.dumps(DATASET))
    dataset = work / "data"
    _, secs = run([ngi, "dataset", "--config", work / "dataset.json", "--out", dataset])
    check(len(data.list_frames(dataset, "train")) == 2 and len(data.list_frames(dataset, "test")) == 1,
          f"ngi dataset rendered 2 + 1 frames ({secs:.1f} s)")

    # 2. Loader == ngi merge.
    test_loader(ngi, dataset, work)

    # 3. Training: the L1 term falls.
    cfg_path = work / "surround.json"
    cfg_path.write_text(json.dumps(dict(TRAIN, layout="surround")))
    _, secs = train(cfg_path, dataset, work / "run_a", ngi)
    log = read_log(work / "run_a")
    l1 = [e["G_L1"] for e in log]
    first, last = float(np.mean(l1[:5])), float(np.mean(l1[-5:]))
    print(f"L1 per step: {' '.join(f'{v:.4f}' for v in l1)}")
    check(len(l1) == TRAIN["steps"] and last < 0.9 * first,
          f"L1 falls over {len(l1)} steps: mean of the first 5 {first:.4f}, of the last 5 {last:.4f} ({secs:.1f} s)")
    check(sorted(p.name for p in (work / "run_a" / "checkpoints").iterdir())
          == ["latest.pt", "step_00000020.pt", "step_00000040.pt"], "checkpoints: latest + every keep_every")

    # 4. Ctrl-C and resume == one uninterrupted run.
    run_b = work / "run_b"
    proc = subprocess.Popen([sys.executable, "-m", TRAIN_MODULE, "--config", cfg_path, "--dataset", dataset,
                             "--run", run_b, "--ngi", ngi, "--steps", "100000"], env=ngi_paths.ngi_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if (run_b / "log.jsonl").is_file() and (run_b / "log.jsonl").read_text().count("\n") >= 3:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    stopped = torch.load(run_b / "checkpoints" / "latest.pt")["step"]
    check(proc.returncode == 128 + signal.SIGINT and 3 <= stopped < 100000 and len(read_log(run_b)) == stopped,
          f"SIGINT: exit {proc.returncode}, checkpoint at step {stopped}, log has {stopped} steps")
    target = stopped + 12
    train(cfg_path, dataset, run_b, ngi, "--steps", target)
    train(cfg_path, dataset, work / "run_c", ngi, "--steps", target)
    sb = torch.load(run_b / "checkpoints" / "latest.pt")
    sc = torch.load(work / "run_c" / "checkpoints" / "latest.pt")
    same = all(torch.equal(sb["model"][net][k], sc["model"][net][k]) for net in ("G", "D") for k in sc["model"][net])
    strip = lambda log: [{k: v for k, v in e.items() if k != "seconds"} for e in log]  # noqa: E731
    check(same and sb["step"] == sc["step"] == target and strip(read_log(run_b)) == strip(read_log(work / "run_c"))
          and torch.equal(sb["torch_rng"], sc["torch_rng"]),
          f"interrupted at {stopped} + resumed to {target} == uninterrupted: same weights, losses, RNG state")

    # 5. Export, ngi generate parity, ngi lightmap, evaluate.py.
    model, worst_s = test_export_and_run(ngi, dataset, work, work / "run_a", "surround")
    proc, _ = run([sys.executable, "-m", EVALUATE_MODULE, "--model", model, "--dataset", dataset, "--split", "test",
                   "--out", work / "eval", "--ngi", ngi])
    summary = json.loads((work / "eval" / "summary.json").read_text())
    check(summary["frames"] == 1 and summary["network"]["final_ldr"]["ssim"] is not None,
          "evaluate.py: summary over the test split")

    # 6b. The indirect output mode.
    test_indirect_mode(ngi, dataset, work)
    # 6c. A network that corrects SSGI.
    test_ssgi_residual_mode(ngi, dataset, work)

    # 6. Single view.
    cfg_sv = work / "single_view.json"
    cfg_sv.write_text(json.dumps(dict(TRAIN, layout="single_view", steps=20)))
    train(cfg_sv, dataset, work / "run_sv", ngi)
    l1_sv = [e["G_L1"] for e in read_log(work / "run_sv")]
    check(np.mean(l1_sv[-5:]) < np.mean(l1_sv[:5]),
          f"single view: L1 {np.mean(l1_sv[:5]):.4f} -> {np.mean(l1_sv[-5:]):.4f} over 20 steps")
    _, worst_v = test_export_and_run(ngi, dataset, work, work / "run_sv", "single_view")

    # 7. Seed 001's AO MLP: tiny orbit data, a short training, and `ngi ao` == the exported network in PyTorch
    # on the ring inputs sampling.py builds (the Python and the C++ ring conventions agree).
    aod = work / "aod"
    run([ngi, "ao-data", "--scene", "sculpture:seed=1", "--out", aod, "--views", 6, "--heldout-views", 1, "--n", 48,
         "--rays", 16])
    ao_model = work / "ao_16x8.safetensors"
    proc, _ = run([sys.executable, "-m", AO_TRAIN_MODULE, "--data", aod, "--size", "16x8", "--out", ao_model,
                   "--max-iters", 40])
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    check(report["parameters"] == 929 and report["test_mse"] < 0.2,
          f"ngi_train.ao.train: 16x8, test MSE {report['test_mse']:.4f}")
    view = aod / "heldout" / "v0000"
    run([ngi, "ao", "--frame", view, "--model", ao_model, "--out", work / "ao_out"])
    got = np.load(work / "ao_out" / "ao.npy")[0]
    v = sampling.load_view(view)
    x, rows, cols = sampling.image_inputs(v, 3.0)  # the model's radius at its own size
    tensors, config = model_file.read_model(ao_model)
    h = reference_models.run_mlp_reference(tensors, config, x)
    want = np.ones_like(got)
    want[rows, cols] = h[:, 0].clamp(0, 1).numpy()
    ao_diff = float(np.abs(got - want).max())
    check(ao_diff < 1e-4 and (~v["mask"]).sum() > 0 and np.all(got[~v["mask"]] == 1.0),
          f"ngi ao == PyTorch on ao_common's ring inputs: max |diff| {ao_diff:.2g}; background 1")

    print(f"training_smoke: all checks passed in {time.monotonic() - t_start:.1f} s "
          f"(L1 {first:.4f} -> {last:.4f}; ngi generate vs PyTorch max |diff| surround {worst_s:.2g}, "
          f"single view {worst_v:.2g})")


if __name__ == "__main__":
    main()

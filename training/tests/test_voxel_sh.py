#!/usr/bin/python3
"""Smoke test of seed 004's training (ngi_train.voxel_sh) against ngi's voxel_sh runner (< 1 min on 2 cores).

    PYTHONPATH=training:build/python /usr/bin/python3 training/tests/test_voxel_sh.py [--work DIR] [--device cpu]

1. data: synthetic scene folders of the generator's format load; the statistics come from the training scenes
   only; a scene of another grid is refused, naming both grids (load_scenes and train.py);
2. networks: the set network's split rho.0 equals the literal broadcast-and-concatenate form; the model-file
   config helper refuses bad fields;
3. train.py (set network): a few steps, SIGINT mid-run (exit 130, checkpoint kept), resume to the end: the weights
   and the log equal those of an uninterrupted run, bit for bit; the loss falls; export.py from the work folder;
4. every architecture (set F32, mlp F16, resnet F32): the exported file loaded in ngi (Python bindings) on the test
   scene equals ngi.voxel_sh.VoxelSh in float64 on the stored weights (max |diff| <= 1e-4 + 1e-4 |y|); NaN inputs are
   counted; the card and the metadata say what was trained.
Exit code 0 on success; an AssertionError (exit 1) names the failed check.
"""

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

import ngi
import ngi.model_file as model_file
import ngi.voxel_sh as networks

from ngi_train.voxel_sh import data
GRID = (12, 10, 8)
# ngi (float32, GEMM summation order) against float64 PyTorch on the same weights: ~1e-6 observed
# (tests/test_voxel_sh_model.cpp); 1e-4 absolute + relative leaves room without letting a wrong layer through.
TOL = 1e-4


def check(cond, what):
    if not cond:
        raise AssertionError(what)


def train_cmd(work, out, arch, steps, scenes, extra=()):
    return [sys.executable, "-m", "ngi_train.voxel_sh.train", "--arch", arch, "--train", *scenes["train"], "--test",
            *scenes["test"], "--steps", str(steps), "--work", str(work), "--out", str(out),
            "--card", str(out) + ".md", "--log-every", "2", "--checkpoint-every", "4", "--threads", "1", *extra]


def run(cmd):
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
    return proc


def make_data(root):
    scenes = {"train": [], "test": []}
    for i in range(3):
        scenes["train"].append(str(data.make_synthetic_scene(root / f"train{i}", GRID, voxels=300, seed=i)))
    scenes["test"].append(str(data.make_synthetic_scene(root / "test0", GRID, voxels=257, seed=10)))
    other = str(data.make_synthetic_scene(root / "other_grid", (16, 16, 16), voxels=300, seed=20))
    return scenes, other


def test_data(scenes, other):
    train = data.load_scenes(scenes["train"])
    check(all(s.grid == GRID and s.attributes.shape == (300, 10) and s.sh.shape == (300, 27) for s in train),
          "synthetic scenes load with their grid and shapes")
    stats = data.Stats.from_scenes(train)
    x = np.concatenate([s.attributes for s in train])
    check(np.array_equal(stats.input_lo, x.min(0).astype(np.float64)), "input_lo = the training scenes' minimum")
    test = data.load_scenes(scenes["test"])
    check(not np.array_equal(data.Stats.from_scenes(test).input_hi, stats.input_hi), "test statistics differ")
    try:
        data.load_scenes(scenes["train"] + [other])
        raise AssertionError("a scene of another grid was accepted")
    except ValueError as e:
        check("16x16x16" in str(e) and "12x10x8" in str(e), f"the grid error names both grids: {e}")


def test_networks():
    torch.manual_seed(0)
    net = networks.build("set", phi=[16, 8], rho=[12]).double()
    x = torch.rand(37, 10, dtype=torch.float64) * 2 - 1
    d = (net(x) - net.forward_concat(x)).abs().max().item()
    check(d < 1e-12, f"split rho.0 == broadcast concat (max diff {d})")
    check(networks.parameter_count(networks.build("set")) == sum(
        int(np.prod(s)) for s in model_file.voxel_sh_shapes({"architecture": "set", **networks.DEFAULT_WIDTHS["set"]})
        .values()), "ngi.voxel_sh and model_file.voxel_sh_shapes agree")
    base = dict(grid=[8, 8, 8], input_lo=[0] * 10, input_hi=[1] * 10, output_mean=[0] * 27, output_std=[1] * 27)
    for bad, fragment in ((dict(base, input_lo=[0] * 9), "input_lo"), (dict(base, grid=[8, 8]), "grid"),
                          (dict(base, output_std=[-1] * 27), "output_std")):
        try:
            model_file.make_voxel_sh_config("mlp", hidden=[4], **bad)
            raise AssertionError(f"make_voxel_sh_config accepted a bad {fragment}")
        except model_file.ConversionError as e:
            check(fragment in str(e), f"error names {fragment}: {e}")
    try:
        model_file.make_voxel_sh_config("resnet", width=4, blocks=1, hidden=[3], **base)
        raise AssertionError("a stray width field was accepted")
    except model_file.ConversionError:
        pass


def test_train_resume(root, scenes):
    """Straight run vs. interrupted + resumed run: the same weights and log."""
    straight = root / "work_straight"
    t0 = time.monotonic()
    run(train_cmd(straight, root / "set_straight.safetensors", "set", 12, scenes))
    seconds = time.monotonic() - t0

    work = root / "work_interrupted"
    cmd = train_cmd(work, root / "set.safetensors", "set", 12, scenes)
    cmd[cmd.index("--log-every") + 1] = "1"
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    log = work / "log.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if log.is_file() and len(log.read_text().splitlines()) >= 2:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    stopped_at = None
    if proc.returncode == 0:
        print("  (the run finished before the signal: resume not exercised by SIGINT)")
    else:
        check(proc.returncode == 128 + signal.SIGINT, f"SIGINT exits 130, got {proc.returncode}:\n{err}")
        state = torch.load(work / "checkpoint.pt")
        stopped_at = state["step"]
        check(0 < stopped_at < 12, f"the stop saved a checkpoint mid-run (step {stopped_at})")
        check("stopped at step" in err, "the stop says where it stopped")
    # Resume with the straight run's log cadence (log_every may change on resume).
    resumed = run(train_cmd(work, root / "set.safetensors", "set", 12, scenes))
    check("resuming at step" in resumed.stderr or proc.returncode == 0, "the second run resumed")

    a, b = torch.load(straight / "checkpoint.pt"), torch.load(work / "checkpoint.pt")
    check(a["step"] == b["step"] == 12, "both runs reached step 12")
    check(all(torch.equal(a["model"][k], b["model"][k]) for k in a["model"]), "resumed weights == straight weights")
    logs = [{json.loads(line)["step"]: json.loads(line) for line in (w / "log.jsonl").read_text().splitlines()}
            for w in (straight, work)]
    for step in (2, 4, 12):
        check(logs[0][step]["train_mse"] == logs[1][step]["train_mse"], f"log at step {step} equal after resume")
    first, last = logs[0][2]["train_mse"], logs[0][12]["train_mse"]
    check(last < first, f"the training MSE falls ({first:.4f} -> {last:.4f})")
    # export.py from the work folder writes the same network train.py exported.
    run([sys.executable, "-m", "ngi_train.voxel_sh.export", "--work", str(work),
         "--out", str(root / "set_export.safetensors")])
    t1, _ = model_file.read_model(str(root / "set.safetensors"))
    t2, c2 = model_file.read_model(str(root / "set_export.safetensors"))
    check(all(np.array_equal(t1[k], t2[k]) for k in t1) and list(t1) == list(t2), "export.py == train.py's export")
    check(c2["grid"] == list(GRID), "the exported grid is the scenes'")
    print(f"  train 12 steps: {seconds:.1f} s; straight == interrupted (SIGINT at step {stopped_at}) + resumed, "
          "bit for bit")


def test_other_grid_refused(root, scenes, other):
    proc = subprocess.run(train_cmd(root / "work_bad", root / "bad.safetensors", "mlp", 2,
                                    {"train": scenes["train"], "test": [other]}), capture_output=True, text=True)
    check(proc.returncode != 0 and "16x16x16" in proc.stderr and "12x10x8" in proc.stderr,
          f"train.py refuses a test scene of another grid, naming both:\n{proc.stderr[-400:]}")


def ngi_output(model, attributes):
    """Model.run on [V, 10]: the bindings' run takes [1, C, H, W] for this family, so [1, 10, 1, V] (planar)."""
    v = len(attributes)
    y = model.run(np.ascontiguousarray(attributes.T.reshape(1, 10, 1, v)))
    return y.reshape(27, v).T


def test_ngi_parity(root, scenes, device):
    test_scene = data.load_scene(scenes["test"][0])
    dev = ngi.Device(device)
    for arch, half in (("set", False), ("mlp", True), ("resnet", False)):
        path = root / f"{arch}.safetensors"
        if arch != "set":
            extra = ["--half"] if half else []
            extra += {"mlp": ["--hidden", "24,16"], "resnet": ["--width", "16", "--blocks", "3"]}[arch]
            run(train_cmd(root / f"work_{arch}", path, arch, 4, scenes, extra))
        tensors, config = model_file.read_model(str(path))
        check(config["architecture"] == arch and config["training"]["steps"] in (4, 12), "metadata says what ran")
        check(Path(str(path) + ".md").is_file(), "model card written")
        net = networks.from_config(config).double()
        net.load_state_dict({k: torch.from_numpy(v.astype(np.float64)) for k, v in tensors.items()})
        standardize = networks.Standardization(config["input_lo"], config["input_hi"], config["output_mean"],
                                               config["output_std"]).double()
        with torch.no_grad():
            want = networks.VoxelSh(net, standardize)(torch.from_numpy(test_scene.attributes).double()).numpy()
        model = ngi.Model(dev, str(path))
        check(model.config["family"] == "voxel_sh" and model.config["metadata"]["grid"] == list(GRID),
              "ngi reads the family and the grid")
        got = ngi_output(model, test_scene.attributes)
        err = np.abs(got - want)
        check((err <= TOL + TOL * np.abs(want)).all(), f"{arch}: ngi == PyTorch (max |diff| {err.max():.3g})")
        bad = test_scene.attributes.copy()
        bad[3, 4] = np.nan
        bad[7, 0] = np.inf
        check(np.isfinite(ngi_output(model, bad)).all() and model.sanitized_inputs == 2, "NaN/Inf counted")
        print(f"  {arch} ({'F16' if half else 'F32'}): max |ngi - PyTorch float64| {err.max():.3g} "
              f"on {len(want)} voxels")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", help="scratch folder (default: a temporary one, removed afterwards)")
    ap.add_argument("--device", default=os.environ.get("NGI_TEST_DEVICE", "cpu"))
    a = ap.parse_args(argv)
    root = Path(a.work) if a.work else Path(tempfile.mkdtemp(prefix="voxel_sh_smoke_"))
    if root.exists():
        shutil.rmtree(root)
    root.mkdir(parents=True)
    t0 = time.monotonic()
    try:
        scenes, other = make_data(root)
        for name, fn in (("data", lambda: test_data(scenes, other)), ("networks", test_networks),
                         ("train, interrupt, resume, export", lambda: test_train_resume(root, scenes)),
                         ("another grid refused", lambda: test_other_grid_refused(root, scenes, other)),
                         ("ngi == PyTorch", lambda: test_ngi_parity(root, scenes, a.device))):
            t = time.monotonic()
            fn()
            print(f"ok: {name} ({time.monotonic() - t:.1f} s)", flush=True)
    finally:
        if not a.work:
            shutil.rmtree(root, ignore_errors=True)
    print(f"voxel_sh smoke test passed in {time.monotonic() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

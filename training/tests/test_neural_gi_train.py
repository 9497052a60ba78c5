"""Tests of seed 002's data, trainer and evaluation (ngi_train.neural_gi.{data,train,evaluate}) on a tiny dataset
that `ngi dataset` renders into a temporary folder (6 frames of bleed:seed=1 at N = 32 with an area light, low
spp). About a minute on one thread.

    NGI_BIN=build/ngi PYTHONPATH=training:build/python /usr/bin/python3 -m pytest -q \
        training/tests/test_neural_gi_train.py
"""

import json
import math
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import torch

import ngi
import ngi.model_file as model_file

from ngi_train import ngi_paths
from ngi_train.neural_gi import data, evaluate, networks, sequences, train

torch.set_num_threads(1)

FRAMES, HELD_OUT = 6, 2
CONFIG = {"n": 32, "feature_spp": 4, "reference_spp": 16, "max_bounces": 2, "frames_per_scene": FRAMES,
          "keyframe_interval": 1,
          "area_light": {"centre_min": [4.5, 6.5, 4.5], "centre_max": [14.5, 7.8, 13.5], "size_min": 1.0,
                         "size_max": 3.0, "radiance": [60, 56, 50], "facing": "down"},
          "train": [{"scene": "bleed:seed=1", "time": 0}], "test": []}
SMALL = ["--buffer-channels", "4", "--ngf", "8", "--num-downs", "5", "--mlp-width", "32", "--mlp-depth", "4",
         "--skip-layer", "2"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("neural_gi")
    cfg = root / "config.json"
    cfg.write_text(json.dumps(CONFIG))
    out = root / "data"
    subprocess.run([ngi_paths.find_ngi(), "dataset", "--config", str(cfg), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ngi_paths.ngi_env())
    return out


def scene_dir(dataset):
    return dataset / "train" / "bleed_seed1"


def train_cmd(dataset, work, steps, extra=()):
    return [sys.executable, "-m", "ngi_train.neural_gi.train", "--dataset", str(dataset),
            "--test-frames", str(HELD_OUT),
            "--work", str(work), "--out", str(work / "model.safetensors"), "--steps", str(steps), "--log-every", "1",
            "--eval-every", "4", "--eval-frames", "2", "--checkpoint-every", "5", "--threads", "1", *SMALL, *extra]


def run(cmd):
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr[-3000:]}"
    return proc


# --------------------------------------------------------------------------
# Frame -> inputs
# --------------------------------------------------------------------------

def hand_position(cam, depth, col, row, n):
    """Plain-Python world position of pixel (col, row): centre + depth (look + u right + v up), right = look x up,
    with up orthogonalized against look (CONVENTIONS section 1)."""
    look = np.array(cam["look"], float)
    look /= math.sqrt(sum(look ** 2))
    up = np.array(cam["up"], float)
    up = up - (up @ look) * look
    up /= math.sqrt(sum(up ** 2))
    right = np.array([look[1] * up[2] - look[2] * up[1], look[2] * up[0] - look[0] * up[2],
                      look[0] * up[1] - look[1] * up[0]])
    u = 2.0 * (col + 0.5) / n - 1.0
    v = 1.0 - 2.0 * (row + 0.5) / n
    ray = look + u * right + v * up
    return np.array(cam["position"]) + depth * ray, ray


def test_inputs_match_hand_computation(dataset):
    frames = data.list_scene_frames(scene_dir(dataset))
    assert len(frames) == FRAMES
    f = frames[3]
    arr = data.decode_frame(f)
    cam = json.loads((f / "camera.json").read_text())
    depth, _ = ngi.read_exr(str(f / "front_depth.exr"))
    n = depth.shape[-1]
    for col, row in ((0, 0), (5, 27), (16, 16), (31, 2), (20, 31)):
        p, ray = hand_position(cam, float(depth[0, row, col]), col, row, n)
        got = arr[data.SLICES["position"], row, col]
        assert np.allclose(got, p, atol=1e-4), f"pixel ({col}, {row}): position {got} != hand {p}"
        light = np.array(cam["area_light"]["centre"]) - p
        assert np.allclose(arr[data.SLICES["light_dir"], row, col], light / np.linalg.norm(light), atol=1e-5)
        assert np.allclose(arr[data.SLICES["view"], row, col], ray / np.linalg.norm(ray), atol=1e-5)
    # Physical check independent of the formula: a surface pixel whose (axis-aligned) normal is along axis k lies
    # on a block face, i.e. its k coordinate is an integer (blocks are unit cubes at integer corners).
    normal = arr[data.SLICES["normal"]]
    mask = arr[data.SLICES["mask"]][0] > 0.5
    axis = np.abs(normal).argmax(axis=0)
    coord = np.take_along_axis(arr[data.SLICES["position"]], axis[None], axis=0)[0]
    off = np.abs(coord - np.round(coord))[mask]
    assert mask.sum() > 100 and np.percentile(off, 99) < 2e-3, f"positions off the block faces: {off.max()}"
    # The box: scene.json's size, and the inputs' positions normalized into it.
    lo, hi = data.scene_box(scene_dir(dataset))
    assert lo == [0.0, 0.0, 0.0] and hi == [19.0, 9.0, 18.0]
    x, direct, ref, m = data.to_tensors(arr, lo, hi)
    assert x.shape == (1, 18, n, n) and direct.shape == ref.shape == (1, 3, n, n)
    want = 2 * arr[data.SLICES["position"], 16, 16] / np.array(hi) - 1
    assert np.allclose(x[0, 0:3, 16, 16].numpy(), want, atol=1e-5)
    assert torch.allclose(x[0, 12:15], torch.log1p(direct[0]) * m[0])


def test_sky_is_masked(dataset, tmp_path):
    """Pixels with the renderer's sky depth (1e4) get mask 0 and the loss ignores them; their inputs are assembled
    as kernels/neural_gi.cl does (a point 1e4 m along the ray: position clamped to the box's faces)."""
    src = data.list_scene_frames(scene_dir(dataset))[0]
    f = tmp_path / "0000"
    shutil.copytree(src, f)
    depth, _ = ngi.read_exr(str(f / "front_depth.exr"))
    rendered_sky = depth[0] >= data.SKY_DEPTH  # the renderer's own sky pixels (this frame sees the skylight)
    depth = depth.copy()
    depth[:, :5, :] = data.SKY_DEPTH  # and the top 5 rows see the sky too
    ngi.write_exr(str(f / "front_depth.exr"), depth, half=False)
    arr = data.decode_frame(f)
    mask = arr[data.SLICES["mask"]][0]
    sky = rendered_sky.copy()
    sky[:5] = True
    assert np.array_equal(mask, (~sky).astype(np.float32)), "mask = 0 exactly on the sky pixels"
    assert 0 < (~sky).sum() < sky.size
    lo, hi = data.scene_box(scene_dir(dataset))
    x, direct, ref, m = data.to_tensors(arr, lo, hi)
    sky_t = torch.from_numpy(sky)
    assert (x[0, 0:3][:, sky_t].abs().amax(0) == 1).all(), "sky positions are far outside the box: clamped"
    real = torch.from_numpy(rendered_sky)  # the renderer's sky (the top rows above only had their depth changed)
    assert real.any(), "frame 0 of this dataset sees the skylight"
    assert (x[0, 3:9][:, real] == 0).all() and (x[0, 12:15][:, real] == 0).all(), "no normal, albedo, direct"
    assert (x[0, 3:6][:, ~sky_t].abs().sum(0) > 0).all()
    pred = ref + 0.1
    base = data.masked_log_l1(pred, ref, m)
    ref2 = ref.clone()
    ref2[..., :5, :] = 1e6  # what the sky pixels hold does not matter
    assert float(data.masked_log_l1(pred, ref2, m)) == float(base)
    ref3 = ref.clone()
    ref3[..., 10, :] = 1e6  # a surface pixel does
    assert float(data.masked_log_l1(pred, ref3, m)) > float(base)


# --------------------------------------------------------------------------
# Training
# --------------------------------------------------------------------------

def read_log(work):
    return [json.loads(line) for line in (work / "log.jsonl").read_text().splitlines()]


def test_training_lowers_the_loss_on_one_frame(dataset, tmp_path):
    work = tmp_path / "one"
    cmd = train_cmd(dataset, work, 30, ["--lr", "1e-3"])
    cmd[cmd.index("--test-frames") + 1] = str(FRAMES - 1)  # one training frame
    cmd[cmd.index("--eval-every") + 1] = "1"
    run(cmd)
    log = read_log(work)
    first, last = log[0]["train_eval_loss"], log[-1]["train_eval_loss"]
    assert last < 0.7 * first, f"30 steps on one frame: loss {first:.4f} -> {last:.4f}"
    assert all("heldout_loss" in line and "seconds" in line for line in log)


def test_interrupt_and_resume_is_bit_exact(dataset, tmp_path):
    steps = 14
    straight = tmp_path / "straight"
    run(train_cmd(dataset, straight, steps))

    work = tmp_path / "interrupted"
    proc = subprocess.Popen(train_cmd(dataset, work, steps), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        log = work / "log.jsonl"
        if log.is_file() and len(log.read_text().splitlines()) >= 3:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGINT, f"SIGINT exits 130, got {proc.returncode}:\n{err[-2000:]}"
    state = torch.load(work / "checkpoint.pt")
    assert 0 < state["step"] < steps and "stopped at step" in err
    assert not (work / "model.safetensors").exists()
    resumed = run(train_cmd(dataset, work, steps))
    assert f"resuming at step {state['step']}" in resumed.stderr

    a, b = torch.load(straight / "checkpoint.pt"), torch.load(work / "checkpoint.pt")
    assert a["step"] == b["step"] == steps
    assert all(torch.equal(a["model"][k], b["model"][k]) for k in a["model"]), "resumed weights != straight"
    sa, sb = a["optimizer"]["state"], b["optimizer"]["state"]
    assert all(torch.equal(sa[i]["exp_avg_sq"], sb[i]["exp_avg_sq"]) for i in sa)
    la, lb = read_log(straight), read_log(work)
    assert [x["step"] for x in la] == [x["step"] for x in lb] == list(range(1, steps + 1))
    for x, y in zip(la, lb):
        assert x["train_loss"] == y["train_loss"] and x.get("heldout_loss") == y.get("heldout_loss")
    ta, _ = model_file.read_model(str(straight / "model.safetensors"))
    tb, _ = model_file.read_model(str(work / "model.safetensors"))
    assert list(ta) == list(tb) and all(np.array_equal(ta[k], tb[k]) for k in ta)

    # A changed setting is refused, naming it.
    bad = subprocess.run(train_cmd(dataset, work, steps, ["--lr", "3e-4"]), capture_output=True, text=True)
    assert bad.returncode != 0 and "lr" in bad.stderr


def test_export_and_evaluate(dataset, tmp_path):
    work = tmp_path / "exp"
    run(train_cmd(dataset, work, 3))
    path = work / "model.safetensors"
    config = model_file.read_config(str(path))
    assert config["family"] == "neural_gi" and config["bn_mode"] == "per_image"
    assert config["neural_gi"]["buffer_channels"] == 4 and config["num_downs"] == 5
    assert train.box_of_config(config) == ([0.0, 0.0, 0.0], [19.0, 9.0, 18.0])
    assert config["training"]["sky"]["depth_min"] == data.SKY_DEPTH_MIN
    tensors, _ = model_file.read_model(str(path))
    assert all(v.dtype == np.float16 for v in tensors.values()), "F16 by default"

    out = tmp_path / "eval.json"
    run([sys.executable, "-m", "ngi_train.neural_gi.evaluate", "--dataset", str(dataset),
         "--test-frames", str(HELD_OUT),
         "--model", str(path), "--out", str(out)])
    result = json.loads(out.read_text())
    assert result["frames"] == HELD_OUT and len(result["per_frame"]) == HELD_OUT
    assert [r["frame"] for r in result["per_frame"]] == [f"bleed_seed1/{k:04d}" for k in range(4, 6)]
    for method in ("model", "direct_only"):
        s = result["summary"][method]
        assert s["log_l1"] > 0 and 0 < s["final"]["mse"] < 1 and s["final"]["psnr"] is not None
    # direct only misses the indirect light: its lighting is below the reference on average.
    assert result["summary"]["direct_only"]["lighting"]["mae"] > 0


def test_no_buffer_baseline_exports_an_equivalent_neural_gi(dataset, tmp_path):
    torch.manual_seed(3)
    net = networks.NoBufferGI(mlp_width=32, mlp_depth=4, skip_layer=2)
    for p in net.parameters():
        p.data.normal_(0, 0.1)
    full = networks.no_buffer_as_neural_gi(net)
    x = torch.rand(1, 18, 32, 32) * 2 - 1
    with train.per_image_bn(full):
        a, b = net.raw_output(x), full.raw_output(x)
    assert torch.allclose(a, b, atol=1e-5, rtol=1e-5), (a - b).abs().max()
    # and through train.py: --no-buffer trains and writes a neural_gi file
    work = tmp_path / "nb"
    run(train_cmd(dataset, work, 2, ["--no-buffer"]))
    config = model_file.read_config(str(work / "model.safetensors"))
    assert config["neural_gi"]["buffer_channels"] == 1 and config["training"]["run"]["no_buffer"] is True


def test_unet_only_baseline_exports_an_equivalent_neural_gi(dataset, tmp_path):
    torch.manual_seed(4)
    net = networks.UnetOnlyGI(ngf=8, num_downs=5)
    for p in net.parameters():
        p.data.normal_(0, 0.1)
    full = networks.unet_as_neural_gi(net)
    x = torch.rand(1, 18, 32, 32) * 2 - 1
    with train.per_image_bn(net), train.per_image_bn(full):
        a, b = net.raw_output(x), full.raw_output(x)
    assert torch.equal(a, b), (a - b).abs().max()  # the pass-through MLP is exact, not approximately equal
    # through train.py: --unet-only trains and writes a neural_gi file that ngi runs like PyTorch
    work = tmp_path / "unet"
    run(train_cmd(dataset, work, 2, ["--unet-only"]))
    path = work / "model.safetensors"
    config = model_file.read_config(str(path))
    assert config["neural_gi"]["buffer_channels"] == 3 and config["training"]["run"]["unet_only"] is True
    arr = data.cached_frame(scene_dir(dataset) / "0005", tmp_path / "cache", "0005")
    box = train.box_of_config(config)
    inputs, _, _, _ = data.to_tensors(arr, *box)
    torch_out = evaluate.Predictor(path, "torch", None)(inputs)
    ngi_out = evaluate.Predictor(path, "ngi", ngi.Device("cpu"))(inputs)
    # F16 weights in both; ngi accumulates in another order: a relative difference of float32 rounding
    err = np.abs(ngi_out - torch_out) / (np.abs(torch_out) + 1e-3)
    assert float(err.max()) < 1e-3, float(err.max())
    with pytest.raises(SystemExit):
        train.parse_args(["--dataset", "d", "--work", "w", "--out", "o", "--no-buffer", "--unet-only"])


def test_ngi_on_frames_matches_training(dataset, tmp_path):
    """Training and inference assemble the inputs independently (data.py + ngi.neural_gi.assemble_inputs here,
    kernels/neural_gi.cl in `ngi neural-gi`): the same exported model on the same held-out frame must give the same
    indirect light. F16 weights in both; float32 both; per-image batch norm."""
    work = tmp_path / "cli"
    run(train_cmd(dataset, work, 3))
    path = work / "model.safetensors"
    predictor = evaluate.Predictor(path, "torch", None)
    box = evaluate.model_box(predictor.config)
    frame = scene_dir(dataset) / f"{FRAMES - 1:04d}"
    inputs, _, _, mask = data.to_tensors(data.decode_frame(frame), box[0], box[1])
    want = predictor(inputs)[0]
    out = tmp_path / "ngi_out"
    proc = subprocess.run([ngi_paths.find_ngi(), "neural-gi", "--frame", str(frame), "--model", str(path), "--out",
                           str(out)], capture_output=True, text=True, env=ngi_paths.ngi_env())
    assert proc.returncode == 0, proc.stderr
    got = np.asarray(ngi.read_exr(str(out / "indirect.exr"))[0], np.float32)
    surface = mask[0, 0].numpy() > 0
    assert surface.sum() > 100
    rel = np.abs(got - want)[:, surface] / np.maximum(np.abs(want)[:, surface], 1e-6)
    # Observed 4.5e-6 on PoCL: sin/cos of the encoding and the GEMMs in another order; 1e-3 is far below what a wrong input
    # channel, order or box gives (tens of percent).
    print(f"ngi neural-gi vs PyTorch on a frame: max relative difference {rel.max():.2e}")
    assert rel.max() < 1e-3, rel.max()
    assert np.all(got[:, ~surface] == 0), "no surface: no indirect light"


def test_temporal_mabd_by_hand():
    """evaluate.temporal: MABD_t = mean |Y_t - Y_t-1| per method; mabd_error against the reference's own."""
    ones = np.ones((4, 4))
    lum = {"reference": [0 * ones, 0.1 * ones, 0.3 * ones],
           "model": [0 * ones, 0.1 * ones, 0.1 * ones],  # steps 0.1, 0.0
           "flat": [0.5 * ones] * 3}                      # no change at all
    t = evaluate.temporal(lum)
    assert t["reference"]["mabd_per_step"] == pytest.approx([0.1, 0.2])
    assert t["reference"]["mabd_error"] == 0
    assert t["model"]["mabd"] == pytest.approx(0.05) and t["model"]["mabd_error"] == pytest.approx(0.1)
    assert t["flat"]["mabd"] == 0 and t["flat"]["mabd_error"] == pytest.approx(0.15)
    # luminance: Rec. 709 weights of the displayed RGB
    rgb = np.zeros((3, 2, 2))
    rgb[1] = 1.0
    assert evaluate.luminance(rgb) == pytest.approx(np.full((2, 2), 0.7152))


def test_sequences_plan():
    """sequences.py: the moving light sweeps x across the config's light box at fixed y, z; the camera moves along
    the path from --start-frame; equal-time renders use other seeds than the references."""
    jobs = sequences.plan(CONFIG, 3, [8], 100)
    cam = [j for j in jobs if j[0] == "moving_camera"]
    light = [j for j in jobs if j[0] == "moving_light"]
    pt = [j for j in jobs if j[0] == "moving_light_pt8"]
    assert [j[2][1] for j in cam] == ["100", "101", "102"] and {j[2][1] for j in light} == {"100"}
    xs = [float(j[2][3].split(",")[0]) for j in light]
    assert xs == pytest.approx([4.5, 9.5, 14.5])
    assert {tuple(j[2][3].split(",")[1:]) for j in light} == {("7.15", "9", "1", "0", "0", "0", "0", "1", "60", "56",
                                                                "50")}
    assert {j[3] for j in pt} == {8} and not {j[4] for j in pt} & {j[4] for j in light}
    assert [j[0] for j in jobs].count("noise") == 1


# The two shipped per-scene models (models/neural_gi/README.md) and the scene each was trained on.
SHIPPED = {"neural_gi_bleed.safetensors": ("bleed:seed=1", [19.0, 9.0, 18.0]),
           "neural_gi_room.safetensors": ("room:seed=1", None)}


def test_shipped_models_run_in_ngi_as_in_pytorch(dataset, tmp_path):
    """Each shipped model: F16, per-image BN, its scene box recorded; ngi (PoCL) gives PyTorch's indirect light on a
    frame of the test dataset (bleed:seed=1; the room model sees it through its own box: valid inputs, another
    scene). Tolerance as test_ngi_on_frames_matches_training: 1e-3 relative on surface pixels."""
    root = ngi_paths.REPO / "models" / "neural_gi"
    frame = scene_dir(dataset) / f"{FRAMES - 1:04d}"
    arr = data.decode_frame(frame)
    for name, (spec, box_max) in SHIPPED.items():
        path = root / name
        assert path.is_file(), f"{path} is missing"
        config = model_file.read_config(str(path))
        assert config["family"] == "neural_gi" and config["bn_mode"] == "per_image"
        tensors, _ = model_file.read_model(str(path))
        assert all(v.dtype == np.float16 for v in tensors.values()), name
        box = train.box_of_config(config)
        assert box[0] == [0.0, 0.0, 0.0] and (box_max is None or box[1] == box_max), (name, box)
        assert spec.replace(":", "_").replace("=", "") in config["training"]["run"]["dataset_scene"], name
        inputs, _, _, mask = data.to_tensors(arr, *box)
        want = evaluate.Predictor(path, "torch", None)(inputs)[0]
        got = evaluate.Predictor(path, "ngi", ngi.Device("cpu"))(inputs)[0]
        surface = mask[0, 0].numpy() > 0
        rel = np.abs(got - want)[:, surface] / np.maximum(np.abs(want)[:, surface], 1e-6)
        print(f"{name}: ngi vs PyTorch max relative difference {rel.max():.2e}")
        assert rel.max() < 1e-3, (name, rel.max())

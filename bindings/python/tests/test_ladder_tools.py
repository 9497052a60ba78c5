"""The ladder's Python tools: ngi.scoring (scores as `ngi lightmap` computes them), ngi.temporal (flicker measures),
ngi.zoo (the manifest and its checks) and ngi.plan (the per-scene choice), on the shipped generators.

Run by ctest as part of `python_bindings`.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ngi
import ngi.plan as plan
import ngi.scoring as scoring
import ngi.temporal as temporal
import ngi.zoo as zoo

REPO = Path(__file__).resolve().parents[3]
MODELS = REPO / "models"
CLI = os.environ.get("NGI_CLI")


@pytest.fixture(scope="module")
def dev():
    return ngi.Device(os.environ.get("NGI_TEST_DEVICE", "cpu"))


@pytest.fixture(scope="module")
def frame(dev):
    return ngi.Renderer(dev, ngi.Scene("room:seed=3")).render(n=64, spp=16, feature_spp=4, frame=5)


def test_upsample_is_pytorch_bilinear_half_pixel():
    torch = pytest.importorskip("torch")
    rng = np.random.default_rng(1)
    for h, size in ((5, 13), (32, 64), (7, 7), (1, 4)):
        x = rng.standard_normal((3, h, h)).astype(np.float32)
        want = torch.nn.functional.interpolate(torch.from_numpy(x)[None], size=(size, size), mode="bilinear",
                                               align_corners=False)[0].numpy()
        np.testing.assert_allclose(scoring.upsample(x, size), want, rtol=0, atol=1e-5)
    x = rng.standard_normal((3, 6, 6)).astype(np.float32)
    assert scoring.upsample(x, 6) is not None and np.array_equal(scoring.upsample(x, 6), x)


def test_compose_equals_the_pipelines_final_image(dev, frame):
    model = ngi.Model(dev, MODELS / "surround.safetensors")
    out = ngi.Pipeline(dev, 64).run(model, frame)
    mine = scoring.compose(frame, out["lightmap"])
    np.testing.assert_allclose(mine, out["final"], rtol=1e-6, atol=1e-7)


def test_reference_scores_itself_perfectly_and_the_direct_light_worse(dev, frame):
    ref = scoring.Reference(dev, ngi.Pipeline(dev, 64), frame)
    same = ref.score(frame.reference)
    assert same["final"]["mse"] == 0 and same["final"]["ssim"] == pytest.approx(1.0)
    direct = ref.score(frame.feature("direct")[0])
    assert direct["final"]["mse"] > 0 and direct["final"]["ssim"] < 1
    # A lightmap at half the size is upsampled, not refused; hostile values are sanitized like compose_final's.
    half = frame.reference.reshape(3, 32, 2, 32, 2).mean(axis=(2, 4))
    s = ref.score(half)
    assert s["display"].shape == (3, 64, 64) and 0 < s["final"]["ssim"] < 1 and s["final"]["mse"] > 0
    bad = frame.reference.copy()
    bad[0, 0, 0], bad[1, 0, 0], bad[2, 0, 0] = np.nan, -np.inf, np.inf
    assert np.isfinite(ref.score(bad)["final"]["mse"])
    with pytest.raises(ngi.InputError):
        scoring.Reference(dev, ngi.Pipeline(dev, 8), ngi.Renderer(dev, ngi.Scene("room:seed=3")).render(
            n=8, spp=1, feature_spp=1, reference=False))


def plane_depth(n, d):
    """Planar depth of a wall at distance d facing the camera: constant."""
    return np.full((n, n), d, np.float32)


def test_reprojection_identity_and_sideways_move():
    n = 16
    cam = ((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0))
    rows, cols, z, inside = temporal.reprojection(plane_depth(n, 4.0), cam, cam)
    grid_r, grid_c = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    assert inside.all() and np.array_equal(rows, grid_r) and np.array_equal(cols, grid_c)
    np.testing.assert_allclose(z, 4.0)
    # The previous camera stood 1 m to the right (+x = right for look -z, up +y): a point seen at column c now was
    # seen at c - 1 m / (2 x 4 m / n) = c - 2 columns there.
    prev = ((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0))
    rows, cols, z, inside = temporal.reprojection(plane_depth(n, 4.0), cam, prev)
    assert np.array_equal(cols[inside], (grid_c - 2)[inside]) and np.array_equal(rows, grid_r)
    assert not inside[:, :2].any() and inside[:, 2:].all()
    # Sky pixels and occlusion: a sky pixel is never valid; a nearer surface in t-1 occludes.
    d = plane_depth(n, 4.0)
    d[0, 0] = 1e4
    prev_depth = plane_depth(n, 4.0)
    prev_depth[5, 5] = 1.0
    (r, c, valid), = temporal.warp_masks([prev_depth, d], [cam, cam])
    assert not valid[0, 0] and not valid[5, 5] and valid.sum() == n * n - 2


def test_mabd_and_warp_error():
    rng = np.random.default_rng(2)
    still = [np.full((3, 8, 8), 0.5, np.float32)] * 4
    assert temporal.mabd(still) == 0
    flicker = [np.full((3, 8, 8), 0.5 + 0.1 * (k % 2), np.float32) for k in range(4)]
    assert temporal.mabd(flicker) == pytest.approx(0.1, rel=1e-5)
    cam = ((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0))
    masks = temporal.warp_masks([plane_depth(8, 3.0)] * 4, [cam] * 4)
    assert temporal.warp_error(still, masks) == (0.0, 1.0)
    assert temporal.warp_error(flicker, masks)[0] == pytest.approx(0.1, rel=1e-5)
    noise = [rng.random((3, 8, 8)).astype(np.float32) for _ in range(4)]
    assert temporal.warp_error(noise, masks)[0] > 0.2
    with pytest.raises(ValueError):
        temporal.mabd(still[:1])


def write_zoo(tmp_path, rungs):
    d = tmp_path / "zoo"
    d.mkdir(exist_ok=True)
    shutil.copy(MODELS / "single_view.safetensors", d / "sv.safetensors")
    path = d / "zoo.json"
    path.write_text(json.dumps({"format": "ngi-zoo", "version": 1, "devices": {}, "switches": [], "rungs": rungs}))
    return path


def sv_rung(**over):
    r = {"name": "sv", "file": "sv.safetensors", "sha256": None, "layout": "single_view", "n": 64, "ngf": 32,
         "num_downs": 6, "bn_mode": "per_image", "cost": {}, "accuracy": {}}
    r.update(over)
    return r


DIRECT = {"name": "direct_only", "file": None, "layout": "none", "n": 64, "ngf": 0, "num_downs": 0,
          "bn_mode": "running", "cost": {}, "accuracy": {}}


def test_zoo_checks_files_and_metadata(tmp_path):
    path = write_zoo(tmp_path, [DIRECT, sv_rung(sha256=zoo.sha256(MODELS / "single_view.safetensors"))])
    z = zoo.load(path)
    assert z["rungs"][1]["path"].endswith("sv.safetensors") and z["rungs"][0]["path"] is None
    cases = [
        ([sv_rung(file="gone.safetensors")], "gone.safetensors does not exist"),
        ([sv_rung(ngf=16)], "ngf 32 in sv.safetensors, 16 in the manifest"),
        ([sv_rung(layout="surround")], "input_nc 10 in sv.safetensors, 12 in the manifest"),
        ([sv_rung(sha256="0" * 64)], "differs from the manifest"),
        ([sv_rung(), sv_rung()], "appears twice"),
        ([sv_rung(bn_mode="batch")], "bn_mode 'batch'"),
        ([{k: v for k, v in sv_rung().items() if k != "cost"}], "missing keys ['cost']"),
    ]
    for rungs, message in cases:
        with pytest.raises(zoo.ZooError, match=None) as e:
            zoo.load(write_zoo(tmp_path, rungs))
        assert message in str(e.value) and "rung" in str(e.value), (message, str(e.value))
    (tmp_path / "zoo" / "zoo.json").write_text('{"format": "other"}')
    with pytest.raises(zoo.ZooError, match="not a zoo manifest"):
        zoo.load(tmp_path / "zoo" / "zoo.json")
    with pytest.raises(zoo.ZooError, match="no such file"):
        zoo.load(tmp_path / "nowhere.json")


def run_plan(*args):
    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "ngi.plan", *map(str, args)], capture_output=True, text=True,
                          env=env)


def test_plan_impossible_budget_names_the_closest_rung_and_writes_nothing(tmp_path):
    path = write_zoo(tmp_path, [DIRECT, sv_rung()])
    out = tmp_path / "plan.json"
    dev = os.environ.get("NGI_TEST_DEVICE", "cpu")
    p = run_plan("--scene", "room:seed=3", "--zoo", path, "--min-ssim", "0.9999", "--max-ms", "0.001", "--frames", 1,
                 "--validate", 0, "--spp", 16, "--feature-spp", 4, "--device", dev, "--out", out)
    assert p.returncode == 1, p.stderr
    assert "no rung meets the budget" in p.stderr and "the closest is" in p.stderr and "nothing written" in p.stderr
    assert not out.exists()


def test_plan_picks_the_cheapest_good_enough_rung_and_ngi_lightmap_runs_it(tmp_path, dev):
    path = write_zoo(tmp_path, [DIRECT, sv_rung()])
    out = tmp_path / "plans" / "plan.json"
    device = os.environ.get("NGI_TEST_DEVICE", "cpu")
    common = ["--scene", "room:seed=3", "--zoo", path, "--frames", 2, "--validate", 1, "--spp", 16,
              "--feature-spp", 4, "--device", device, "--out", out]
    # Any quality: the direct-light rung costs nothing.
    p = run_plan(*common, "--min-ssim", "0")
    assert p.returncode == 0, p.stderr
    got = json.loads(out.read_text())
    assert got["rung"] == "direct_only" and got["model"] is None and got["validation"]["kept_quality_promise"]
    # Time only: the most accurate rung within it; the plan's model path is relative to the plan's folder.
    p = run_plan(*common, "--max-ms", "1e9")
    assert p.returncode == 0, p.stderr
    got = json.loads(out.read_text())
    cal = {r["name"]: r for r in got["calibration"]["rungs"]}
    best = max(cal, key=lambda k: cal[k]["ssim"])
    assert got["rung"] == best and got["device"]["zoo_key"] is None  # this device is not in the test zoo
    if got["model"]:
        assert (out.parent / got["model"]).resolve() == (path.parent / "sv.safetensors").resolve()
    if CLI:
        fr = tmp_path / "frame"
        ngi.write_frame(fr, ngi.Renderer(dev, ngi.Scene("room:seed=3")).render(n=64, spp=8, feature_spp=2, frame=9))
        r = subprocess.run([CLI, "lightmap", "--frame", fr, "--plan", out, "--out", tmp_path / "lm", "--device",
                            device], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert json.loads((tmp_path / "lm" / "metrics.json").read_text())["plan"]["rung"] == got["rung"]


def test_plan_needs_a_budget(tmp_path):
    p = run_plan("--scene", "room:seed=3", "--out", tmp_path / "p.json")
    assert p.returncode == 2 and "give a budget" in p.stderr

"""ngi_train.adapt (issue 46): bad input refused before any work, and one whole adaptation on a tiny budget --
frames on other camera paths than the dataset's, fine-tuning from the base, early stopping, an F16 model with its
"adapt" record and card that ngi runs, the budget honoured, a rerun resuming instead of redoing.

    PYTHONPATH=training:build/python NGI_BIN=build/ngi /usr/bin/python3 -m pytest -q training/tests/test_adapt.py

The end-to-end case shrinks the module's constants (frames of 16 spp, 20-step chunks, two validation views) so
that it takes about a minute; what it checks does not depend on them.
"""

import json

import numpy as np
import pytest

import ngi
import ngi.model_file as model_file

from ngi_train import adapt, ngi_paths

SCENE = "knot:seed=1"


def run(tmp_path, *extra, scene=SCENE, base=adapt.DEFAULT_BASE, budget="5"):
    return adapt.main(["--scene", scene, "--out", str(tmp_path / "m.safetensors"), "--base", base,
                       "--budget-minutes", budget, "--work", str(tmp_path / "work"), *extra])


def nothing_written(tmp_path):
    assert not (tmp_path / "m.safetensors").exists() and not (tmp_path / "m.md").exists()
    assert not (tmp_path / "work" / "data").exists()


def test_base_that_does_not_correct_ssgi_is_refused(tmp_path, capsys):
    assert run(tmp_path, base="ssgi_surround") == 2
    assert "output mode ssgi_residual" in capsys.readouterr().err
    nothing_written(tmp_path)


def test_unknown_base_and_scene_are_refused(tmp_path, capsys):
    assert run(tmp_path, base="no_such_model") == 2
    assert "--base no_such_model" in capsys.readouterr().err
    assert run(tmp_path, scene=str(tmp_path / "missing.vox")) == 2
    assert "cannot be loaded" in capsys.readouterr().err
    nothing_written(tmp_path)


def test_budget_too_small_is_refused_before_rendering(tmp_path, capsys, monkeypatch):
    # Too small for any frame: refused without rendering.
    assert run(tmp_path, budget="0.05") == 2
    err = capsys.readouterr().err
    assert "too small" in err and "s per frame" in err
    nothing_written(tmp_path)
    # 6 s with 1 s of training and 1 s to export: 0.48 s per frame, which no 64 x 64 frame at 512 spp (six faces of
    # direct light) takes here: the measuring render is stopped and removed.
    monkeypatch.setattr(adapt, "MIN_TRAIN_SECONDS", 1.0)
    monkeypatch.setattr(adapt, "EXPORT_RESERVE_S", 1.0)
    assert run(tmp_path, budget="0.1") == 2
    err = capsys.readouterr().err
    assert "too small" in err and ("took" in err), err
    nothing_written(tmp_path)
    # The same folder then takes another budget (nothing was recorded).
    assert not (tmp_path / "work" / "adapt.json").exists()


def test_default_work_folder_in_the_checkout_and_in_the_user_cache(tmp_path, monkeypatch):
    # A checkout: runs/adapt/<scene> (as before issue 46's installation); an installed package (no repository): the
    # user's cache, $XDG_CACHE_HOME/ngi/adapt/<scene> else ~/.cache/ngi/adapt/<scene>.
    assert adapt.default_work("scenes/level.vox") == ngi_paths.REPO / "runs" / "adapt" / "level"
    assert adapt.default_work("room:seed=3") == ngi_paths.REPO / "runs" / "adapt" / "room_seed3"
    monkeypatch.setattr(ngi_paths, "REPO", None)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert adapt.default_work("/a/level.vox") == tmp_path / "xdg" / "ngi" / "adapt" / "level"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert adapt.default_work("room:seed=3") == tmp_path / "home" / ".cache" / "ngi" / "adapt" / "room_seed3"


def test_bad_options(tmp_path):
    for extra in (["--lr", "0"], ["--lr", "nan"], ["--times", "9,9"], ["--times", "49"], ["--times", "noon"]):
        with pytest.raises(SystemExit) as e:
            run(tmp_path, *extra)
        assert e.value.code == 2
    assert adapt.main(["--scene", SCENE, "--out", str(tmp_path / "m.onnx"), "--work", str(tmp_path / "w")]) == 2


def test_adapt_end_to_end_and_resume(tmp_path, monkeypatch):
    monkeypatch.setattr(adapt, "FEATURE_SPP", 16)
    monkeypatch.setattr(adapt, "REFERENCE_SPP", 16)
    monkeypatch.setattr(adapt, "VAL_FRAMES", (12, 62))
    monkeypatch.setattr(adapt, "CHUNK_STEPS", 20)
    monkeypatch.setattr(adapt, "MIN_TRAIN_SECONDS", 5.0)
    monkeypatch.setattr(adapt, "EXPORT_RESERVE_S", 5.0)
    monkeypatch.setattr(adapt, "MAX_TRAIN_FRAMES", 4)
    budget_s = 60.0
    times = "9,15"  # the views take the times of day in turn (the sun-adaptation path; without --times: the scene's)
    assert run(tmp_path, "--times", times, budget=str(budget_s / 60.0)) == 0
    out = tmp_path / "m.safetensors"
    tensors, config = model_file.read_model(str(out))
    assert all(t.dtype == np.float16 for t in tensors.values())
    a = config["adapt"]
    assert a["scene"] == "knot:seed=1" and a["frames"]["val"] == 2 and 1 <= a["frames"]["train"] <= 4
    # The budget: render + train + export within it (the run stops training at budget - reserve; the export of a
    # small model takes a few seconds more than the reserve at most).
    assert sum(a["spent_s"].values()) <= budget_s + 15.0, a["spent_s"]
    assert a["steps"] >= 20 and a["validation"]["chosen"]["l1"] <= a["validation"]["base"]["l1"]
    assert (a["chosen_step"] is None) == (a["validation"]["chosen"] == a["validation"]["base"])
    card = (tmp_path / "m.md").read_text()
    assert "knot:seed=1" in card and "validation L1" in card and "9 h, 15 h" in card
    assert a["frames"]["times_h"] == [9.0, 15.0]
    # No adaptation view is on the dataset path the evaluation scores, and the validation path is not a training one.
    data = tmp_path / "work" / "data"
    recs = [json.loads((d / "render.json").read_text()) for d in sorted((data / "train").iterdir())]
    vals = [json.loads((d / "render.json").read_text()) for d in sorted((data / "val").iterdir())]
    assert all(r["path_seed"] is not None and r["path_seed"] != adapt.VAL_PATH_SEED for r in recs)
    assert all(r["path_seed"] == adapt.VAL_PATH_SEED for r in vals)
    assert [r["camera"]["time_h"] for r in vals] == [9.0, 15.0]
    assert {r["camera"]["time_h"] for r in recs} == {9.0, 15.0} or len(recs) == 1
    # ngi runs it (the residual output mode through the pipeline) on a frame it was not trained on.
    dev = ngi.Device()
    fr = ngi.read_frame(str(data / "val" / sorted(p.name for p in (data / "val").iterdir())[0]))
    lm = ngi.Pipeline(dev, 64).run(ngi.Model(dev, str(out)), fr, outputs=("lightmap",))["lightmap"]
    assert lm.shape == (3, 64, 64) and np.isfinite(lm).all() and lm.min() >= 0
    # Rerun: the frames are not rendered again (same files), the model is written again from the finished run.
    stamps = {p: p.stat().st_mtime_ns for p in data.rglob("reference.exr")}
    assert run(tmp_path, "--times", times, budget=str(budget_s / 60.0)) == 0
    assert {p: p.stat().st_mtime_ns for p in data.rglob("reference.exr")} == stamps
    # Another budget or other times of day are another adaptation: refused in the same folder.
    assert run(tmp_path, "--times", times, budget="2") == 2
    assert run(tmp_path, budget=str(budget_s / 60.0)) == 2


def test_views_without_times_take_the_scene_own_and_with_times_take_them_in_turn():
    views = adapt.train_views()
    assert all(next(views)[3] is None for _ in range(20))
    views = adapt.train_views([8.0, 12.0, 16.0])
    assert [next(views)[3] for _ in range(7)] == [8.0, 12.0, 16.0, 8.0, 12.0, 16.0, 8.0]
    assert [h for _, h, _ in adapt.val_views()] == [None] * len(adapt.VAL_FRAMES)
    names = [name for _, _, name in adapt.val_views([8.0, 12.0])]
    assert names[0].endswith("_t08.00") and names[1].endswith("_t12.00") and len(set(names)) == len(names)


def test_init_model_loads_the_base_and_refuses_another_architecture():
    import torch

    from ngi_train.generator import networks, train

    path = ngi.resolve_model(adapt.DEFAULT_BASE)
    tensors, config = model_file.read_model(path)
    cfg = dict(config["training"]["config"], init_model=path)
    G = networks.build_generator(13, 3, cfg["ngf"], cfg["num_downs"], use_dropout=True)
    train.init_generator(G, cfg)
    state = G.state_dict()
    for name, t in tensors.items():
        assert torch.equal(state[name], torch.from_numpy(t.astype(np.float32))), name
    small = networks.build_generator(13, 3, 8, cfg["num_downs"], use_dropout=True)
    with pytest.raises(SystemExit, match="is not this config's generator"):
        train.init_generator(small, dict(cfg, ngf=8))

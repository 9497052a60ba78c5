"""The per-frame honesty numbers of issue 45's evaluation (ngi_train.generator.engine_eval: margins, honesty,
summarize) on hand-made scores; pure Python, well under a second.

    PYTHONPATH=build/python:training /usr/bin/python3 -m pytest -q training/tests/test_engine_eval.py
"""

import math

import pytest

from ngi_train.generator import engine_eval as ee


def rows(psnrs, group="scans"):
    """Rows as engine_eval.rows_of makes them: frame 'file/KKKK' -> final PSNR (SSIM and lightmap made up)."""
    return [{"frame": f, "file": f.rsplit("/", 1)[0], "group": group,
             "final": {"psnr": p, "ssim": 0.5, "mse": 0.1}, "lightmap": {"psnr": p - 3, "ssim": 0.4, "mse": 1.0}}
            for f, p in psnrs.items()]


DIRECT = {"dragon/0010": 20.0, "dragon/0050": 25.0, "teapot/0010": 30.0, "teapot/0050": 22.0}


def test_engine_honesty_by_hand():
    rung = rows({"dragon/0010": 18.5, "dragon/0050": 24.4, "teapot/0010": 31.0, "teapot/0050": 21.0})
    ssgi = rows({"dragon/0010": 21.0, "dragon/0050": 25.0, "teapot/0010": 29.0, "teapot/0050": 22.5})
    h = ee.honesty(rung, rows(DIRECT), ssgi)
    assert h["frames"] == 4
    # margins vs direct: -1.5, -0.6, +1.0, -1.0 -> more than 1 dB below: one frame (-1.0 is not more than 1 dB)
    assert h["below_direct_share"] == pytest.approx(0.25)
    assert h["below_direct_half_db_frames"] == 3
    # margins vs ssgi: -2.5, -0.6, +2.0, -1.5 -> two frames
    assert h["below_ssgi_share"] == pytest.approx(0.5)
    assert h["worst_vs_direct"] == {"file": "dragon", "frame": 10, "db": pytest.approx(-1.5)}


def test_engine_honesty_without_ssgi_and_direct_against_itself():
    h = ee.honesty(rows(DIRECT), rows(DIRECT))
    assert h["below_ssgi_share"] is None
    assert h["below_direct_share"] == 0 and h["below_direct_half_db_frames"] == 0
    assert h["worst_vs_direct"]["db"] == 0


def test_engine_honesty_non_finite_margins_never_below():
    # identical to the reference on both sides: inf - inf is not a number, counted as not below, not the worst
    h = ee.honesty(rows({"a/0010": math.inf, "a/0050": 10.0}), rows({"a/0010": math.inf, "a/0050": 12.0}))
    assert h["below_direct_share"] == pytest.approx(0.5)
    assert h["worst_vs_direct"] == {"file": "a", "frame": 50, "db": pytest.approx(-2.0)}
    empty = ee.honesty([], [])
    assert empty["frames"] == 0 and empty["below_direct_share"] is None and empty["worst_vs_direct"] is None


def test_engine_honesty_refuses_unpaired_frames():
    with pytest.raises(ValueError):
        ee.honesty(rows({"a/0010": 1.0}), rows({"a/0050": 1.0}))


def test_engine_summarize_groups_and_files():
    by = {"direct_only": rows(DIRECT) + rows({"chr_cat/0050": 15.0}, "characters"),
          "ssgi_surround_n64": rows({k: v + 1 for k, v in DIRECT.items()}) + rows({"chr_cat/0050": 12.0},
                                                                                   "characters")}
    s = ee.summarize(by, "ssgi_surround_n64")
    ssgi = s["ssgi_surround_n64"]
    assert ssgi["groups"]["all"]["frames"] == 5 and ssgi["groups"]["scans"]["frames"] == 4
    assert ssgi["groups"]["scans"]["psnr"] == pytest.approx(25.25)
    assert ssgi["groups"]["scans"]["lightmap_psnr"] == pytest.approx(22.25)
    assert ssgi["files"]["teapot"]["psnr"] == pytest.approx(27.0)
    assert ssgi["honesty"]["all"]["below_direct_share"] == pytest.approx(0.2)
    assert ssgi["honesty"]["scans"]["below_direct_share"] == 0
    assert ssgi["honesty"]["characters"]["worst_vs_direct"] == {"file": "chr_cat", "frame": 50, "db": -3.0}
    assert s["direct_only"]["honesty"]["all"]["below_ssgi_share"] == 0  # exactly 1 dB below is not more than 1 dB


def test_ssgi_variants_write_loadable_rungs_named_by_their_settings(tmp_path):
    import ngi
    from ngi import model_file
    from ngi_train.generator import ssgi_variants as sv

    grid = sv.parse_grid(["bounces=1,2", "visibility_steps=4", "thickness=0.25"])
    assert grid == {"bounces": [1, 2], "visibility_steps": [4], "thickness": [0.25]}
    sv.main(["--out", str(tmp_path), "--grid", "bounces=1,2", "visibility_steps=4", "thickness=0.25"])
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["b1_v4_t0.25.safetensors", "b2_v4_t0.25.safetensors"]
    cfg = model_file.read_config(str(tmp_path / "b2_v4_t0.25.safetensors"))
    assert (cfg["family"], cfg["bounces"], cfg["visibility_steps"], cfg["thickness"]) == ("ssgi", 2, 4, 0.25)
    ngi.Model(ngi.Device(), str(tmp_path / "b2_v4_t0.25.safetensors"))  # the C++ loader accepts the settings
    assert sv.name_of({"view": "front", "cluster_level": 2}) == "f_L2"
    for bad in (["bounces"], ["wings=2"], ["bounces=two"], ["visibility_steps=1.5"]):
        with pytest.raises(SystemExit):
            sv.parse_grid(bad)

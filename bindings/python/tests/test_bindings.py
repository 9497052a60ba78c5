"""The Python bindings (ngi._ngi) against the library's other faces: the CLI, frame folders, pyopencl.

Run by ctest as `python_bindings` (PYTHONPATH=<build>/python, NGI_CLI=<build>/ngi, NGI_TEST_DEVICE as the suite).
The shipped models are the fixtures: their parity with PyTorch is the C++ suite's job; here the question is whether
Python gets the same numbers as the C++ paths, and whether bad input becomes an exception instead of a crash.
"""

import ast
import gc
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import ngi

REPO = Path(__file__).resolve().parents[3]
MODELS = REPO / "models"
CLI = os.environ.get("NGI_CLI")


@pytest.fixture(scope="module")
def dev():
    return ngi.Device(os.environ.get("NGI_TEST_DEVICE", "cpu"))


@pytest.fixture(scope="module")
def surround(dev):
    return ngi.Model(dev, MODELS / "surround.safetensors")


@pytest.fixture(scope="module")
def frame(dev):
    # N = 64: the shipped generators have 7 levels, so the global view must be a multiple of 128 wide and high.
    return ngi.Renderer(dev, ngi.Scene("room:seed=3")).render(n=64, spp=8, feature_spp=2, frame=5)


@pytest.fixture(scope="module")
def frame_dir(tmp_path_factory, frame):
    d = tmp_path_factory.mktemp("frame") / "f"
    ngi.write_frame(d, frame)
    return d


def run_cli(*args):
    assert CLI, "NGI_CLI is not set (ctest sets it to the built ngi binary)"
    proc = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_version_and_devices():
    assert ngi.__version__.count(".") == 2
    devices = ngi.devices()
    assert devices and all({"index", "platform", "name", "type"} <= set(d) for d in devices)


def test_model_run_equals_cli_generate(dev, surround, tmp_path):
    x = np.random.default_rng(1).uniform(-1, 1, (1, 12, 128, 256)).astype(np.float32)
    np.save(tmp_path / "x.npy", x)
    run_cli("generate", "--model", MODELS / "surround.safetensors", "--input", tmp_path / "x.npy",
            "--output", tmp_path / "y.npy", "--device", os.environ.get("NGI_TEST_DEVICE", "cpu"))
    y = surround.run(x)
    assert y.shape == (1, 3, 128, 256) and y.dtype == np.float32
    np.testing.assert_array_equal(y, np.load(tmp_path / "y.npy"))  # same kernels, same order: same bits


def test_models_by_name(dev, surround, monkeypatch, tmp_path):
    # A shipped model's name loads the same file as its path (from the source tree here, or an installed copy of it).
    monkeypatch.delenv("NGI_MODEL_PATH", raising=False)
    by_name = ngi.Model(dev, "surround")
    assert Path(by_name.path).name == "surround.safetensors"
    assert Path(by_name.path).parent in map(Path, ngi.model_search_path())
    x = np.random.default_rng(4).uniform(-1, 1, (1, 12, 128, 128)).astype(np.float32)
    np.testing.assert_array_equal(by_name.run(x), surround.run(x))
    names = ngi.model_names()
    assert {"surround", "single_view", "voxel_sh_set", "ao_sculpture_16x8", "neural_gi_room",
            "surround_n64_ngf8"} <= set(names)
    assert ngi.AoNetwork(dev, "ao_sculpture_16x8").normals in ("smooth", "face")
    assert ngi.resolve_model(MODELS / "surround.safetensors") == str(MODELS / "surround.safetensors")
    # The override comes first; an unknown name lists the known ones.
    (tmp_path / "mine.safetensors").write_bytes((MODELS / "ao_sculpture_16x8.safetensors").read_bytes())
    monkeypatch.setenv("NGI_MODEL_PATH", str(tmp_path))
    assert ngi.model_search_path()[0] == str(tmp_path.resolve())
    assert ngi.Model(dev, "mine").path == str(tmp_path.resolve() / "mine.safetensors")
    with pytest.raises(ngi.InputError,
                       match=r"model 'surroundd': not a file and not a known model name .*known names: .*mine.*surround"):
        ngi.Model(dev, "surroundd")


def test_warm_up_fills_the_program_cache(dev, monkeypatch, tmp_path):
    # A new cache folder: programs this process has not built yet are built and written there; the call again finds
    # everything in memory (no build, no load); another family and a cache folder it cannot write are refused.
    monkeypatch.setenv("NGI_CACHE_DIR", str(tmp_path / "cache"))
    assert ngi.program_cache_dir() == str(tmp_path / "cache")
    rung = ngi.Model(dev, "ssgi_surround")
    first = ngi.warm_up(rung, n=8, display=12)
    assert first["cache_dir"] == str(tmp_path / "cache") and first["first_frame_ms"] > 0
    assert set(first) == {"cache_dir", "programs_built", "programs_from_cache", "first_frame_ms", "second_frame_ms"}
    again = ngi.warm_up(rung, n=8, display=12)
    assert again["programs_built"] == 0 and again["programs_from_cache"] == 0
    with pytest.raises(ngi.InputError, match="not a frame rung"):
        ngi.warm_up(ngi.Model(dev, "ao_sculpture_16x8"), n=8)
    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("NGI_CACHE_DIR", str(tmp_path / "file" / "cache"))
    with pytest.raises(ngi.InputError, match="program cache folder"):
        ngi.warm_up(rung, n=8)


def test_model_run_converts_other_layouts(surround):
    x = np.random.default_rng(2).uniform(-1, 1, (1, 12, 128, 256)).astype(np.float32)
    y = surround.run(x)
    np.testing.assert_array_equal(surround.run(x.astype(np.float64)), y)       # float64: converted
    fortran = np.asfortranarray(x)
    np.testing.assert_array_equal(surround.run(fortran), y)                   # not C-contiguous: copied
    sliced = np.concatenate([x, x], axis=3)[..., ::2]                          # strided view
    np.testing.assert_array_equal(surround.run(sliced), surround.run(np.ascontiguousarray(sliced)))


def test_mlp_points_and_pixels(dev):
    m = ngi.Model(dev, MODELS / "ao_sculpture_16x8.safetensors")
    x = np.random.default_rng(3).uniform(-1, 1, (1, 48, 5, 7)).astype(np.float32)
    per_pixel = m.run(x)
    points = m.run(np.ascontiguousarray(x[0].reshape(48, -1).T))              # [35, 48]
    assert per_pixel.shape == (1, 1, 5, 7) and points.shape == (35, 1)
    np.testing.assert_allclose(points[:, 0], per_pixel.reshape(-1), rtol=0, atol=1e-6)


def test_model_config_traits_and_sections(dev, surround):
    # The family's traits (what to choose by instead of the family's name) and only the sections a model has.
    c = surround.config
    assert (c["input"], c["has_network"], c["output_keeps_size"]) == ("image", True, True) and c["ngf"] > 0
    mlp = ngi.Model(dev, MODELS / "ao_sculpture_16x8.safetensors").config
    assert (mlp["input"], mlp["has_network"], mlp["output_keeps_size"]) == ("items", True, True)
    assert "ngf" not in mlp and "architecture" not in mlp
    voxel = ngi.Model(dev, "voxel_sh_set").config
    assert voxel["input"] == "items" and voxel["architecture"] == "set" and "ngf" not in voxel
    rung = ngi.Model(dev, "ssgi_surround").config
    assert (rung["input"], rung["has_network"]) == ("image", False) and "ngf" not in rung and "bn_mode" not in rung


def test_pipeline_numpy_dict_equals_frame_folder_and_cli(dev, surround, frame, frame_dir, tmp_path):
    pipe = ngi.Pipeline(dev, 64)
    # The folder stores colours as half floats, so the dict is made from the frame as read back.
    from_dict = pipe.run(surround, ngi.read_frame(frame_dir).to_dict(), outputs=["lightmap", "final", "display"])
    from_folder = pipe.run(surround, frame_dir, outputs=["lightmap", "final", "display"])
    from_frame = pipe.run(surround, ngi.read_frame(frame_dir), outputs=["lightmap", "final", "display"])
    for k in ("lightmap", "final", "display"):
        assert from_dict[k].shape == (3, 64, 64)
        np.testing.assert_array_equal(from_dict[k], from_folder[k])
        np.testing.assert_array_equal(from_dict[k], from_frame[k])
    # The CLI writes the lightmap as float EXR: the same numbers.
    run_cli("lightmap", "--frame", frame_dir, "--model", MODELS / "surround.safetensors", "--out", tmp_path / "lm",
            "--device", os.environ.get("NGI_TEST_DEVICE", "cpu"))
    cli_lightmap, names = ngi.read_exr(tmp_path / "lm" / "lightmap.exr")
    assert names == ["R", "G", "B"]
    np.testing.assert_allclose(cli_lightmap, from_dict["lightmap"], rtol=1e-3, atol=1e-6)  # EXR may store half


def test_pipeline_single_view_from_front_face_only(dev, frame):
    model = ngi.Model(dev, MODELS / "single_view.safetensors")
    pipe = ngi.Pipeline(dev, 64)
    full = pipe.run(model, frame.to_dict())["lightmap"]
    front = {k: (v[:1] if isinstance(v, np.ndarray) and v.ndim >= 3 and v.shape[0] == 6 else v)
             for k, v in frame.to_dict().items()}
    np.testing.assert_array_equal(pipe.run(model, front)["lightmap"], full)


def test_pipeline_run_images_engine_layouts(dev, frame):
    """Render targets as an engine holds them (interleaved RGBA half with bottom-up rows, a padded R32F depth, unorm8
    normals) give what the same values give as a frame dict; bad descriptors name the face and feature."""
    model = ngi.Model(dev, MODELS / "ladder" / "gi_single_view_n64_ngf16.safetensors")
    pipe = ngi.Pipeline(dev, 64)
    d = frame.to_dict()
    images, as_dict = {}, {"look": d["look"], "up": d["up"]}
    for feature in ("albedo", "normal", "depth", "direct", "emission", "env"):
        planes = d[feature][:1]                                   # [1, C, N, N]: the front face
        hwc = np.moveaxis(planes[0], 0, -1)                       # [N, N, C]
        if feature == "normal":                                   # RGBA8, n / 2 + 1/2
            stored = np.zeros((64, 64, 4), np.uint8)
            stored[..., :3] = np.round(np.clip(hwc * 0.5 + 0.5, 0, 1) * 255)
            images[("front", feature)] = {"array": stored, "scale": 2.0, "bias": -1.0}
            decoded = stored[..., :3].astype(np.float32) * np.float32(1 / 255) * 2 - 1
        elif feature == "depth":                                  # R32F in a padded pitch: a view of a wider array
            wide = np.zeros((64, 80), np.float32)
            wide[:, :64] = hwc[..., 0]
            images[("front", feature)] = wide[:, :64]
            decoded = hwc
        else:                                                     # RGBA16F, bottom-up rows
            stored = np.zeros((64, 64, 4), np.float16)
            stored[..., :3] = hwc[::-1]
            images[("front", feature)] = {"array": stored, "bottom_up": True}
            decoded = stored[::-1, :, :3].astype(np.float32)
        as_dict[feature] = np.ascontiguousarray(np.moveaxis(decoded, -1, 0)[None])
    want = pipe.run(model, as_dict, outputs=["lightmap", "final"])
    got = pipe.run_images(model, images, look=d["look"], up=d["up"], outputs=["lightmap", "final"], timings=True)
    # unorm normals: the device's x * scale + bias may be fused (one rounding), NumPy's is not
    np.testing.assert_allclose(got["lightmap"], want["lightmap"], rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(got["final"], want["final"], rtol=1e-4, atol=1e-5)
    assert got["timings"]["network_ms"] > 0
    bad = dict(images)
    bad[("front", "direct")] = np.zeros((64, 64, 2), np.float32)
    with pytest.raises(ngi.InputError, match="image 'direct' of face 'front' has 2 channels"):
        pipe.run_images(model, bad)
    bad[("front", "direct")] = np.zeros((64, 64, 3), np.float32)[::-1]
    with pytest.raises(ValueError, match="bottom_up"):
        pipe.run_images(model, bad)
    with pytest.raises(TypeError, match="float64"):
        pipe.run_images(model, {("front", "albedo"): np.zeros((64, 64, 3))})
    # A descriptor field of the wrong type names the image, the key and both types (issue 51: pybind11's
    # "Unable to cast Python instance to C++ type" named none of them).
    for key, value, wanted in (("scale", "2", "a number, got str"), ("bottom_up", 1, "True or False, got int"),
                               ("srgb", None, "True or False, got NoneType")):
        bad = dict(images)
        bad[("front", "env")] = dict(images[("front", "env")], **{key: value})
        with pytest.raises(TypeError, match=rf"images\[\('front', 'env'\)\]: '{key}' must be {wanted}"):
            pipe.run_images(model, bad)


def octahedral(n):
    """Unit vectors [..., 3] -> their octahedral map [..., 2] (Cigolle et al. 2014)."""
    p = n[..., :2] / np.abs(n).sum(-1, keepdims=True)
    fold = (1 - np.abs(p[..., ::-1])) * np.where(p >= 0, 1.0, -1.0)
    return np.where(n[..., 2:3] >= 0, p, fold)


def from_octahedral(e):
    v = np.concatenate([e, 1 - np.abs(e).sum(-1, keepdims=True)], -1)
    fold = (1 - np.abs(e[..., ::-1])) * np.where(e >= 0, 1.0, -1.0)
    v[..., :2] = np.where(v[..., 2:3] < 0, fold, v[..., :2])
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_pipeline_run_images_gl_attachments(dev, frame):
    """Issue 48: what a GL engine renders, handed over as it is -- a reversed-Z depth attachment with an infinite far
    plane, octahedral view-space normals in RG16_SNORM, RGB10A2 albedo, R11G11B10F direct light, RGBA16 unorm
    emission -- gives what its decoded values give as a frame dict."""
    model = ngi.Model(dev, MODELS / "ladder" / "gi_single_view_n64_ngf16.safetensors")
    pipe = ngi.Pipeline(dev, 64)
    d = frame.to_dict()
    hwc = {f: np.moveaxis(d[f][0], 0, -1).astype(np.float64) for f in ("albedo", "normal", "depth", "direct",
                                                                       "emission", "env")}
    near = 0.05
    view_to_world = np.array([[0.6, 0, 0.8], [0, 1, 0], [-0.8, 0, 0.6]])      # row-major: world = R v
    n = hwc["normal"] / np.maximum(np.linalg.norm(hwc["normal"], axis=-1, keepdims=True), 1e-6)
    n[np.linalg.norm(hwc["normal"], axis=-1) < 0.5] = [0, 0, 1]               # the tracer's sky: any unit vector
    oct16 = np.round(np.clip(octahedral(n @ view_to_world), -1, 1) * 32767).astype(np.int16)   # (R^T n) in rows
    window = near / hwc["depth"][..., 0]                                       # reversed Z, infinite far: d = near / z
    window[hwc["depth"][..., 0] >= 1000] = 0.0                                 # sky: the cleared value
    albedo10 = np.round(np.clip(hwc["albedo"], 0, 1) * 1023).astype(np.uint32)
    rgb10a2 = albedo10[..., 0] | albedo10[..., 1] << 10 | albedo10[..., 2] << 20 | np.uint32(3) << 30
    halves = np.clip(hwc["direct"], 0, 60000).astype(np.float16).view(np.uint16).astype(np.uint32)
    r11 = (halves[..., 0] >> 4) | (halves[..., 1] >> 4) << 11 | (halves[..., 2] >> 5) << 22  # truncated halves
    emission16 = np.round(np.clip(hwc["emission"], 0, 1) * 65535).astype(np.uint16)
    images = {
        ("front", "normal"): {"array": oct16, "normal": "octahedral", "normal_to_world": view_to_world},
        ("front", "depth"): {"array": window.astype(np.float32), "depth": "perspective", "near": near,
                             "far": float("inf"), "reversed_z": True},
        ("front", "albedo"): {"array": rgb10a2, "format": "rgb10a2"},
        ("front", "direct"): {"array": r11, "format": "r11g11b10f"},
        ("front", "emission"): emission16,
        ("front", "env"): hwc["env"].astype(np.float32),
    }
    # What those bytes hold, decoded by NumPy in float64.
    normal = from_octahedral(np.maximum(oct16 / 32767.0, -1)) @ view_to_world.T
    w32 = window.astype(np.float32).astype(np.float64)
    depth = np.where(w32 <= 0, 1e4, near / np.where(w32 > 0, w32, 1))
    albedo = np.stack([(rgb10a2 >> (10 * c)) & 1023 for c in range(3)], -1) / 1023.0
    direct = np.stack([((r11 & 2047) << 4).astype(np.uint16), (((r11 >> 11) & 2047) << 4).astype(np.uint16),
                       ((r11 >> 22) << 5).astype(np.uint16)], -1).view(np.float16).astype(np.float64)
    normal[depth >= 1e4] = 0                  # an octahedral normal where the depth says "no surface": none
    decoded = {"albedo": albedo, "normal": normal, "depth": depth[..., None], "direct": direct,
               "emission": emission16 / 65535.0, "env": hwc["env"]}
    as_dict = {"look": d["look"], "up": d["up"]}
    for f, v in decoded.items():
        as_dict[f] = np.ascontiguousarray(np.moveaxis(v.astype(np.float32), -1, 0)[None])
    want = pipe.run(model, as_dict, outputs=["lightmap"])
    got = pipe.run_images(model, images, look=d["look"], up=d["up"], outputs=["lightmap"])
    np.testing.assert_allclose(got["lightmap"], want["lightmap"], rtol=1e-4, atol=1e-5)
    with pytest.raises(ValueError, match="'normal' must be 'xyz' or 'octahedral'"):
        pipe.run_images(model, {**images, ("front", "normal"): dict(images[("front", "normal")], normal="oct")})
    with pytest.raises(ngi.InputError, match="the perspective depth encoding needs 0 < near_m < far_m"):
        pipe.run_images(model, {**images, ("front", "depth"): dict(images[("front", "depth")], near=0.0)})
    with pytest.raises(TypeError, match="format r11g11b10f stores 4-byte values"):
        pipe.run_images(model, {**images, ("front", "direct"): {"array": oct16, "format": "r11g11b10f"}})


def test_negative_depth_is_refused_from_host_memory(dev, frame):
    # Issue 51: a frame folder refuses a negative depth (a distance); the in-memory paths took it and clamped it to
    # 0. Now Pipeline.run(dict) (host planes) and run_images (host descriptors: F32, F16, unorm8 with a bias) refuse
    # it too, naming the face; -Inf is negative, NaN is not (it is sanitized and counted, as in a frame folder).
    model = ngi.Model(dev, MODELS / "ladder" / "gi_single_view_n64_ngf16.safetensors")
    pipe = ngi.Pipeline(dev, 64)
    d = {k: v[:1] if isinstance(v, np.ndarray) else v for k, v in frame.to_dict().items()}
    for bad_value in (-0.5, -np.inf):
        bad = dict(d, depth=d["depth"].copy())
        bad["depth"][0, 0, 3, 5] = bad_value
        with pytest.raises(ngi.InputError, match="1 of 4096 depth values of face 'front' are negative"):
            pipe.run(model, bad)
    nan = dict(d, depth=d["depth"].copy())
    nan["depth"][0, 0, 3, 5] = np.nan
    assert np.isfinite(pipe.run(model, nan, outputs=["lightmap"])["lightmap"]).all()
    images = {("front", f): np.ascontiguousarray(np.moveaxis(d[f][0], 0, -1)) for f in ("albedo", "normal", "direct")}
    for depth in (np.full((64, 64), -1.0, np.float32), np.full((64, 64), -1.0, np.float16),
                  {"array": np.zeros((64, 64), np.float32), "bias": -0.25}):
        with pytest.raises(ngi.InputError, match="image 'depth' of face 'front': 4096 of 4096 pixels have a negative"):
            pipe.run_images(model, {**images, ("front", "depth"): depth}, look=d["look"], up=d["up"])
    # unorm depth is a depth attachment: without the perspective encoding's planes it cannot hold metres (issue 48)
    with pytest.raises(ngi.InputError, match="format u8 cannot hold linear depth in metres"):
        pipe.run_images(model, {**images, ("front", "depth"): np.zeros((64, 64), np.uint8)}, look=d["look"], up=d["up"])
    ok = pipe.run_images(model, {**images, ("front", "depth"): np.ascontiguousarray(d["depth"][0, 0])},
                         look=d["look"], up=d["up"])
    assert np.isfinite(ok["lightmap"]).all()


def test_frame_round_trip(frame, frame_dir):
    back = ngi.read_frame(frame_dir)
    assert back.n == frame.n and back.look == pytest.approx(frame.look)
    np.testing.assert_array_equal(back.feature("normal"), frame.feature("normal"))  # normals are stored as float
    np.testing.assert_array_equal(back.reference, frame.reference)
    again = ngi.Frame.from_dict(frame.to_dict())
    np.testing.assert_array_equal(again.feature("depth"), frame.feature("depth"))


def test_renderer_is_deterministic(dev):
    r = ngi.Renderer(dev, ngi.Scene("sculpture:seed=1"))
    a = r.render_ao(n=24, rays=16, frame=3)
    np.testing.assert_array_equal(a, r.render_ao(n=24, rays=16, frame=3))
    assert a.shape == (1, 24, 24) and 0 <= a.min() and a.max() <= 1
    assert r.render_geometry(n=24, frame=3).shape == (7, 24, 24)


def test_voxel_probes_bake_and_shade(dev):
    # A lighting bake at the surface voxels (ngi_train.adapt_eval's probe competitor): the full lighting holds the
    # direct light plus bounces, the bake is deterministic in its seed, and shading a field lights every surface
    # pixel with the value of the voxel behind it (a constant field: that constant; sky pixels: 0).
    r = ngi.Renderer(dev, ngi.Scene("cornell:seed=1"))
    probes = ngi.VoxelProbes(r)
    v = probes.count
    b = probes.bake(samples=8, seed=3)
    assert b["direct"].shape == (v, 3) and b["lighting"].shape == (v, 3) and b["rays"] > 0 and b["seconds"] >= 0
    assert np.isfinite(b["lighting"]).all() and b["lighting"].sum() > b["direct"].sum() > 0
    np.testing.assert_array_equal(b["lighting"], probes.bake(samples=8, seed=3)["lighting"])
    # Per exposed face (+x -x +y -y +z -z): hidden faces are 0, every voxel has a lit or at least exposed face.
    faces = b["face_lighting"]
    assert faces.shape == (v, 6, 3) and np.isfinite(faces).all() and faces.min() >= 0
    assert (faces.sum(axis=2) == 0).any() and (faces.sum(axis=2) > 0).any()
    size = ngi.Scene("cornell:seed=1").size
    at = (size[0] / 2, size[1] / 2, size[2] / 2)  # inside the box, looking down -z at its back wall
    fr = r.render(n=24, spp=1, feature_spp=1, position=at, reference=False)
    depth = fr.feature("depth")[0][0]
    surface = depth < 5.0e3
    assert surface.any()
    for c in (0.25, 2.0):
        lit, misses = probes.shade(fr, at, np.full((v, 3), c, np.float32))
        assert lit.shape == (3, 24, 24)
        hit = surface & (lit[0] > 0)
        assert hit.sum() + misses == surface.sum()
        np.testing.assert_allclose(lit[:, hit], c)
        assert (lit[:, ~surface] == 0).all()
    with pytest.raises(ValueError, match="field must be"):
        probes.shade(fr, at, np.zeros((v + 1, 3), np.float32))
    with pytest.raises(ValueError, match="samples"):
        probes.bake(samples=0)


def test_network_input_and_channels(dev, surround, frame):
    pipe = ngi.Pipeline(dev, 64)
    x = pipe.network_input(frame, surround)
    assert x.shape == (1, 12, 128, 256)
    assert list(ngi.surround_input_channels()) == surround.config["input_layout"]
    lo, hi = surround.config["input_range"]
    assert lo <= x.min() and x.max() <= hi
    # The generator on that input, decoded, is exactly the one-call pipeline's lightmap.
    lm = pipe.front_lightmap(surround.run(x), surround)
    np.testing.assert_array_equal(lm, pipe.run(surround, frame)["lightmap"])
    target = pipe.encode_lightmap(frame.reference, surround)
    assert target.shape == (1, 3, 64, 64)


def test_output_mode_indirect_adds_the_front_direct_light(dev, surround, frame, frame_dir, tmp_path):
    # The shipped weights rewritten as an output_mode "indirect" model (ngi.model_file: what ngi.convert
    # --output-mode indirect writes): the same network output, decoded as indirect light and added to the frame's
    # front direct light.
    from ngi import model_file
    tensors, config = model_file.read_model(MODELS / "surround.safetensors")
    config = dict(config, output_mode="indirect", required=["output_mode"])
    path = tmp_path / "indirect.safetensors"
    model_file.write_model(path, tensors, config)
    model = ngi.Model(dev, path)
    assert surround.output_mode == "lightmap" and surround.config["output_mode"] == "lightmap"
    assert model.output_mode == "indirect" and model.config["output_mode"] == "indirect"

    pipe = ngi.Pipeline(dev, 64)
    y = model.run(pipe.network_input(frame, model))
    direct = frame.feature("direct")[0]  # the front face, [3, N, N]
    want = pipe.front_lightmap(y, surround) + np.clip(np.nan_to_num(direct, nan=0.0), 0.0, None)
    got = pipe.front_lightmap(y, model, frame)
    np.testing.assert_array_equal(got, want)
    # A frame folder works too (its EXRs may round the light to half, so against the folder read back).
    np.testing.assert_array_equal(pipe.front_lightmap(y, model, frame_dir),
                                  pipe.front_lightmap(y, model, ngi.read_frame(frame_dir)))
    np.testing.assert_array_equal(pipe.front_lightmap(y, surround, frame), pipe.front_lightmap(y, surround))
    np.testing.assert_array_equal(pipe.run(model, frame)["lightmap"], got)
    with pytest.raises(ngi.InputError, match="needs the frame's front direct light"):
        pipe.front_lightmap(y, model)

    config["output_mode"] = "residual"
    model_file.write_model(tmp_path / "bad.safetensors", tensors, config)
    with pytest.raises(ngi.InputError, match="residual"):
        ngi.Model(dev, tmp_path / "bad.safetensors")


def test_indirect_share_equals_the_numpy_formula(dev, surround, frame):
    # The guard's signal (docs/CONVENTIONS.md section 17) on the network's lightmap of a rendered frame, and on a
    # hostile one, against the formula in NumPy (float64 sums).
    pipe = ngi.Pipeline(dev, 64)
    lightmap = pipe.run(surround, frame)["lightmap"]
    f32max = float(np.finfo(np.float32).max)

    def clean(v):
        return np.clip(np.nan_to_num(np.asarray(v, np.float64), nan=0.0, posinf=f32max, neginf=0.0), 0.0, f32max)

    def front(name):
        v = frame.feature(name)
        return 0.0 if v is None else clean(v[0])

    def share(lm):
        albedo = np.clip(np.nan_to_num(frame.feature("albedo")[0].astype(np.float64), nan=0.0), 0.0, 1.0)
        luma = np.array([0.2126, 0.7152, 0.0722])[:, None, None]
        added = np.sum(luma * albedo * np.maximum(clean(lm) - front("direct"), 0.0))
        total = np.sum(luma * np.minimum(clean(lm) * albedo + front("emission") + front("env"), f32max))
        return float(np.clip(added / total, 0.0, 1.0)) if total > 0 else 0.0

    s = ngi.indirect_share(frame, lightmap)
    assert 0.0 < s < 1.0
    assert s == pytest.approx(share(lightmap), rel=1e-6)
    hostile = lightmap.copy()
    hostile[0, 0, :3] = [np.nan, -np.inf, -5.0]
    hostile[1, 2, 2] = np.inf
    assert ngi.indirect_share(frame, hostile) == pytest.approx(share(hostile), rel=1e-6)
    assert ngi.indirect_share(frame, frame.feature("direct")[0]) == 0.0  # direct light adds nothing
    with pytest.raises(ngi.InputError, match="indirect_share: the lightmap is 64x32x3, expected 64x64x3"):
        ngi.indirect_share(frame, lightmap[:, :32])


def test_make_config_output_mode():
    from ngi import model_file
    assert model_file.make_config("pix2pix_unet", bn_mode="running")["output_mode"] == "lightmap"
    config = model_file.make_config("pix2pix_unet", bn_mode="running", output_mode="indirect")
    assert config["output_mode"] == "indirect" and config["required"] == ["output_mode"]
    with pytest.raises(model_file.ConversionError, match="output_mode"):
        model_file.make_config("pix2pix_unet", bn_mode="running", output_mode="residual")
    with pytest.raises(model_file.ConversionError, match="pix2pix_unet only"):
        model_file.make_config("deepillumination", bn_mode="running", output_mode="indirect")


def test_network_input_equals_ngi_merge(dev, frame, frame_dir, tmp_path):
    pipe = ngi.Pipeline(dev, 64)
    back = ngi.read_frame(frame_dir)
    for single_view in (False, True):
        out = tmp_path / f"merged{int(single_view)}"
        run_cli("merge", "--frame", frame_dir, "--out", out, "--npy-only", *(["--single-view"] if single_view else []),
                "--device", os.environ.get("NGI_TEST_DEVICE", "cpu"))
        np.testing.assert_array_equal(pipe.network_input(back, single_view=single_view), np.load(out / "input.npy"))
        np.testing.assert_array_equal(pipe.encode_lightmap(back.reference), np.load(out / "target.npy"))
    with pytest.raises(ValueError, match="exclude"):
        pipe.network_input(back, ngi.Model(dev, MODELS / "surround.safetensors"), single_view=True)


def test_metrics_match_skimage(dev):
    skm = pytest.importorskip("skimage.metrics")
    rng = np.random.default_rng(4)
    a = rng.uniform(0, 1, (3, 40, 37)).astype(np.float32)
    b = np.clip(a + rng.normal(0, 0.1, a.shape), 0, 1).astype(np.float32)
    m = ngi.compare_images(dev, a, b)
    ref = skm.structural_similarity(a.astype(np.float64), b.astype(np.float64), gaussian_weights=True, sigma=1.5,
                                    use_sample_covariance=False, data_range=1.0, channel_axis=0)
    assert m["ssim"] == pytest.approx(ref, abs=1e-5)
    assert m["mse"] == pytest.approx(skm.mean_squared_error(a.astype(np.float64), b.astype(np.float64)), rel=1e-5)
    small = ngi.compare_images(dev, a[:, :8, :8], b[:, :8, :8])
    assert small["ssim"] is None and "ssim_note" in small


@pytest.mark.parametrize("ext", ["exr", "png", "npy"])
def test_image_round_trip(tmp_path, ext):
    img = np.random.default_rng(5).uniform(0, 1, (3, 9, 11)).astype(np.float32)
    ngi.write_image(tmp_path / f"a.{ext}", img)
    back = ngi.read_image(tmp_path / f"a.{ext}")
    np.testing.assert_allclose(back, img, atol=0.5 / 255 + 1e-6 if ext == "png" else 0)


# ---- bad input: exceptions with clear messages, never a crash -------------------------------------------------

def test_bad_arrays(surround):
    with pytest.raises(TypeError, match="floating-point"):
        surround.run(np.zeros((1, 12, 128, 256), np.int32))
    with pytest.raises(ValueError, match=r"\[1, 12, H, W\]"):
        surround.run(np.zeros((1, 5, 128, 256), np.float32))
    with pytest.raises(ValueError, match="expected shape"):
        surround.run(np.zeros((12, 128, 256), np.float32))
    with pytest.raises(ngi.InputError, match="2\\^num_downs"):
        surround.run(np.zeros((1, 12, 100, 256), np.float32))
    with pytest.raises(TypeError):
        surround.run("not an array")


def test_non_finite_inputs_are_sanitized_and_counted(surround):
    x = np.random.default_rng(6).uniform(-1, 1, (1, 12, 128, 256)).astype(np.float32)
    x[0, 0, 0, :3] = [np.nan, np.inf, -np.inf]
    x[0, 1, 5, 5] = 3.4e38
    y = surround.run(x)
    assert surround.sanitized_inputs == 4 and np.isfinite(y).all()


def test_bad_files_and_frames(dev, tmp_path):
    with pytest.raises(ngi.InputError, match="nonexistent"):
        ngi.Model(dev, tmp_path / "nonexistent.safetensors")
    (tmp_path / "junk.safetensors").write_bytes(b"\x10\x00\x00\x00\x00\x00\x00\x00{not json}")
    with pytest.raises(ngi.InputError, match="junk.safetensors"):
        ngi.Model(dev, tmp_path / "junk.safetensors")
    with pytest.raises(ngi.InputError):
        ngi.read_frame(tmp_path)
    with pytest.raises(ValueError, match="'normal'"):
        ngi.Frame.from_dict({"albedo": np.zeros((6, 3, 8, 8), np.float32)})
    with pytest.raises(ValueError, match="albedo"):
        ngi.Frame.from_dict({"albedo": np.zeros((6, 2, 8, 8), np.float32)})
    with pytest.raises(ngi.InputError, match="unknown"):
        ngi.Scene("no_such_family")
    with pytest.raises(ngi.InputError):
        ngi.compare_images(dev, np.full((1, 16, 16), np.nan, np.float32), np.zeros((1, 16, 16), np.float32))


def test_closed_device_refuses_every_object():
    d = ngi.Device(os.environ.get("NGI_TEST_DEVICE", "cpu"))
    m = ngi.Model(d, MODELS / "ao_sculpture_16x8.safetensors")
    ao = ngi.AoNetwork(d, MODELS / "ao_sculpture_16x8.safetensors")
    p = ngi.Pipeline(d, 8)
    b = ngi.DeviceBuffer(d, 64)
    with d:
        pass  # leaving the block closes it
    assert d.closed
    for call in (lambda: m.run(np.zeros((3, 48), np.float32)), lambda: p.tonemap(np.zeros((3, 4, 4), np.float32)),
                 lambda: ao.run(np.zeros((3, 4, 4), np.float32)),
                 lambda: b.download([4]), lambda: ngi.Model(d, MODELS / "ao_sculpture_16x8.safetensors"),
                 lambda: d.finish()):
        with pytest.raises(ngi.Error, match="was closed"):
            call()


# ---- pyopencl interop: the same context, no host copy ------------------------------------------------------

@pytest.fixture(scope="module")
def cl_queue(dev):
    cl = pytest.importorskip("pyopencl")
    name, platform = dev.info["name"], dev.info["platform"]
    for p in cl.get_platforms():
        for d in p.get_devices():
            if d.name == name and p.name == platform:
                ctx = cl.Context([d])
                return cl, ctx, cl.CommandQueue(ctx)
    pytest.fail(f"pyopencl does not see the test device {name} ({platform})")


def test_pyopencl_model_enqueue(cl_queue):
    cl, ctx, queue = cl_queue
    d = ngi.Device.from_pyopencl(queue)
    m = ngi.Model(d, MODELS / "surround.safetensors")
    x = np.random.default_rng(7).uniform(-1, 1, (1, 12, 128, 256)).astype(np.float32)
    mf = cl.mem_flags
    xin = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=x)
    yout = cl.Buffer(ctx, mf.WRITE_ONLY, 3 * 128 * 256 * 4)
    before = d.host_transfers()
    m.enqueue(xin, yout, 128, 256)
    queue.finish()
    assert d.host_transfers() == before  # ngi moved nothing through the host
    y = np.empty((1, 3, 128, 256), np.float32)
    cl.enqueue_copy(queue, y, yout)
    np.testing.assert_array_equal(y, m.run(x))


def test_pyopencl_pipeline_enqueue(cl_queue, frame):
    cl, ctx, queue = cl_queue
    d = ngi.Device.from_pyopencl(queue)
    m = ngi.Model(d, MODELS / "surround.safetensors")
    pipe = ngi.Pipeline(d, 64)
    fd = frame.to_dict()
    planes = np.zeros((6, 16, 64, 64), np.float32)
    for name, first in (("albedo", 0), ("normal", 3), ("depth", 6), ("direct", 7), ("emission", 10), ("env", 13)):
        planes[:, first:first + fd[name].shape[1]] = fd[name]
    mf = cl.mem_flags
    pin = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=planes)
    lm = cl.Buffer(ctx, mf.READ_WRITE, 3 * 64 * 64 * 4)
    pipe.enqueue(m, pin, fd["look"], fd["up"], lightmap=lm)
    queue.finish()
    out = np.empty((3, 64, 64), np.float32)
    cl.enqueue_copy(queue, out, lm)
    np.testing.assert_array_equal(out, pipe.run(m, fd, outputs=["lightmap"])["lightmap"])
    # A wrapped sub-range and an ngi-allocated buffer work the same way.
    whole = ngi.DeviceBuffer.wrap(d, lm)
    assert whole.nbytes == 3 * 64 * 64 * 4 and not whole.owned
    np.testing.assert_array_equal(whole.download([3, 64, 64]), out)


def test_pyopencl_buffer_of_another_context(cl_queue):
    cl, ctx, queue = cl_queue
    d = ngi.Device.from_pyopencl(queue)
    other = cl.Context(ctx.devices)
    m = ngi.Model(d, MODELS / "ao_sculpture_16x8.safetensors")
    foreign = cl.Buffer(other, cl.mem_flags.READ_WRITE, 48 * 16 * 4)
    mine = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 16 * 4)
    with pytest.raises(ngi.InputError, match="another OpenCL context"):
        m.enqueue(foreign, mine, 4, 4)
    with pytest.raises(TypeError, match="int_ptr"):
        m.enqueue(np.zeros(48 * 16, np.float32), mine, 4, 4)


# ---- resources and the GIL ---------------------------------------------------------------------------------

def rss_bytes():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS")


def test_no_leak_over_1000_loads(dev):
    path = MODELS / "ao_sculpture_16x8.safetensors"
    x = np.zeros((4, 48), np.float32)
    for _ in range(50):  # warm-up: program cache, allocator pools
        ngi.Model(dev, path).run(x)
    gc.collect()
    before = rss_bytes()
    for _ in range(1000):
        ngi.Model(dev, path).run(x)
    gc.collect()
    growth = rss_bytes() - before
    print(f"RSS growth over 1000 model loads + runs: {growth / 1e6:.2f} MB")
    # One leaked model would keep ~22 KB of weights and buffers: 1000 of them ~22 MB. Allocator noise stays < 8 MB.
    assert growth < 8e6, f"RSS grew by {growth / 1e6:.1f} MB over 1000 loads"


def test_gil_is_released_during_long_calls(surround):
    x = np.random.default_rng(8).uniform(-1, 1, (1, 12, 256, 512)).astype(np.float32)
    surround.run(x)  # build the graph for this size first
    start = time.perf_counter()
    surround.run(x)
    call = time.perf_counter() - start
    ticks = []
    t = threading.Thread(target=surround.run, args=(x,))
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    gaps = np.diff(ticks) if len(ticks) > 1 else np.array([call])
    # With the GIL held for the whole call this thread would stall for all of it; released, it keeps ticking.
    assert len(ticks) >= 5 and gaps.max() < 0.5 * call, (len(ticks), gaps.max(), call)


def test_type_stubs_match_the_module():
    stub = ast.parse((Path(ngi.__file__).parent / "_ngi.pyi").read_text())
    names = {n.name for n in stub.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    names |= {t.id for n in stub.body if isinstance(n, ast.AnnAssign) for t in [n.target]}
    public = set(ngi._ngi.__all__) | {"__version__"}
    assert names == public, f"missing in stub: {public - names}; not in module: {names - public}"
    for cls in (n for n in stub.body if isinstance(n, ast.ClassDef)):
        methods = {f.name for f in cls.body if isinstance(f, ast.FunctionDef)}
        runtime = {a for a in dir(getattr(ngi, cls.name)) if not a.startswith("_")}
        if not issubclass(getattr(ngi, cls.name), BaseException):
            assert methods - {"__init__", "__enter__", "__exit__"} == runtime, cls.name


def test_help_reads_well():
    import pydoc
    text = pydoc.render_doc(ngi.Pipeline, renderer=pydoc.plaintext)
    assert "run(" in text and "one upload" in text
    assert ngi.__doc__ and "ngi.Device" in ngi.__doc__
    for name in ngi._ngi.__all__:
        assert getattr(ngi, name).__doc__, f"ngi.{name} has no docstring"


def test_display_view_brings_a_lightmap_to_display_resolution(dev, frame):
    # The same camera at face 96 (not a multiple of 64): the pipeline's 64 x 64 lightmap (here its direct light plus
    # a constant indirect 0.25) at 96 x 96, composed with the display frame's own direct light.
    hi = ngi.Renderer(dev, ngi.Scene("room:seed=3")).render(n=96, spp=2, feature_spp=2, frame=5, reference=False)
    lightmap = frame.feature("direct")[0] + 0.25
    view = ngi.DisplayView(dev, 96)
    a = view.run(frame, lightmap, hi, (0, 0, 0), outputs=("lightmap", "final", "display"), stats=True, timings=True)
    assert a["lightmap"].shape == (3, 96, 96) and a["display"].shape == (3, 96, 96)
    assert not a["stats"]["history_used"] and set(a["timings"]) == {"geometry_ms", "upsample_ms", "temporal_ms",
                                                                     "outputs_ms"}
    surface = np.linalg.norm(hi.feature("normal")[0], axis=0) > 0.5
    extra = (a["lightmap"] - hi.feature("direct")[0])[:, surface]
    assert np.allclose(extra, 0.25, atol=1e-5), (extra.min(), extra.max())  # a constant is upsampled exactly
    b = view.run(frame, lightmap, hi, (0, 0, 0), stats=True)
    assert b["stats"]["history_used"] and b["stats"]["disoccluded"] == 0
    view.reset()
    assert not view.run(frame, lightmap, hi, (0, 0, 0), stats=True)["stats"]["history_used"]
    with pytest.raises(ngi.InputError, match="display frame is 64x64"):
        view.run(frame, lightmap, frame, (0, 0, 0))
    with pytest.raises(ngi.InputError, match="jbu, bilinear"):
        ngi.DisplayView(dev, 96, upsampler="nearest")

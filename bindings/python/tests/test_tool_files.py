"""Issue 51, round three: the Python tools (ngi.convert, ngi.onnx_import, ngi.plan) against hostile files.

ngi's file rule, the C++ side's: only regular files are read (judged by os.stat before anything opens them, with a
size cap) or replaced; an output is written beside its path and renamed into place. Conversion refuses what the
model loader would refuse for non-finite numbers. A long graph converts and loads (the loader's fusion, which
replaced the importer's, is linear in the node count). Plans are read strictly. Each failure is one line naming the
file, exit code 1 (2 for ngi.plan's usage errors).

FIFOs and device nodes are made in pytest's tmp_path only. Run by ctest as part of `python_bindings`.
"""

import json
import os
import resource
import stat
import subprocess
import sys
import time

import numpy as np
import pytest

from ngi import model_file
from ngi.model_file import ConversionError


def run_convert(*args, timeout=30):
    """python3 -m ngi.convert ARGS in a child process -> (returncode, stderr). Its address space is capped (2 GiB) and
    it is timed out, so that a regression reading /dev/zero or waiting on a FIFO fails the test, not the machine."""
    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
    proc = subprocess.run([sys.executable, "-m", "ngi.convert", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, preexec_fn=cap)
    return proc.returncode, proc.stderr


def convert(capsys, *args):
    """ngi.convert's main() in this process (no interpreter start-up; for inputs that cannot block) ->
    (returncode, stderr). An exception escaping main() is the traceback the CLI would print: the test fails."""
    from ngi import convert as convert_mod
    rc = convert_mod.main([str(a) for a in args])
    return rc, capsys.readouterr().err


def one_error_line(err, *needles):
    # torch 1.x's warning that it falls back to full unpickling may come first (ngi.convert._torch_load).
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("ngi.convert: warning:")]
    assert len(lines) == 1 and lines[0].startswith("ngi.convert: error: "), err
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


def onnx_module():
    return pytest.importorskip("onnx", reason="ONNX import needs Debian's python3-onnx")


def onnx_bytes(nodes, initializers=(), input_dims=(1, 2, 4, 4)):
    onnx = onnx_module()
    h, tp = onnx.helper, onnx.TensorProto
    graph = h.make_graph(nodes, "g", [h.make_tensor_value_info("x", tp.FLOAT, list(input_dims))],
                         [h.make_tensor_value_info("y", tp.FLOAT, [1, None, None, None])], list(initializers))
    return h.make_model(graph, opset_imports=[h.make_opsetid("", 13)]).SerializeToString()


def weight(name, array):
    onnx = onnx_module()
    array = np.asarray(array, np.float32)
    return onnx.helper.make_tensor(name, onnx.TensorProto.FLOAT, array.shape, array.tobytes(), raw=True)


def node(*args, **kwargs):
    return onnx_module().helper.make_node(*args, **kwargs)


def conv_onnx(w=None):
    """x [1, 2, 4, 4] -> 1 x 1 Conv 'the_conv' (3 output channels) -> y."""
    w = np.ones((3, 2, 1, 1), np.float32) if w is None else w
    return onnx_bytes([node("Conv", ["x", "w"], ["y"], name="the_conv")], [weight("w", w)])


def leaves(folder):
    return sorted(p.name for p in folder.iterdir())


# --------------------------------------------------------------------------
# Finding 1: an output that is not a regular file is refused, before anything is written
# --------------------------------------------------------------------------

def test_convert_refuses_an_output_that_is_not_a_regular_file(tmp_path, capsys):
    src = tmp_path / "model.onnx"
    src.write_bytes(conv_onnx())
    fifo, folder = tmp_path / "fifo_out", tmp_path / "folder_out"
    os.mkfifo(fifo)
    folder.mkdir()
    outputs = [(fifo, "a FIFO, not a regular file"), (folder, "a directory")]
    try:
        os.mknod(tmp_path / "null_out", 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # /dev/null's device numbers
        outputs.append((tmp_path / "null_out", "a device, not a regular file"))
    except PermissionError:
        pass  # not root (no CAP_MKNOD): the FIFO and the folder still test the rule
    before = leaves(tmp_path)
    for out, kind in outputs:
        rc, err = convert(capsys, src, out)
        assert rc == 1, err
        one_error_line(err, f"cannot write {out}: it exists and is {kind}; refusing to replace it")
    assert leaves(tmp_path) == before  # no temporary file left either
    assert stat.S_ISFIFO(fifo.stat().st_mode) and folder.is_dir()
    if len(outputs) == 3:
        assert stat.S_ISCHR((tmp_path / "null_out").stat().st_mode)


def test_written_model_is_renamed_into_place_with_the_umask_mode(tmp_path, capsys):
    # The control: a regular output is replaced whole (written beside it, renamed), no temporary file stays, and the
    # mode is the umask's (the staging file was mkstemp's 0600 before).
    src, out = tmp_path / "model.onnx", tmp_path / "out.safetensors"
    src.write_bytes(conv_onnx())
    out.write_bytes(b"old")
    rc, err = convert(capsys, src, out)
    assert rc == 0, err
    assert model_file.read_config(out)["family"] == "graph"
    assert leaves(tmp_path) == ["model.onnx", "out.safetensors"]
    umask = os.umask(0o022)
    os.umask(umask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask


# --------------------------------------------------------------------------
# Finding 2: inputs must be regular files of a bounded size, checked before any open() that could block
# --------------------------------------------------------------------------

def test_convert_refuses_fifo_and_device_inputs_without_blocking(tmp_path):
    os.mkfifo(tmp_path / "fifo.onnx")
    os.mkfifo(tmp_path / "fifo.pth")
    os.symlink("/dev/zero", tmp_path / "zero.onnx")
    os.symlink("/dev/zero", tmp_path / "zero.pth")
    os.mkdir(tmp_path / "folder.onnx")
    checkpoint = ["--family", "pix2pix_unet", "--bn-mode", "running"]
    for name, kind, extra in [("fifo.onnx", "a FIFO, not a regular file", []),
                              ("fifo.pth", "a FIFO, not a regular file", checkpoint),
                              ("zero.onnx", "a device, not a regular file", []),
                              ("zero.pth", "a device, not a regular file", checkpoint),
                              ("folder.onnx", "a directory", [])]:
        rc, err = run_convert(tmp_path / name, tmp_path / "out.safetensors", *extra)
        assert rc == 1, err
        one_error_line(err, f"cannot read {tmp_path / name}: it is {kind}")
    assert not (tmp_path / "out.safetensors").exists()


def test_convert_refuses_inputs_beyond_the_size_cap(tmp_path):
    # Sparse files: their size is what stat says, without a byte on the disk. ONNX: protobuf's 2 GiB; checkpoints:
    # the model loader's 4 GiB.
    from ngi.onnx_import import ONNX_MAX_BYTES
    for name, size, extra in [("big.onnx", ONNX_MAX_BYTES + 1, []),
                              ("big.pth", model_file.MAX_INPUT_BYTES + 1,
                               ["--family", "pix2pix_unet", "--bn-mode", "running"])]:
        with open(tmp_path / name, "wb") as f:
            f.truncate(size)
        rc, err = run_convert(tmp_path / name, tmp_path / "out.safetensors", *extra)
        assert rc == 1, err
        one_error_line(err, f"cannot read {tmp_path / name}: it is larger ({size} bytes) than the limit")


# --------------------------------------------------------------------------
# Finding 3: write failures and missing or unreadable inputs are one line, exit 1 (they were tracebacks)
# --------------------------------------------------------------------------

def test_convert_write_failures_and_missing_inputs_are_one_line(tmp_path, capsys):
    src = tmp_path / "model.onnx"
    src.write_bytes(conv_onnx())
    (tmp_path / "a_file").write_bytes(b"")
    for out, reason in [(tmp_path / "missing" / "out.safetensors", "No such file or directory"),
                        (tmp_path / "a_file" / "out.safetensors", "Not a directory")]:
        rc, err = convert(capsys, src, out)
        assert rc == 1, err
        one_error_line(err, f"cannot write {out}: {reason}")
    rc, err = convert(capsys, tmp_path / "missing.pth", tmp_path / "out.safetensors", "--family", "pix2pix_unet",
                      "--bn-mode", "running")
    assert rc == 1, err
    one_error_line(err, f"cannot read {tmp_path / 'missing.pth'}: No such file or directory")
    assert leaves(tmp_path) == ["a_file", "model.onnx"]


def test_convert_refuses_a_corrupt_checkpoint_in_one_line(tmp_path, capsys):
    pytest.importorskip("torch")
    bad = tmp_path / "bad.pth"
    bad.write_bytes(b"garbage\n")
    rc, err = convert(capsys, bad, tmp_path / "out.safetensors", "--family", "pix2pix_unet", "--bn-mode", "running")
    assert rc == 1, err
    one_error_line(err, f"{bad} is not a readable PyTorch checkpoint")


def test_write_model_failures_name_the_file(tmp_path):
    out = tmp_path / "missing" / "m.safetensors"
    with pytest.raises(ConversionError, match=f"cannot write {out}: No such file or directory"):
        model_file.write_model(out, {}, {"family": "ssgi"})


# --------------------------------------------------------------------------
# Finding 4: conversion refuses non-finite numbers (and slopes) that the loader refuses
# --------------------------------------------------------------------------

def test_convert_refuses_non_finite_attributes_and_weights(tmp_path, capsys):
    src = tmp_path / "bad.onnx"
    leaky = [node("LeakyRelu", ["x"], ["y"], name="the_leaky", alpha=float("nan"))]
    big = np.full((3, 2, 1, 1), 1e5, np.float32)
    cases = [
        (onnx_bytes(leaky), [], "node 'the_leaky' (LeakyRelu): attribute 'alpha' is nan: not a finite number"),
        (onnx_bytes([node("LeakyRelu", ["x"], ["y"], name="the_leaky", alpha=2.0)]), [],
         "node 'the_leaky' (LeakyRelu): alpha 2.0: ngi's leaky_relu slope must lie in [-1, 1]"),
        (conv_onnx(np.full((3, 2, 1, 1), np.inf, np.float32)), [],
         "node 'the_conv' (conv2d): its weight has 6 value(s) that are not finite F32 numbers"),
        (conv_onnx(big), ["--half"], "node 'the_conv' (conv2d): its weight has 6 value(s) that are not finite F16"),
    ]
    for data, extra, needle in cases:
        src.write_bytes(data)
        rc, err = convert(capsys, src, tmp_path / "out.safetensors", *extra)
        assert rc == 1, err
        one_error_line(err, f"{src}: {needle}")
        assert leaves(tmp_path) == ["bad.onnx"]
    # Finite weights whose fold would not be (1e5 x 1e34 is beyond float32's 3.4e38) were refused while the importer
    # folded. The file now holds the network as written, which float32 computes (x * 1e5, then * 1e34); the loader
    # does not make that fold (tests/test_graph_fuse.cpp, "a fold that would overflow float32 is not made").
    scale = weight("s", np.full((1, 3, 1, 1), 1e34, np.float32))
    nodes = [node("Conv", ["x", "w"], ["c"], name="the_conv"), node("Mul", ["c", "s"], ["y"], name="the_mul")]
    src.write_bytes(onnx_bytes(nodes, [weight("w", big), scale]))
    rc, err = convert(capsys, src, tmp_path / "out.safetensors")
    assert rc == 0, err
    assert [n["op"] for n in model_file.read_config(tmp_path / "out.safetensors")["graph"]["nodes"]] == \
        ["conv2d", "affine"]


def test_write_model_refuses_a_non_finite_config_number(tmp_path):
    # The last line of defence: json.dumps would write NaN, which no JSON reader (the loader's "malformed JSON") takes.
    out = tmp_path / "m.safetensors"
    config = {"family": "graph", "graph": {"nodes": [{"name": "a"}, {"name": "b", "slope": float("nan")}]}}
    with pytest.raises(ConversionError, match=r"field 'graph.nodes\[1\].slope' is not a finite number"):
        model_file.write_model(out, {}, config)
    assert leaves(tmp_path) == []


# --------------------------------------------------------------------------
# Finding 5: fusion is linear in the node count
# --------------------------------------------------------------------------

def test_a_3900_node_graph_converts_and_loads_in_seconds(tmp_path):
    # The shape that made the importer's old fusion cubic: a long head of nodes that never fold (every restart walked
    # past them, and the second pass looked for each one's readers in the whole list), then foldable nodes: 1,950
    # Relu, then 650 x (Conv, Tanh, Relu): each Tanh folds into its Conv's epilogue, each Relu before a Conv into its
    # gather. 3,900 ONNX nodes, ~130 KB (that code: 7.4 s at 1,200 nodes, several minutes at 3,900). The importer
    # writes them as nodes now and the loader fuses (host/src/models/graph_fuse.cpp, one walk a pass).
    nodes, inits, prev = [], [], "x"
    ops = ["Relu"] * 1950 + ["Conv", "Tanh", "Relu"] * 650
    for k, op in enumerate(ops):
        out = "y" if k == len(ops) - 1 else f"t{k}"
        if op == "Conv":
            inits.append(weight(f"w{k}", np.full((1, 1, 1, 1), 0.5, np.float32)))
            nodes.append(node("Conv", [prev, f"w{k}"], [out], name=f"n{k}"))
        else:
            nodes.append(node(op, [prev], [out], name=f"n{k}"))
        prev = out
    src, out = tmp_path / "long.onnx", tmp_path / "long.safetensors"
    src.write_bytes(onnx_bytes(nodes, inits, input_dims=(1, 1, 1, 1)))
    t0 = time.perf_counter()
    rc, err = run_convert(src, out, timeout=60)
    seconds = time.perf_counter() - t0
    assert rc == 0, err
    assert seconds < 30, f"{seconds:.1f} s"
    graph = model_file.read_config(out)["graph"]["nodes"]
    assert [n["op"] for n in graph] == ["activation"] * 1950 + ["conv2d", "activation", "activation"] * 650
    assert not any("input_activation" in n for n in graph)  # as ONNX describes it: nothing fused
    print(f"3,900-node conversion (whole CLI): {seconds:.2f} s")
    # The loader fuses it to 1,950 + 650 nodes and runs it: relu, then 650 x relu(tanh(0.5 v)).
    native = pytest.importorskip("ngi._ngi", reason="the native module (not in sanitizer builds)")
    t0 = time.perf_counter()
    model = native.Model(native.Device(os.environ.get("NGI_TEST_DEVICE", "cpu")), str(out))
    y = model.run(np.full((1, 1, 1, 1), 0.75, np.float32))
    seconds = time.perf_counter() - t0
    v = np.float64(0.75)
    for _ in range(650):
        v = max(np.tanh(0.5 * v), 0.0)
    assert abs(float(y.reshape(-1)[0]) - v) < 1e-6
    assert seconds < 60, f"{seconds:.1f} s"
    print(f"3,900-node load (fusion, 2,600 ops built) and run: {seconds:.2f} s")


# --------------------------------------------------------------------------
# Findings 6 and 7: plans are read strictly (ngi.plan.read_plan; `ngi lightmap --plan` is the C++ reader)
# --------------------------------------------------------------------------

def write_plan(folder, text):
    path = folder / "plan.json"
    path.write_text(text)
    return path


def plan_text(model, **extra):
    return json.dumps({"format": "ngi-plan", "version": 1, "rung": "r", "model": model, "n": 64,
                       "bn_mode": "running", **extra})


def test_plan_reader_refuses_duplicate_keys(tmp_path):
    plan = pytest.importorskip("ngi.plan")
    (tmp_path / "m.safetensors").write_bytes(b"")
    good = plan_text("m.safetensors")
    assert plan.read_plan(write_plan(tmp_path, good))["model"] == "m.safetensors"
    dup = good[:-1] + ', "model": "other.safetensors"}'  # the second "model" silently won
    with pytest.raises(plan.PlanFileError, match="the key 'model' appears twice in one object"):
        plan.read_plan(write_plan(tmp_path, dup))
    nested = good[:-1] + ', "switch": {"below_outside_light_share": 0.1, "rung": "a", "rung": "b", "model": null}}'
    with pytest.raises(plan.PlanFileError, match="the key 'rung' appears twice"):
        plan.read_plan(write_plan(tmp_path, nested))


def test_plan_reader_says_what_a_model_path_is(tmp_path):
    plan = pytest.importorskip("ngi.plan")
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "folder").mkdir()
    for model, what in [("/dev/zero", "is a device, not a regular file"), ("fifo", "is a FIFO, not a regular file"),
                        ("folder", "is a directory"), ("missing.safetensors", "does not exist")]:
        path = write_plan(tmp_path, plan_text(model))
        with pytest.raises(plan.PlanFileError) as info:
            plan.read_plan(path)
        shown = model if os.path.isabs(model) else tmp_path / model
        assert f"plan {path}: the top level.model: {shown} {what} (rung r)" == str(info.value)
    # The plan itself by the same rule.
    with pytest.raises(plan.PlanFileError, match="it is a FIFO, not a regular file"):
        plan.read_plan(tmp_path / "fifo")


def test_plan_refuses_an_out_that_is_not_a_regular_file(tmp_path, capsys):
    plan = pytest.importorskip("ngi.plan")
    os.mkfifo(tmp_path / "fifo.json")
    with pytest.raises(SystemExit) as info:  # before the zoo (missing here) or any device work
        plan.main(["--scene", "room", "--max-ms", "1", "--zoo", str(tmp_path / "nozoo.json"),
                   "--out", str(tmp_path / "fifo.json")])
    assert info.value.code == 2
    assert "it exists and is a FIFO, not a regular file; refusing to replace it" in capsys.readouterr().err
    assert stat.S_ISFIFO((tmp_path / "fifo.json").stat().st_mode)

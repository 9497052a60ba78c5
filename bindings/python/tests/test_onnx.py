"""ONNX import (python3 -m ngi.convert model.onnx out; ngi.onnx_import, docs/MODEL_FORMAT.md family "graph").

torch.onnx.export of three of ngi's networks (small widths, so the whole file runs in seconds) is converted by the
CLI and run on the test device; the outputs are compared with the PyTorch module in float64. Then the bad-input
classes of issue 28: each ONNX file is refused with one error naming the problem and nothing is written; and the C++
loader refuses hand-made "graph" files whose node list is hostile, naming the node.
"""

import copy
import io
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import ngi
from ngi.model_file import write_model

onnx = pytest.importorskip("onnx", reason="ONNX import needs Debian's python3-onnx (tools/install-deps.sh)")
torch = pytest.importorskip("torch")

from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from ngi import neural_gi as ngi_net  # noqa: E402
from ngi.reference_models import ao_mlp, build_generator  # noqa: E402


@pytest.fixture(scope="module")
def dev():
    return ngi.Device(os.environ.get("NGI_TEST_DEVICE", "cpu"))


def export(module, example):
    """torch.onnx.export in eval mode at opset 13, as bytes."""
    f = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torch.onnx.export(module, example, f, opset_version=13)
    return f.getvalue()


def convert(tmp_path, data, name="model"):
    """Writes `data` as name.onnx and runs the CLI; returns (returncode, stderr, output path)."""
    src = tmp_path / f"{name}.onnx"
    src.write_bytes(data)
    out = tmp_path / f"{name}.safetensors"
    proc = subprocess.run([sys.executable, "-m", "ngi.convert", str(src), str(out)], capture_output=True, text=True)
    return proc.returncode, proc.stderr, out


def randomize_batch_norm(module):
    """Running statistics and affine parameters away from their 0 / 1 initial values, so folding them is tested."""
    g = torch.Generator().manual_seed(7)
    for m in module.modules():
        if isinstance(m, torch.nn.BatchNorm2d):
            m.running_mean.copy_(torch.rand(m.num_features, generator=g) - 0.5)
            m.running_var.copy_(torch.rand(m.num_features, generator=g) * 1.5 + 0.5)
            m.weight.data.copy_(torch.rand(m.num_features, generator=g) + 0.5)
            m.bias.data.copy_(torch.rand(m.num_features, generator=g) - 0.5)


def reference(module, x):
    with torch.no_grad():
        return copy.deepcopy(module).double()(torch.from_numpy(x).double()).numpy()


# --------------------------------------------------------------------------
# Round trips
# --------------------------------------------------------------------------

def export_at(module, example, opset):
    f = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torch.onnx.export(module.eval(), example, f, opset_version=opset)
    return f.getvalue()


class _MobileBlock(torch.nn.Module):
    """MobileNet-style depthwise-separable block: conv, BN, ReLU; depthwise 3 x 3 (groups = C); pointwise 1 x 1."""

    def __init__(self):
        super().__init__()
        self.stem = torch.nn.Sequential(torch.nn.Conv2d(3, 8, 3, padding=1), torch.nn.BatchNorm2d(8), torch.nn.ReLU())
        self.dw = torch.nn.Sequential(torch.nn.Conv2d(8, 8, 3, padding=1, groups=8), torch.nn.BatchNorm2d(8),
                                      torch.nn.ReLU())
        self.pw = torch.nn.Conv2d(8, 16, 1)

    def forward(self, x):
        return self.pw(self.dw(self.stem(x)))


class _MobileV2Block(torch.nn.Module):
    """MobileNetV2-style inverted residual: 1 x 1 expansion, ReLU6, depthwise 3 x 3, ReLU6, 1 x 1 projection, the
    residual add; then SiLU (x sigmoid(x)), PReLU with one slope and a Clip with an upper bound only."""

    def __init__(self):
        super().__init__()
        self.expand = torch.nn.Sequential(torch.nn.Conv2d(4, 12, 1), torch.nn.BatchNorm2d(12), torch.nn.ReLU6())
        self.dw = torch.nn.Sequential(torch.nn.Conv2d(12, 12, 3, padding=1, groups=12), torch.nn.BatchNorm2d(12),
                                      torch.nn.ReLU6())
        self.project = torch.nn.Sequential(torch.nn.Conv2d(12, 4, 1), torch.nn.BatchNorm2d(4))
        self.prelu = torch.nn.PReLU()

    def forward(self, x):
        y = x + self.project(self.dw(self.expand(x * 4.0)))
        y = self.prelu(torch.nn.functional.silu(y))
        return torch.clamp(y, max=0.5)


class _Espcn(torch.nn.Module):
    """ESPCN-style upsampler: convolutions, then PixelShuffle (DepthToSpace)."""

    def __init__(self):
        super().__init__()
        self.body = torch.nn.Sequential(torch.nn.Conv2d(3, 12, 5, padding=2), torch.nn.Tanh(),
                                        torch.nn.Conv2d(12, 3 * 4, 3, padding=1), torch.nn.PixelShuffle(2))

    def forward(self, x):
        return self.body(x)


class _PoolUnet(torch.nn.Module):
    """An OIDN-style level: conv, average pooling, conv, nearest upsampling, skip concatenation, conv."""

    def __init__(self):
        super().__init__()
        self.enc = torch.nn.Conv2d(3, 6, 3, padding=1)
        self.pool = torch.nn.AvgPool2d(2)
        self.mid = torch.nn.Conv2d(6, 6, 3, padding=1)
        self.dec = torch.nn.Conv2d(12, 3, 3, padding=1)

    def forward(self, x):
        e = torch.relu(self.enc(x))
        m = torch.relu(self.mid(self.pool(e)))
        u = torch.nn.functional.interpolate(m, scale_factor=2, mode="nearest")
        return self.dec(torch.cat([u, e], 1))


class _DilatedGrouped(torch.nn.Module):
    """A dilated convolution, a grouped convolution, a grouped transposed convolution."""

    def __init__(self):
        super().__init__()
        self.dil = torch.nn.Conv2d(4, 6, 3, padding=2, dilation=2)
        self.conv = torch.nn.Conv2d(6, 4, 3, padding=1, groups=2)
        self.up = torch.nn.ConvTranspose2d(4, 6, 4, stride=2, padding=1, groups=2)

    def forward(self, x):
        return self.up(torch.relu(self.conv(torch.relu(self.dil(x)))))


class _MaxPoolUnet(torch.nn.Module):
    """OIDN's level: conv, 2 x 2 max pooling, conv, nearest upsampling, skip concatenation; and a ResNet stem's
    3 x 3 / stride 2 / pad 1 max pooling (padding that must never win)."""

    def __init__(self):
        super().__init__()
        self.enc = torch.nn.Conv2d(3, 6, 3, padding=1)
        self.mid = torch.nn.Conv2d(6, 6, 3, padding=1)
        self.dec = torch.nn.Conv2d(12, 3, 3, padding=1)

    def forward(self, x):
        e = torch.relu(self.enc(x))
        m = torch.relu(self.mid(torch.nn.functional.max_pool2d(e, 2)))
        u = torch.nn.functional.interpolate(m, scale_factor=2, mode="nearest")
        y = self.dec(torch.cat([u, e], 1))
        return torch.nn.functional.max_pool2d(y - 2.0, 3, stride=2, padding=1)


class _SqueezeExcite(torch.nn.Module):
    """torchvision's squeeze-excitation (global average pool, 1 x 1 convolutions, sigmoid gate multiplied in) and a
    ReduceMean over H and W added back (x.mean((2, 3), keepdim=True))."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(4, 8, 3, padding=1)
        self.fc1 = torch.nn.Conv2d(8, 2, 1)
        self.fc2 = torch.nn.Conv2d(2, 8, 1)
        self.out = torch.nn.Conv2d(8, 3, 1)

    def forward(self, x):
        y = torch.relu(self.conv(x))
        s = torch.sigmoid(self.fc2(torch.relu(self.fc1(torch.nn.functional.adaptive_avg_pool2d(y, 1)))))
        y = y * s
        return self.out(y + y.mean((2, 3), keepdim=True))


class _InstanceNormGelu(torch.nn.Module):
    """Style-transfer / diffusion-style activations: instance normalization (affine), exact GELU (Erf), Softplus."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(3, 6, 3, padding=1)
        self.norm = torch.nn.InstanceNorm2d(6, affine=True)
        self.conv2 = torch.nn.Conv2d(6, 3, 3, padding=1)

    def forward(self, x):
        y = torch.nn.functional.gelu(self.norm(self.conv(x) * 3.0))
        return torch.nn.functional.softplus(self.conv2(y) * 4.0)


class _PReluPerChannel(torch.nn.Module):
    """A PReLU with a slope per channel (SRGAN / EDSR-style bodies), slopes on both sides of 0 and above 1."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(3, 6, 3, padding=1)
        self.act = torch.nn.PReLU(6)
        self.out = torch.nn.Conv2d(6, 3, 3, padding=1)
        with torch.no_grad():
            self.act.weight.copy_(torch.tensor([0.25, -0.5, 0.0, 1.5, 0.01, -1.0]))

    def forward(self, x):
        return self.out(self.act(self.conv(x)))


class _DiffusersBlock(torch.nn.Module):
    """A diffusers-style up block: GroupNorm + SiLU, bilinear upsampling (half-pixel), a reflect-padded convolution, an
    edge-padded one and an align-corners bilinear downsampling."""

    def __init__(self):
        super().__init__()
        self.conv_in = torch.nn.Conv2d(3, 8, 3, padding=1)
        self.norm = torch.nn.GroupNorm(4, 8)
        self.conv = torch.nn.Conv2d(8, 6, 3)
        self.norm2 = torch.nn.GroupNorm(2, 6, eps=1e-6)
        self.conv_out = torch.nn.Conv2d(6, 3, 3)

    def forward(self, x):
        f = torch.nn.functional
        y = f.silu(self.norm(self.conv_in(x) * 2.0))
        y = f.interpolate(y, scale_factor=2, mode="bilinear", align_corners=False)
        y = f.silu(self.norm2(self.conv(f.pad(y, (1, 1, 1, 1), mode="reflect"))))
        y = self.conv_out(f.pad(y, (2, 0, 1, 1), mode="replicate"))
        return f.interpolate(y, scale_factor=0.75, mode="bilinear", align_corners=True)


class _TransposeOutputPadding(torch.nn.Module):
    """ConvTranspose with output_padding (the decoder of many autoencoders: stride 2, kernel 3, padding 1,
    output_padding 1 doubles the size exactly), and a crop written as a negative F.pad."""

    def __init__(self):
        super().__init__()
        self.up = torch.nn.ConvTranspose2d(3, 6, 3, stride=2, padding=1, output_padding=1)
        self.up3 = torch.nn.ConvTranspose2d(6, 3, 5, stride=3, padding=2, output_padding=2)

    def forward(self, x):
        y = torch.relu(self.up(x))
        return torch.nn.functional.pad(self.up3(y), (-1, 0, -2, -1))


class _ResizeToSize(torch.nn.Module):
    """Bilinear resizes to fixed sizes (F.interpolate(size=...): ONNX sizes from Shape(x)), half-pixel and
    align-corners, up and down."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(3, 4, 3, padding=1)

    def forward(self, x):
        f = torch.nn.functional
        y = f.interpolate(self.conv(x), size=(23, 9), mode="bilinear", align_corners=False)
        return f.interpolate(torch.tanh(y), size=(12, 20), mode="bilinear", align_corners=True)


class _SqueezeExciteLinear(torch.nn.Module):
    """Squeeze-excitation as many ResNets write it: a mean over H and W (keepdims off), Linear layers, the gate
    reshaped with view(b, c, 1, 1); and a second gate through Flatten and an Unsqueeze."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(4, 8, 3, padding=1)
        self.fc1 = torch.nn.Linear(8, 2)
        self.fc2 = torch.nn.Linear(2, 8)
        self.fc3 = torch.nn.Linear(8, 8)

    def forward(self, x):
        y = torch.relu(self.conv(x))
        b, c = y.shape[:2]
        s = torch.sigmoid(self.fc2(torch.relu(self.fc1(y.mean((2, 3))))))
        y = y * s.view(b, c, 1, 1)
        t = torch.tanh(self.fc3(torch.flatten(torch.nn.functional.adaptive_avg_pool2d(y, 1), 1)))
        return y + t[:, :, None, None]


@pytest.mark.parametrize("opset", [13, 17])
@pytest.mark.parametrize("name,make,channels", [("mobile", _MobileBlock, 3), ("mobile_v2", _MobileV2Block, 4),
                                                ("espcn", _Espcn, 3),
                                                ("pool_unet", _PoolUnet, 3), ("dilated", _DilatedGrouped, 4),
                                                ("maxpool_unet", _MaxPoolUnet, 3), ("squeeze_excite", _SqueezeExcite, 4),
                                                ("instance_norm_gelu", _InstanceNormGelu, 3),
                                                ("prelu_per_channel", _PReluPerChannel, 3),
                                                ("diffusers_block", _DiffusersBlock, 3),
                                                ("squeeze_excite_linear", _SqueezeExciteLinear, 4),
                                                ("transpose_output_padding", _TransposeOutputPadding, 3),
                                                ("resize_to_size", _ResizeToSize, 3)])
def test_common_blocks_convert_with_pytorch_parity(dev, tmp_path, name, make, channels, opset):
    # Issue 48: blocks public projects write -- depthwise-separable convolutions, PixelShuffle, average pooling with
    # nearest upsampling, dilated and grouped convolutions, explicit zero padding -- convert (as the exact dense or
    # channel-copying convolutions they equal) and match PyTorch in float64 within 1e-5 relative to the output's range.
    torch.manual_seed(21)
    net = make().eval()
    randomize_batch_norm(net)
    rc, err, out = convert(tmp_path, export_at(net, torch.randn(1, channels, 16, 16), opset), name)
    assert rc == 0, err
    model = ngi.Model(dev, out)
    x = np.random.default_rng(22).uniform(-1, 1, (1, channels, 16, 16)).astype(np.float32)
    want = reference(net, x)
    got = model.run(x)
    assert got.shape == want.shape
    rel = float(np.max(np.abs(got - want)) / np.max(np.abs(want)))
    print(f"{name} opset {opset}: max |ngi - PyTorch float64| / max |PyTorch| = {rel:.3g}")
    assert rel < 1e-5


def test_pix2pix_generator_round_trip(dev, tmp_path):
    # junyanz UnetGenerator (eval: BatchNorm with running statistics, dropout off), ngf 4, 5 levels, 64 x 32.
    torch.manual_seed(1)
    net = build_generator("pix2pix_unet", 3, 3, 4, 5).eval()
    randomize_batch_norm(net)
    rc, err, out = convert(tmp_path, export(net, torch.randn(1, 3, 64, 32)), "pix2pix")
    assert rc == 0, err
    model = ngi.Model(dev, out)
    assert model.config["family"] == "graph" and model.config["layout"] == "nchw"
    nodes = model.config["metadata"]["graph"]["nodes"]
    # The file holds the network as ONNX describes it: 5 conv + 5 conv_transpose + 4 concat, the BatchNorms the
    # exporter did not fold into a Conv as affines (those after a ConvTranspose), LeakyReLU / ReLU / Tanh activation
    # nodes (the loader folds them: tests/test_graph_fuse.cpp).
    ops = [n["op"] for n in nodes]
    assert (ops.count("conv2d"), ops.count("conv_transpose2d"), ops.count("concat")) == (5, 5, 4)
    assert ops.count("affine") >= 4 and ops.count("activation") >= 9
    assert not any("input_activation" in n or ("activation" in n and n["op"] != "activation") for n in nodes)
    x = np.random.default_rng(2).uniform(-1, 1, (1, 3, 64, 32)).astype(np.float32)
    err_max = float(np.max(np.abs(model.run(x) - reference(net, x))))
    print(f"pix2pix ONNX round trip: max |ngi - PyTorch float64| = {err_max:.3g}")
    # float32 sums of at most 4*4*8*ngf = 512 products per layer over 10 layers, outputs in [-1, 1]: ~1e-6 seen.
    assert err_max < 1e-4
    # The graph is not tied to the exported size: another multiple of 2^5.
    y = np.random.default_rng(3).uniform(-1, 1, (1, 3, 32, 96)).astype(np.float32)
    assert float(np.max(np.abs(model.run(y) - reference(net, y)))) < 1e-4


def test_ao_mlp_round_trip(dev, tmp_path):
    # Seed 001's AO network as training builds it (48 -> x -> y -> 1, tanh), exported on [N, 48] points: Gemm nodes.
    torch.manual_seed(4)
    net = ao_mlp(16, 8).eval()
    rc, err, out = convert(tmp_path, export(net, torch.randn(5, 48)), "ao")
    assert rc == 0, err
    model = ngi.Model(dev, out)
    assert model.config["layout"] == "nc"
    assert [n["op"] for n in model.config["metadata"]["graph"]["nodes"]] == ["dense", "activation"] * 2 + ["dense"]
    x = np.random.default_rng(5).uniform(-1, 1, (300, 48)).astype(np.float32)
    y = model.run(x)
    assert y.shape == (300, 1)
    err_max = float(np.max(np.abs(y - reference(net, x))))
    print(f"AO MLP ONNX round trip: max |ngi - PyTorch float64| = {err_max:.3g}")
    assert err_max < 1e-5  # 48-term float32 dot products, |values| < ~3


def test_neural_gi_round_trip(dev, tmp_path):
    # ngi.neural_gi.NeuralGI (U-Net buffer, Eq. 3 encoding, DeepSDF MLP with a skip, exp decoding, nan_to_num),
    # small: buffer 4, ngf 4, 5 levels, MLP 3 x 16 with the input re-injected at layer 2; 32 x 32.
    torch.manual_seed(6)
    net = ngi_net.NeuralGI(buffer_channels=4, ngf=4, num_downs=5, mlp_width=16, mlp_depth=3, skip_layer=2).eval()
    randomize_batch_norm(net)
    rc, err, out = convert(tmp_path, export(net, torch.randn(1, 18, 32, 32)), "neural_gi")
    assert rc == 0, err
    model = ngi.Model(dev, out)
    ops = [n["op"] for n in model.config["metadata"]["graph"]["nodes"]]
    assert ops.count("frequency_encode") == 1 and ops[-1] == "nan_to_num"
    x = np.random.default_rng(7).uniform(-1, 1, (1, 18, 32, 32)).astype(np.float32)
    want = reference(net, x)
    rel = float(np.max(np.abs(model.run(x) - want) / want))
    print(f"Neural GI ONNX round trip: max relative |ngi - PyTorch float64| = {rel:.3g}")
    # As tests/test_neural_gi_model.cpp: the encoding's top band multiplies x by 2^8 pi in float32, whose rounding
    # the MLP and the exp carry into a relative error of the order of 1e-4.
    assert rel < 2e-3


# --------------------------------------------------------------------------
# Bad ONNX files: one clear error, nothing written
# --------------------------------------------------------------------------

def small_model(nodes, initializers=(), input_dims=(1, 2, 8, 8), opset=13, outputs=("y",)):
    graph = helper.make_graph(
        nodes, "g", [helper.make_tensor_value_info("x", TensorProto.FLOAT, list(input_dims))],
        [helper.make_tensor_value_info(o, TensorProto.FLOAT, [1, None, None, None]) for o in outputs], list(initializers))
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)])


def conv_weight(raw_bytes=None):
    w = np.ones((3, 2, 3, 3), np.float32)
    t = helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.tobytes(), raw=True)
    if raw_bytes is not None:
        t.raw_data = raw_bytes
    return t


def conv_model(**kw):
    return small_model([helper.make_node("Conv", ["x", "w"], ["y"], name="the_conv", pads=[1, 1, 1, 1])],
                       [conv_weight(kw.pop("raw_bytes", None))], **kw)


def assert_refused(tmp_path, data, *needles):
    rc, err, out = convert(tmp_path, data, "bad")
    assert rc == 1, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("ngi.convert: error:"), err
    for needle in needles:
        assert needle in lines[0], lines[0]
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["bad.onnx"]  # no temporary file left either


def test_a_valid_small_model_converts(tmp_path, dev):
    # The control for the cases below: the same model unbroken converts and runs (3 x 3 conv, pad 1).
    rc, err, out = convert(tmp_path, conv_model().SerializeToString())
    assert rc == 0, err
    y = ngi.Model(dev, out).run(np.ones((1, 2, 8, 8), np.float32))
    assert y.shape == (1, 3, 8, 8) and y[0, 0, 4, 4] == pytest.approx(18.0) and y[0, 0, 0, 0] == pytest.approx(8.0)
    if os.environ.get("NGI_CLI"):  # the README's path: ngi generate on the imported model, on another size
        np.save(tmp_path / "x.npy", np.ones((1, 2, 6, 10), np.float32))
        proc = subprocess.run([os.environ["NGI_CLI"], "generate", "--model", str(out), "--input",
                               str(tmp_path / "x.npy"), "--output", str(tmp_path / "y.npy")],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        assert np.load(tmp_path / "y.npy").shape == (1, 3, 6, 10)


def test_elementwise_nodes_round_trip(tmp_path, dev):
    # Ops that fold into no convolution: Relu, Mul and Add of computed tensors (in place, so x is copied for its other
    # readers), Sub and Div by constants, a BatchNormalization alone (affine), Sigmoid, LeakyRelu, Concat.
    c = np.array([0.25, -0.5], np.float32).reshape(1, 2, 1, 1)
    bn = [np.array(v, np.float32) for v in ([1.5, 0.5], [0.1, -0.2], [0.3, -0.1], [2.0, 0.5])]
    inits = [helper.make_tensor("c", TensorProto.FLOAT, c.shape, c.tobytes(), raw=True),
             helper.make_tensor("two", TensorProto.FLOAT, [], [2.0])]
    inits += [helper.make_tensor(n, TensorProto.FLOAT, [2], v.tobytes(), raw=True)
              for n, v in zip(("g", "b", "m", "v"), bn)]
    nodes = [helper.make_node("Relu", ["x"], ["r"], name="relu"),
             helper.make_node("Mul", ["x", "r"], ["xr"], name="mul"),
             helper.make_node("Add", ["xr", "x"], ["a"], name="add"),
             helper.make_node("Sub", ["a", "c"], ["s"], name="sub"),
             helper.make_node("Div", ["s", "two"], ["d"], name="div"),
             helper.make_node("BatchNormalization", ["d", "g", "b", "m", "v"], ["n"], name="bn", epsilon=1e-3),
             helper.make_node("Sigmoid", ["n"], ["sig"], name="sigmoid"),
             helper.make_node("LeakyRelu", ["x"], ["l"], name="leaky", alpha=0.1),
             helper.make_node("Concat", ["sig", "l"], ["y"], name="cat", axis=1)]
    rc, err, out = convert(tmp_path, small_model(nodes, inits, input_dims=(1, 2, 4, 4)).SerializeToString())
    assert rc == 0, err
    x = np.random.default_rng(9).uniform(-2, 2, (1, 2, 4, 4)).astype(np.float32)
    g, b, m, v = (t.astype(np.float64).reshape(1, 2, 1, 1) for t in bn)
    d = ((x * np.maximum(x, 0) + x) - c) / 2.0
    n = (d - m) / np.sqrt(v + 1e-3) * g + b
    want = np.concatenate([1 / (1 + np.exp(-n)), np.where(x >= 0, x, 0.1 * x)], axis=1)
    got = ngi.Model(dev, out).run(x)
    assert float(np.max(np.abs(got - want))) < 1e-6


def test_matmul_and_gemm_round_trip(tmp_path, dev):
    # [N, C] items: MatMul by a constant + Add of a bias row (the loader folds it into the dense layer), Relu, Gemm with
    # transB = 0, alpha and beta.
    rng = np.random.default_rng(10)
    w1, b1 = rng.normal(size=(6, 5)).astype(np.float32), rng.normal(size=5).astype(np.float32)
    w2, b2 = rng.normal(size=(5, 3)).astype(np.float32), rng.normal(size=(1, 3)).astype(np.float32)
    inits = [helper.make_tensor(n, TensorProto.FLOAT, v.shape, v.tobytes(), raw=True)
             for n, v in (("w1", w1), ("b1", b1), ("w2", w2), ("b2", b2))]
    nodes = [helper.make_node("MatMul", ["x", "w1"], ["h"], name="matmul"),
             helper.make_node("Add", ["h", "b1"], ["hb"], name="bias"),
             helper.make_node("Relu", ["hb"], ["r"], name="relu"),
             helper.make_node("Gemm", ["r", "w2", "b2"], ["y"], name="gemm", alpha=0.5, beta=2.0)]
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [4, 6])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [4, 3])], inits)
    data = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)]).SerializeToString()
    rc, err, out = convert(tmp_path, data)
    assert rc == 0, err
    model = ngi.Model(dev, out)
    # The bias Add an affine, the Relu an activation node (the loader folds both into the first dense layer).
    assert [n["op"] for n in model.config["metadata"]["graph"]["nodes"]] == ["dense", "affine", "activation", "dense"]
    x = rng.normal(size=(37, 6)).astype(np.float32)
    want = 0.5 * np.maximum(x.astype(np.float64) @ w1 + b1, 0) @ w2 + 2.0 * b2
    assert float(np.max(np.abs(model.run(x) - want))) < 1e-5


def test_what_the_loader_would_refuse_is_refused_at_conversion(tmp_path):
    # Issue 51: the converter used to write files the C++ loader then refused; now it applies the loader's limits
    # (ngi/_constants.py, from host/src/models/graph_model.hpp) and names the .onnx file and the node.
    long = "n" * 600  # a node name of 600 bytes (the loader reads 1..512)
    data = small_model([helper.make_node("Conv", ["x", "w"], ["y"], name=long, pads=[1, 1, 1, 1])],
                       [conv_weight()]).SerializeToString()
    assert_refused(tmp_path, data, "bad.onnx", "600 bytes", "1..512 bytes")
    # A tensor name past the limit, on the graph's input.
    wide = "x" * 513
    nodes = [helper.make_node("Conv", [wide, "w"], ["y"], name="c", pads=[1, 1, 1, 1])]
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info(wide, TensorProto.FLOAT, [1, 2, 8, 8])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, None, None, None])],
                              [conv_weight()])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    for f in tmp_path.iterdir():
        f.unlink()
    assert_refused(tmp_path, model.SerializeToString(), "bad.onnx", "graph input", "1..512 bytes")


def test_the_converter_fuzzer_findings_are_one_line_refusals(tmp_path):
    # Issue 51: the first minutes of fuzz/fuzz_onnx_convert.py found five inputs that made the converter raise
    # something other than its one-line ConversionError (a Python traceback) or print a multi-line error.
    def fresh():
        for f in tmp_path.iterdir():
            f.unlink()

    # An initializer of data type 99 (no ONNX type): ValueError from protobuf's enum Name().
    m = conv_model()
    m.graph.initializer[0].data_type = 99
    assert_refused(tmp_path, m.SerializeToString(), "bad.onnx", "'w' has data type 99 (not an ONNX data type)")
    # A node name that is not valid UTF-8 (protobuf hands it over as bytes, and refused to store it again), and one
    # holding a newline (which split the error message over lines).
    fresh()
    data = conv_model().SerializeToString().replace(b"the_conv", b"the\x80conv")
    assert_refused(tmp_path, data, "bad.onnx", "the name of node 0 (Conv) is not printable UTF-8 text")
    fresh()
    data = conv_model().SerializeToString().replace(b"the_conv", b"the\nconv")
    assert_refused(tmp_path, data, "bad.onnx", "the name of node 0 (Conv) is not printable UTF-8 text")
    # A frequency-encoding pattern (Mul by s, Sin, Cos, Concat) whose scale is negative or infinite: math.log2 raised
    # ValueError / OverflowError while matching the pattern; now the pattern simply does not match.
    for scale in (-1.0, float("inf")):
        fresh()
        nodes = [helper.make_node("Mul", ["x", "s"], ["xs"], name="mul"),
                 helper.make_node("Sin", ["xs"], ["sin"], name="sin"),
                 helper.make_node("Cos", ["xs"], ["cos"], name="cos"),
                 helper.make_node("Concat", ["sin", "cos"], ["y"], name="cat", axis=1)]
        inits = [helper.make_tensor("s", TensorProto.FLOAT, [], [scale])]
        assert_refused(tmp_path, small_model(nodes, inits).SerializeToString(), "bad.onnx",
                       "supported only as part of a frequency encoding")


def test_an_imported_model_without_an_input_range_is_refused_by_the_pipeline(tmp_path, dev):
    # Issue 51: a 12-channel ONNX model through the surround pipeline had the default input range [-FLT_MAX,
    # FLT_MAX]; scaling the features into it overflowed (hi - lo = Inf), every network input was NaN, the input guard
    # zeroed them and the lightmap was scored as valid. Now the pipeline refuses such a model, naming the fix, and
    # `ngi.convert --input-range` gives it one.
    w = np.random.default_rng(3).uniform(-0.1, 0.1, (3, 12, 3, 3)).astype(np.float32)
    model = small_model([helper.make_node("Conv", ["x", "w"], ["c"], name="conv", pads=[1, 1, 1, 1]),
                         helper.make_node("Tanh", ["c"], ["y"], name="tanh")],
                        [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.tobytes(), raw=True)],
                        input_dims=(1, 12, 32, 64)).SerializeToString()
    rc, err, out = convert(tmp_path, model, "twelve")
    assert rc == 0, err
    n = 16
    rng = np.random.default_rng(4)
    frame = {"look": [0.0, 0.0, -1.0], "up": [0.0, 1.0, 0.0],
             "albedo": rng.uniform(0, 1, (6, 3, n, n)).astype(np.float32),
             "normal": np.tile(np.array([0, 1, 0], np.float32)[None, :, None, None], (6, 1, n, n)),
             "depth": rng.uniform(1, 20, (6, 1, n, n)).astype(np.float32),
             "direct": rng.uniform(0, 2, (6, 3, n, n)).astype(np.float32)}
    pipe = ngi.Pipeline(dev, n)
    with pytest.raises(ngi.InputError, match=r"input_range .* is no range the pipeline can scale its features into.*"
                                             r"--input-range=-1,1"):
        pipe.run(ngi.Model(dev, out), frame, outputs=["lightmap"])
    src = tmp_path / "twelve.onnx"
    ranged = tmp_path / "ranged.safetensors"
    proc = subprocess.run([sys.executable, "-m", "ngi.convert", str(src), str(ranged), "--input-range=-1,1"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    lightmap = pipe.run(ngi.Model(dev, ranged), frame, outputs=["lightmap"])["lightmap"]
    assert np.isfinite(lightmap).all() and lightmap.std() > 0
    for bad in ("1,-1", "0,nan", "1", "a,b"):
        proc = subprocess.run([sys.executable, "-m", "ngi.convert", str(src), str(tmp_path / "x.safetensors"),
                               f"--input-range={bad}"], capture_output=True, text=True)
        assert proc.returncode == 2 and "is not LO,HI with finite LO < HI" in proc.stderr, (bad, proc.stderr)


def test_a_model_whose_tensors_outgrow_the_host_memory_limit_is_refused(tmp_path, dev, monkeypatch):
    # Issue 51: two stride-64 ConvTranspose layers on a 4 x 4 input (a 295 KB file) make a 3 GiB output; with
    # NGI_HOST_MEMORY_LIMIT=1G the run reached 9.5 GB. Now the graph's arena on a CPU device (host memory there) and
    # the host output are judged against the limit before they are allocated. Here the same at a smaller scale: two
    # stride-16 layers, a 12 MiB output, an 8 MiB limit.
    w = np.full((3, 3, 16, 16), 0.01, np.float32)
    nodes = [helper.make_node("ConvTranspose", ["x", "w"], ["a"], name="up1", strides=[16, 16], kernel_shape=[16, 16]),
             helper.make_node("ConvTranspose", ["a", "w"], ["y"], name="up2", strides=[16, 16], kernel_shape=[16, 16])]
    data = small_model(nodes, [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.tobytes(), raw=True)],
                       input_dims=(1, 3, 4, 4)).SerializeToString()
    rc, err, out = convert(tmp_path, data, "upsample")
    assert rc == 0, err
    model = ngi.Model(dev, out)
    x = np.ones((1, 3, 4, 4), np.float32)
    monkeypatch.setenv("NGI_HOST_MEMORY_LIMIT", "8M")
    with pytest.raises(ngi.InputError, match="host-memory limit of 8388608 bytes"):
        model.run(x)
    monkeypatch.setenv("NGI_HOST_MEMORY_LIMIT", "64M")
    y = model.run(x)
    assert y.shape == (1, 3, 1024, 1024) and np.isfinite(y).all()


def test_a_relu_shared_by_two_readers_before_a_gemm_converts_to_what_the_loader_takes(tmp_path, dev):
    # Issue 51, found by the fuzz target's load check: MatMul + Add, then two Relu nodes reading that sum (so neither
    # folds into the dense layer as its output activation), one of them read by a Gemm. The converter folded that Relu
    # into the Gemm's dense node as an input_activation, a field the loader takes on convolutions only: the file
    # converted with exit 0 and `ngi.Model` refused it. Now it stays an activation node, and the model runs.
    rng = np.random.default_rng(12)
    w1, b1, w2 = (rng.normal(size=s).astype(np.float32) for s in ((6, 5), (5,), (5, 3)))
    inits = [helper.make_tensor(n, TensorProto.FLOAT, v.shape, v.tobytes(), raw=True)
             for n, v in (("w1", w1), ("b1", b1), ("w2", w2))]
    nodes = [helper.make_node("MatMul", ["x", "w1"], ["h"], name="matmul"),
             helper.make_node("Add", ["h", "b1"], ["hb"], name="bias"),
             helper.make_node("Relu", ["hb"], ["r"], name="relu"),
             helper.make_node("Relu", ["hb"], ["r2"], name="relu_again"),
             helper.make_node("Gemm", ["r", "w2"], ["g"], name="gemm"),
             helper.make_node("MatMul", ["r2", "w2"], ["g2"], name="matmul2"),
             helper.make_node("Add", ["g", "g2"], ["y"], name="sum")]
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [4, 6])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [4, 3])], inits)
    rc, err, out = convert(tmp_path, helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
                           .SerializeToString())
    assert rc == 0, err
    model = ngi.Model(dev, out)
    x = rng.normal(size=(9, 6)).astype(np.float32)
    want = 2 * np.maximum(x.astype(np.float64) @ w1 + b1, 0) @ w2
    assert float(np.max(np.abs(model.run(x) - want))) < 1e-5


def test_every_node_that_cannot_be_converted_is_named_in_one_error(tmp_path):
    # Issue 48: only the first unsupported node was reported. Now one error names each node that cannot be mapped
    # (op, name, why); nodes that read a failed node's output are not listed (they fail only because of it), and
    # nothing is written.
    nodes = [helper.make_node("LpPool", ["x"], ["p"], name="pool", kernel_shape=[2, 2], strides=[2, 2]),
             helper.make_node("Conv", ["p", "w"], ["c"], name="after_pool", pads=[1, 1, 1, 1]),
             helper.make_node("Elu", ["x"], ["s"], name="soft"),
             helper.make_node("Conv", ["x", "w"], ["g"], name="grouped", pads=[1, 1, 1, 1], group=2),
             helper.make_node("Concat", ["c", "s", "g"], ["y"], name="cat", axis=1)]
    data = small_model(nodes, [conv_weight()]).SerializeToString()
    assert_refused(tmp_path, data, "bad.onnx: 3 nodes cannot be converted:", "node 'pool' (LpPool): op LpPool is not "
                   "supported", "node 'soft' (Elu): op Elu is not supported", "node 'grouped' (Conv)",
                   "(supported ops: Conv,")
    rc, err, _ = convert(tmp_path, data, "again")
    assert "after_pool" not in err and "'cat'" not in err


def test_zero_pad_nodes_become_the_padding_of_what_reads_them(tmp_path, dev):
    # Issue 48: an explicit zero Pad (initializer pads, as exporters with constant folding write it) before a Conv
    # and before an AveragePool becomes their padding (the pool's average counts the padded zeros, as ONNX's Pad
    # then AveragePool does).
    w = np.random.default_rng(31).uniform(-1, 1, (3, 2, 3, 3)).astype(np.float32)
    pads = np.array([0, 0, 1, 1, 0, 0, 1, 1], np.int64)
    inits = [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.tobytes(), raw=True),
             helper.make_tensor("pads", TensorProto.INT64, [8], pads.tobytes(), raw=True)]
    nodes = [helper.make_node("Pad", ["x", "pads"], ["p"], name="pad"),
             helper.make_node("Conv", ["p", "w"], ["c"], name="conv"),
             helper.make_node("Pad", ["c", "pads"], ["q"], name="pad2"),
             helper.make_node("AveragePool", ["q"], ["y"], name="pool", kernel_shape=[3, 3], strides=[1, 1])]
    rc, err, out = convert(tmp_path, small_model(nodes, inits).SerializeToString())
    assert rc == 0, err
    model = ngi.Model(dev, out)
    assert [n["op"] for n in model.config["metadata"]["graph"]["nodes"]] == ["conv2d", "conv2d"]
    x = np.random.default_rng(32).uniform(-1, 1, (1, 2, 8, 8)).astype(np.float32)
    xt = torch.from_numpy(x).double()
    c = torch.nn.functional.conv2d(xt, torch.from_numpy(w).double(), padding=1)
    want = torch.nn.functional.avg_pool2d(c, 3, stride=1, padding=1, count_include_pad=True).numpy()
    assert float(np.max(np.abs(model.run(x) - want))) < 1e-5


def test_the_new_ops_fuzzer_findings_are_quick_one_line_refusals(tmp_path):
    # Issue 48/51: the fuzz target's first minutes on the new conversions (grouped, dilated, Pad, DepthToSpace,
    # Resize, AveragePool) found a MemoryError (a dilation of 2^40 expanding the kernel), a 10 s timeout (dilation
    # 65537), a ValueError (a grouped ConvTranspose's weight not fitting its input) and UnicodeDecodeErrors (a mode
    # attribute that is not UTF-8). Each is now refused at once in one line, before any large array exists.
    def fresh():
        for f in tmp_path.iterdir():
            f.unlink()

    for dil in ([1, 1 << 40], [1, 65537]):
        fresh()
        m = conv_model()
        m.graph.node[0].attribute.append(helper.make_attribute("dilations", dil))
        assert_refused(tmp_path, m.SerializeToString(), "bad.onnx", f"dilations {dil} make a 3 x 3 kernel",
                       "beyond ngi's 64")
    fresh()
    w = np.ones((4, 2, 3, 3), np.float32)  # ConvTranspose weight [cin = 4, cout / group, kh, kw] on a 2-channel input
    nodes = [helper.make_node("ConvTranspose", ["x", "w"], ["y"], name="up", group=2)]
    inits = [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.tobytes(), raw=True)]
    assert_refused(tmp_path, small_model(nodes, inits).SerializeToString(), "node 'up' (ConvTranspose): weight "
                   "[4, 2, 3, 3] with group 2 does not fit 2 input channels")
    fresh()
    scales = helper.make_tensor("s", TensorProto.FLOAT, [4], [1, 1, 2, 2])
    nodes = [helper.make_node("Resize", ["x", "", "s"], ["y"], name="resize", mode=b"\xff\xfe")]
    assert_refused(tmp_path, small_model(nodes, [scales]).SerializeToString(), "node 'resize' (Resize): mode \ufffd")
    fresh()
    scales = helper.make_tensor("s", TensorProto.FLOAT, [4], [1, 1, 65, 65])
    nodes = [helper.make_node("Resize", ["x", "", "s"], ["y"], name="resize", coordinate_transformation_mode="asymmetric",
                              nearest_mode="floor")]
    assert_refused(tmp_path, small_model(nodes, [scales]).SerializeToString(), "only one integer factor along H and W "
                   "is supported (at most 64)")
    # Found by the load check of the 1M campaign: an AveragePool on an [N, C] item list became a 2 x 2 conv2d, which
    # the loader refuses for layout "nc". Refused at conversion now.
    fresh()
    nodes = [helper.make_node("AveragePool", ["x"], ["y"], name="pool", kernel_shape=[2, 2], strides=[2, 2])]
    assert_refused(tmp_path, small_model(nodes, input_dims=(5, 2)).SerializeToString(),
                   "node 'pool' (AveragePool): a spatial op on an [N, C] item list")


def test_space_to_depth_routes_each_block_pixel_to_its_channel(tmp_path, dev):
    # ONNX SpaceToDepth (output channel (i b + j) C + c = input channel c at block offset (i, j)); torch's
    # PixelUnshuffle orders channels the other way and exports as Reshape / Transpose, which ngi does not convert.
    nodes = [helper.make_node("SpaceToDepth", ["x"], ["y"], name="s2d", blocksize=2)]
    rc, err, out = convert(tmp_path, small_model(nodes, input_dims=(1, 3, 8, 8)).SerializeToString())
    assert rc == 0, err
    x = np.random.default_rng(41).uniform(-1, 1, (1, 3, 8, 8)).astype(np.float32)
    want = x.reshape(1, 3, 4, 2, 4, 2).transpose(0, 3, 5, 1, 2, 4).reshape(1, 12, 4, 4)
    np.testing.assert_array_equal(ngi.Model(dev, out).run(x), want)


def test_review_findings_on_the_new_conversions(tmp_path, dev):
    # A review of the new conversions found: (1) an affine folded into a channel-copying kernel named its new bias
    # by cutting ".weight" off "NAME.copy", so two Resize layers followed by a Mul shared one bias; (2) AveragePool
    # ignored auto_pad; (3) a Pad folded into a pool that pads without count_include_pad changed its border average;
    # (4) a wide Clip lost precision (x - lo + lo); (5) a 100-byte file could build a 1.8 GiB kernel.
    def fresh():
        for f in tmp_path.iterdir():
            f.unlink()

    scales = helper.make_tensor("s", TensorProto.FLOAT, [4], [1, 1, 2, 2])
    c1 = helper.make_tensor("c1", TensorProto.FLOAT, [1, 2, 1, 1], [2.0, 3.0])
    c2 = helper.make_tensor("c2", TensorProto.FLOAT, [1, 2, 1, 1], [0.5, -1.0])
    up = {"coordinate_transformation_mode": "asymmetric", "nearest_mode": "floor"}
    nodes = [helper.make_node("Resize", ["x", "", "s"], ["a"], name="r1", **up),
             helper.make_node("Add", ["a", "c1"], ["b"], name="add1"),
             helper.make_node("Resize", ["b", "", "s"], ["c"], name="r2", **up),
             helper.make_node("Add", ["c", "c2"], ["y"], name="add2")]
    rc, err, out = convert(tmp_path, small_model(nodes, [scales, c1, c2], input_dims=(1, 2, 4, 4)).SerializeToString())
    assert rc == 0, err
    x = np.random.default_rng(51).uniform(-1, 1, (1, 2, 4, 4)).astype(np.float32)
    want = x.repeat(4, 2).repeat(4, 3) + np.array([2.5, 2.0], np.float32).reshape(1, 2, 1, 1)
    np.testing.assert_allclose(ngi.Model(dev, out).run(x), want, atol=1e-6)

    fresh()  # found by the million-run campaign: float pads holding NaN raised ValueError (int(nan))
    pads = helper.make_tensor("p", TensorProto.FLOAT, [8], [0, 0, float("nan"), 1, 0, 0, 1, 1])
    nodes = [helper.make_node("Pad", ["x", "p"], ["q"], name="pad"), helper.make_node("Conv", ["q", "w"], ["y"],
                                                                                       name="conv")]
    assert_refused(tmp_path, small_model(nodes, [pads, conv_weight()]).SerializeToString(),
                   "node 'pad' (Pad): pads of type float32: integers expected")
    fresh()
    nodes = [helper.make_node("AveragePool", ["x"], ["y"], name="pool", kernel_shape=[3, 3], auto_pad="SAME_UPPER")]
    assert_refused(tmp_path, small_model(nodes).SerializeToString(), "node 'pool' (AveragePool): auto_pad SAME_UPPER")
    fresh()
    pads = helper.make_tensor("p", TensorProto.INT64, [8], [0, 0, 1, 1, 0, 0, 1, 1])
    nodes = [helper.make_node("Pad", ["x", "p"], ["q"], name="pad"),
             helper.make_node("AveragePool", ["q"], ["y"], name="pool", kernel_shape=[3, 3], pads=[1, 1, 1, 1])]
    assert_refused(tmp_path, small_model(nodes, [pads]).SerializeToString(), "a Pad before a pooling that pads "
                   "without count_include_pad")
    fresh()
    lim = [helper.make_tensor("lo", TensorProto.FLOAT, [], [-65504.0]), helper.make_tensor("hi", TensorProto.FLOAT, [],
                                                                                            [65504.0])]
    nodes = [helper.make_node("Clip", ["x", "lo", "hi"], ["y"], name="clip")]
    rc, err, out = convert(tmp_path, small_model(nodes, lim).SerializeToString())
    assert rc == 0, err
    x = np.random.default_rng(52).uniform(-1, 1, (1, 2, 8, 8)).astype(np.float32)
    x[0, 0, 0, :3] = [1e5, -1e5, 65504.0]
    want = np.clip(x, -65504.0, 65504.0)
    np.testing.assert_array_equal(ngi.Model(dev, out).run(x), want)  # exact inside the range and at the bounds
    fresh()
    nodes = [helper.make_node("AveragePool", ["x"], ["y"], name="pool", kernel_shape=[3, 3])]
    assert_refused(tmp_path, small_model(nodes, input_dims=(1, 5000, 8, 8)).SerializeToString(),
                   "node 'pool' (AveragePool): it would make a kernel of 225000000 values")


def test_truncated_file_is_refused(tmp_path):
    data = conv_model().SerializeToString()
    assert_refused(tmp_path, data[:len(data) // 2], "bad.onnx", "truncated")


def test_cyclic_graph_is_refused(tmp_path):
    nodes = [helper.make_node("Add", ["x", "b"], ["a"], name="add_node"),
             helper.make_node("Relu", ["a"], ["b"], name="relu_node"),
             helper.make_node("Relu", ["a"], ["y"], name="out_node")]
    assert_refused(tmp_path, small_model(nodes).SerializeToString(), "cycle", "add_node", "relu_node")


def test_unsupported_op_is_refused(tmp_path):
    nodes = [helper.make_node("Softmax", ["x"], ["y"], name="the_softmax", axis=1)]
    assert_refused(tmp_path, small_model(nodes).SerializeToString(), "node 'the_softmax' (Softmax)", "not supported")


def test_unsupported_opsets_are_refused(tmp_path):
    assert_refused(tmp_path, conv_model(opset=7).SerializeToString(), "opset 7 is not supported")
    (tmp_path / "bad.onnx").unlink()
    m = conv_model()
    m.opset_import.append(helper.make_opsetid("com.microsoft", 1))
    assert_refused(tmp_path, m.SerializeToString(), "domain 'com.microsoft'")


def test_symbolic_and_negative_shapes_are_refused(tmp_path):
    assert_refused(tmp_path, conv_model(input_dims=(1, 2, "H", 8)).SerializeToString(), "symbolic", "'H'")
    (tmp_path / "bad.onnx").unlink()
    assert_refused(tmp_path, conv_model(input_dims=(1, 2, -8, 8)).SerializeToString(), "dimension 2 is -8")


def test_initializer_of_the_wrong_size_is_refused(tmp_path):
    short = np.ones(3 * 2 * 3 * 3 - 1, np.float32).tobytes()
    assert_refused(tmp_path, conv_model(raw_bytes=short).SerializeToString(), "bad.onnx: initializer 'w'", "212 bytes", "216")


def test_unsupported_attribute_names_the_node(tmp_path):
    nodes = [helper.make_node("Conv", ["x", "w"], ["y"], name="grouped", group=2)]
    assert_refused(tmp_path, small_model(nodes, [conv_weight()]).SerializeToString(), "node 'grouped' (Conv)",
                   "group 2")


# --------------------------------------------------------------------------
# The C++ loader of family "graph" against hand-made hostile node lists
# --------------------------------------------------------------------------

def graph_file(tmp_path, nodes, tensors, output="y", input_nc=2):
    config = {"format_version": 1, "family": "graph", "input_nc": input_nc,
              "graph": {"layout": "nchw", "input": "x", "output": output, "nodes": nodes}}
    path = tmp_path / "g.safetensors"
    write_model(path, tensors, config)
    return path


CONV = {"name": "c", "op": "conv2d", "inputs": ["x"], "output": "y", "in": 2, "out": 3, "kernel": [3, 3],
        "stride": 1, "pad": 1, "weight": "c.weight"}
WEIGHT = {"c.weight": np.ones((3, 2, 3, 3), np.float32)}


@pytest.mark.parametrize("nodes,tensors,needle", [
    ([dict(CONV, op="softmax")], WEIGHT, "node 'c' (softmax): op 'softmax' is not one of"),
    ([dict(CONV, inputs=["nowhere"])], WEIGHT, "node 'c' (conv2d): input 'nowhere' is neither the graph input"),
    ([dict(CONV, inputs=["y"])], WEIGHT, "node 'c' (conv2d): input 'y' is neither"),  # reads its own output: a cycle
    ([dict(CONV, **{"in": 5})], WEIGHT, "node 'c' (conv2d): 'in' is 5, its input has 2 channels"),
    ([dict(CONV, weight="missing")], WEIGHT, "node 'c' (conv2d): tensor 'missing' (weight) is not in the file"),
    ([CONV], {"c.weight": np.ones((3, 2, 5, 5), np.float32)}, "tensor 'c.weight' (weight) is [3, 2, 5, 5], expected [3, 2, 3, 3]"),
    ([CONV], dict(WEIGHT, extra=np.ones(1, np.float32)), "tensor 'extra' is not used by any node"),
    ([dict(CONV, activation="gelu")], WEIGHT, "node 'c' (conv2d): 'activation' must be one of"),
    ([dict(CONV, dilation=2)], WEIGHT, "node 'c' (conv2d): unknown field 'dilation'"),
    ([CONV, dict(CONV, name="c")], WEIGHT, "node 'c': a second node of this name"),
    ([CONV, dict(CONV, name="d")], WEIGHT, "node 'd' (conv2d): output 'y' is made a second time"),
    ([dict(CONV, stride=0)], WEIGHT, "node 'c' (conv2d): 'stride' must be an integer in 1..64"),
    # Issue 48's new nodes.
    ([{"name": "p", "op": "max_pool2d", "inputs": ["x"], "output": "y", "kernel": [2, 2], "stride": [2, 2],
       "pads": [2, 0, 0, 0]}], {}, "node 'p' (max_pool2d): 'pads' must be [top, left, bottom, right]"),
    ([{"name": "p", "op": "max_pool2d", "inputs": ["x"], "output": "y", "kernel": [2, 65], "stride": [2, 2],
       "pads": [0, 0, 0, 0]}], {}, "node 'p' (max_pool2d): 'kernel' must be [h, w], integers in 1..64"),
    ([{"name": "p", "op": "max_pool2d", "inputs": ["x"], "output": "y", "kernel": [2, 2], "stride": 2,
       "pads": [0, 0, 0, 0]}], {}, "node 'p' (max_pool2d): 'stride' must be [h, w]"),
    ([{"name": "g", "op": "global_avg_pool", "inputs": ["x"], "output": "y", "kernel": [2, 2]}], {},
     "node 'g' (global_avg_pool): unknown field 'kernel'"),
    ([{"name": "n", "op": "instance_norm", "inputs": ["x"], "output": "y", "scale": "s", "shift": "b", "eps": 0}],
     {"s": np.ones(2, np.float32), "b": np.zeros(2, np.float32)}, "node 'n' (instance_norm): 'eps' must be a number"),
    ([{"name": "n", "op": "instance_norm", "inputs": ["x"], "output": "y", "scale": "s", "eps": 1e-5}],
     {"s": np.ones(2, np.float32)}, "node 'n' (instance_norm): 'shift' (a tensor name) is missing"),
    ([{"name": "n", "op": "instance_norm", "inputs": ["x"], "output": "y", "scale": "s", "shift": "b", "eps": 1e-5}],
     {"s": np.ones(3, np.float32), "b": np.zeros(2, np.float32)}, "tensor 's' (scale) is [3], expected [2]"),
    ([{"name": "m", "op": "mul", "inputs": ["x", "x"], "output": "y", "broadcast": 1}], {},
     "node 'm' (mul): 'broadcast' must be true or false"),
    ([{"name": "p", "op": "pad2d", "inputs": ["x"], "output": "y", "pads": [1, 1, 1, 1], "mode": "wrap"}], {},
     "node 'p' (pad2d): 'mode' must be"),
    ([{"name": "p", "op": "pad2d", "inputs": ["x"], "output": "y", "pads": [1, 1, 65, 1], "mode": "edge"}], {},
     "node 'p' (pad2d): 'pads' must be [top, left, bottom, right], integers in -64..64"),
    ([{"name": "r", "op": "resize_bilinear", "inputs": ["x"], "output": "y", "scales": [2, 100],
       "coordinate": "half_pixel"}], {}, "node 'r' (resize_bilinear): 'scales' must be [h, w], numbers in [1/64, 64]"),
    ([{"name": "r", "op": "resize_bilinear", "inputs": ["x"], "output": "y", "scales": [2, 2],
       "coordinate": "tf_crop_and_resize"}], {}, "node 'r' (resize_bilinear): 'coordinate' must be"),
    ([{"name": "r", "op": "resize_bilinear", "inputs": ["x"], "output": "y", "scales": [2, 2], "sizes": [4, 4],
       "coordinate": "half_pixel"}], {}, "node 'r' (resize_bilinear): exactly one of 'scales'"),
    ([{"name": "r", "op": "resize_bilinear", "inputs": ["x"], "output": "y", "sizes": [0, 4],
       "coordinate": "half_pixel"}], {}, "node 'r' (resize_bilinear): 'sizes' must be [h, w], integers in 1..65536"),
    ([{"name": "g", "op": "group_norm", "inputs": ["x"], "output": "y", "groups": 3, "scale": "s", "shift": "b",
       "eps": 1e-5}], {"s": np.ones(3, np.float32), "b": np.zeros(3, np.float32)},
     "node 'g' (group_norm): 'groups' (3) must divide the input's 2 channels"),
])
def test_graph_loader_refuses_hostile_node_lists(dev, tmp_path, nodes, tensors, needle):
    path = graph_file(tmp_path, nodes, tensors)
    with pytest.raises(ngi.InputError, match=None) as info:
        ngi.Model(dev, path)
    assert needle in str(info.value)


def test_broadcast_needs_one_value_a_channel_when_the_graph_is_built(dev, tmp_path):
    # A 'broadcast' mul whose second input is not C x 1 x 1 is refused when the graph is built for a size, naming it.
    nodes = [{"name": "m", "op": "mul", "inputs": ["x", "x"], "output": "y", "broadcast": True}]
    model = ngi.Model(dev, graph_file(tmp_path, nodes, {}))
    with pytest.raises(ngi.InputError, match=r"the second must be 2x1x1"):
        model.run(np.ones((1, 2, 4, 4), np.float32))


def test_channel_counts_beyond_the_loader_are_refused_before_anything_is_built(tmp_path):
    # Found by the fuzzer (2026-12-07): an input of 2^31 - 1 channels multiplied by a constant built the per-channel
    # constant in float64 first (16 GiB, minutes) and was refused by the loader's limits only at the end. Now the
    # input, and any node making more channels than the loader takes (a concat), is refused at once.
    import time
    scale = numpy_helper.from_array(np.array(2.0, np.float32), "s")
    start = time.monotonic()
    data = small_model([helper.make_node("Mul", ["x", "s"], ["y"], name="m")], [scale],
                       input_dims=(1, 2**31 - 1, 8, 8)).SerializeToString()
    assert_refused(tmp_path, data, "input 'x' has 2147483647 channels; ngi loads at most 65536")
    data = small_model([helper.make_node("Concat", ["x", "x", "x"], ["y"], name="cat", axis=1)],
                       input_dims=(1, 40000, 1, 1)).SerializeToString()
    assert_refused(tmp_path, data, "node 'cat' (Concat): makes 120000 channels; ngi loads at most 65536")
    assert time.monotonic() - start < 30


def test_new_pooling_and_normalization_refusals_name_the_node(tmp_path):
    # MaxPool forms ngi does not run, a ReduceMean over other axes and an InstanceNormalization with computed
    # parameters: one-line refusals, nothing written.
    w = conv_weight()
    cases = [
        (helper.make_node("MaxPool", ["x"], ["y"], name="p", kernel_shape=[2, 2], ceil_mode=1), "ceil_mode 0"),
        (helper.make_node("MaxPool", ["x"], ["y"], name="p", kernel_shape=[2, 2], pads=[2, 0, 0, 0]),
         "each pad must be below its kernel side"),
        (helper.make_node("MaxPool", ["x"], ["y"], name="p", kernel_shape=[2, 2], dilations=[2, 2]), "dilations 1"),
        (helper.make_node("ReduceMean", ["x"], ["y"], name="p", axes=[1]), "only the mean over H and W"),
        (helper.make_node("ReduceMean", ["x"], ["y"], name="p", axes=[-1, -3]), "only the mean over H and W"),
        (helper.make_node("InstanceNormalization", ["x", "x", "x"], ["y"], name="p"), "scale and bias must be constants"),
        (helper.make_node("Pad", ["x", "pads"], ["y"], name="p", mode="wrap"), "mode wrap"),
        (helper.make_node("Resize", ["x", "", "scales"], ["y"], name="p", mode="cubic"), "mode cubic"),
        (helper.make_node("Resize", ["x", "", "scales"], ["y"], name="p", mode="linear", exclude_outside=1),
         "exclude_outside"),
        (helper.make_node("Resize", ["x", "", "scales"], ["y"], name="p", mode="linear",
                          coordinate_transformation_mode="tf_crop_and_resize"), "coordinate_transformation_mode"),
        (helper.make_node("Resize", ["x", "", "big"], ["y"], name="p", mode="linear"), "scales of H and W in"),
        # Shape arithmetic that would build a huge constant is not folded: its reader is refused.
        (helper.make_node("Pad", ["x", "huge"], ["y"], name="bomb", mode="reflect"),
         "node 'bomb' (ConstantOfShape): ConstantOfShape is supported only as shape arithmetic between constants"),
    ]
    extra = [numpy_helper.from_array(np.array([0, 0, 1, 1, 0, 0, 1, 1], np.int64), "pads"),
             numpy_helper.from_array(np.array([1, 1, 2, 2], np.float32), "scales"),
             numpy_helper.from_array(np.array([1, 1, 2, 100], np.float32), "big")]
    huge = [numpy_helper.from_array(np.array([1 << 20, 1 << 20], np.int64), "shape"),
            helper.make_node("ConstantOfShape", ["shape"], ["huge"], name="bomb")]
    for k, (node, needle) in enumerate(cases):
        nodes = [huge[1], node] if "huge" in node.input else [node]
        data = small_model(nodes, [w, *extra, huge[0]]).SerializeToString()
        assert_refused(tmp_path, data, f"node 'p' ({node.op_type})" if node.name == "p" else "", needle)


def test_graph_loader_refuses_an_output_no_node_makes(dev, tmp_path):
    with pytest.raises(ngi.InputError, match="field 'graph.output' must be the output of a node; no node makes 'z'"):
        ngi.Model(dev, graph_file(tmp_path, [CONV], WEIGHT, output="z"))


def test_graph_copies_where_a_tensor_is_read_twice(dev, tmp_path):
    # y = relu(x) in place would change what the concat reads of x; x cannot live inside the concat either (it is
    # the graph input): the builder copies. out = [x, relu(x), x + x].
    nodes = [{"name": "r", "op": "activation", "inputs": ["x"], "output": "rx", "activation": "relu"},
             {"name": "s", "op": "add", "inputs": ["x", "x"], "output": "xx"},
             {"name": "cat", "op": "concat", "inputs": ["x", "rx", "xx"], "output": "y"}]
    model = ngi.Model(dev, graph_file(tmp_path, nodes, {}))
    x = np.random.default_rng(8).uniform(-1, 1, (1, 2, 4, 4)).astype(np.float32)
    y = model.run(x)
    np.testing.assert_array_equal(y, np.concatenate([x, np.maximum(x, 0), x + x], axis=1))


def test_graph_copies_a_concat_before_changing_it_in_place(dev, tmp_path):
    # relu in place on a concat would also change its member t, which the add reads afterwards.
    # t = 0.5 x (an affine: memory of its own, so the concat places t inside itself).
    nodes = [{"name": "t", "op": "affine", "inputs": ["x"], "output": "t", "scale": "half"},
             {"name": "cat", "op": "concat", "inputs": ["t", "t"], "output": "c"},
             {"name": "r", "op": "activation", "inputs": ["c"], "output": "rc", "activation": "relu"},
             {"name": "s", "op": "add", "inputs": ["t", "t"], "output": "tt"},
             {"name": "out", "op": "concat", "inputs": ["rc", "tt"], "output": "y"}]
    model = ngi.Model(dev, graph_file(tmp_path, nodes, {"half": np.full(2, 0.5, np.float32)}))
    x = np.random.default_rng(11).uniform(-1, 1, (1, 2, 4, 4)).astype(np.float32)
    y = model.run(x)
    t = 0.5 * x.astype(np.float64)
    np.testing.assert_allclose(y, np.concatenate([np.maximum(t, 0), np.maximum(t, 0), 2 * t], axis=1), atol=1e-6)


class _SqueezeReLU6Odd(torch.nn.Module):
    """Review findings: a squeeze-excitation gate through ReLU6 (Clip(0, 6): several nodes) multiplied in, and a
    bilinear resize by 0.7 (10 pixels -> 7, where the float32 scale times 10 is 6.99999988)."""

    def __init__(self):
        super().__init__()
        self.conv = torch.nn.Conv2d(3, 4, 3, padding=1)
        self.fc = torch.nn.Conv2d(4, 4, 1)

    def forward(self, x):
        y = self.conv(x)
        s = torch.nn.functional.relu6(self.fc(torch.nn.functional.adaptive_avg_pool2d(y, 1)) * 4.0 + 3.0)
        return torch.nn.functional.interpolate(y * s, scale_factor=0.7, mode="bilinear")


@pytest.mark.parametrize("opset", [13, 17])
def test_review_findings_of_the_new_ops_convert_and_match(dev, tmp_path, opset):
    torch.manual_seed(5)
    net = _SqueezeReLU6Odd().eval()
    rc, err, out = convert(tmp_path, export_at(net, torch.randn(1, 3, 10, 10), opset), "odd")
    assert rc == 0, err
    x = np.random.default_rng(6).uniform(-1, 1, (1, 3, 10, 10)).astype(np.float32)
    want = reference(net, x)
    got = ngi.Model(dev, out).run(x)
    assert got.shape == want.shape == (1, 4, 7, 7)
    assert float(np.max(np.abs(got - want)) / np.max(np.abs(want))) < 1e-5


def test_review_findings_of_the_new_ops_are_refused_or_mapped(tmp_path, dev):
    import time
    w = conv_weight()
    # A linear Resize at opset 10 has no coordinate modes: it is asymmetric (it was mapped as half-pixel).
    scales = numpy_helper.from_array(np.array([1, 1, 2, 2], np.float32), "scales")
    data = small_model([helper.make_node("Resize", ["x", "scales"], ["y"], name="r", mode="linear")], [scales],
                       opset=10).SerializeToString()
    rc, err, out = convert(tmp_path, data, "r10")
    assert rc == 0, err
    from ngi.model_file import read_config
    assert [n["coordinate"] for n in read_config(str(out))["graph"]["nodes"]] == ["asymmetric"]
    # Shape arithmetic whose every node reads its predecessor twice: refused at once, not in exponential time.
    base = numpy_helper.from_array(np.array([0, 2, -1], np.int64), "base")
    nodes = [helper.make_node("Shape", ["x"], ["c0"], name="shape")]
    for i in range(40):
        nodes.append(helper.make_node("Concat", [f"c{i}", f"c{i}"], [f"c{i + 1}"], name=f"cat{i}", axis=0))
    nodes += [helper.make_node("Reshape", ["x", "c40"], ["r"], name="reshape"),
              helper.make_node("InstanceNormalization", ["r", "s", "b"], ["y"], name="norm")]
    s, b = (numpy_helper.from_array(np.ones(2, np.float32), n) for n in ("s", "b"))
    start = time.monotonic()
    rc, err, _ = convert(tmp_path, small_model(nodes, [base, s, b]).SerializeToString(), "doubling")
    assert rc == 1 and time.monotonic() - start < 30, err
    # 5,000 Identity nodes in a row before a shape input: a one-line refusal, not a RecursionError.
    nodes = [helper.make_node("Identity", ["base" if i == 0 else f"i{i - 1}"], [f"i{i}"], name=f"id{i}")
             for i in range(5000)]
    nodes.append(helper.make_node("Pad", ["x", "i4999"], ["y"], name="pad", mode="reflect"))
    rc, err, _ = convert(tmp_path, small_model(nodes, [base]).SerializeToString(), "deep")
    assert rc == 1 and "RecursionError" not in err and len(err.strip().splitlines()) == 1, err
    # The converter's own tensors never take a name the file uses: a Relu output named 'p/positive' beside a
    # per-channel PRelu whose output is 'p'.
    slope = numpy_helper.from_array(np.array([0.1, -0.2], np.float32).reshape(2, 1, 1), "slope")
    nodes = [helper.make_node("Relu", ["x"], ["p/positive"], name="relu"),
             helper.make_node("PRelu", ["x", "slope"], ["p"], name="prelu"),
             helper.make_node("Add", ["p", "p/positive"], ["y"], name="add")]
    rc, err, out = convert(tmp_path, small_model(nodes, [slope]).SerializeToString(), "names")
    assert rc == 0, err
    xs = np.random.default_rng(3).normal(size=(1, 2, 8, 8)).astype(np.float32)
    a = np.array([0.1, -0.2]).reshape(1, 2, 1, 1)
    want = np.where(xs > 0, xs, a * xs) + np.maximum(xs, 0)
    assert float(np.max(np.abs(ngi.Model(dev, out).run(xs) - want))) < 1e-6
    # A Shape node outside GroupNorm's pattern names what it is for.
    data = small_model([helper.make_node("Shape", ["x"], ["y"], name="p")]).SerializeToString()
    (tmp_path / "shape").mkdir()
    assert_refused(tmp_path / "shape", data, "node 'p' (Shape): supported only as part of GroupNorm")


def test_shape_constants_that_are_not_whole_numbers_are_refused(tmp_path):
    # Found by the CI's fuzz stage (stop 60): GroupNorm's Reshape read a float shape holding NaN with int(), a
    # ValueError instead of a refusal. Shape-like constants that are not finite whole numbers now fail the pattern, and
    # the node is refused in one line; the same for a Resize whose sizes are floats.
    s, b = (numpy_helper.from_array(np.ones(2, np.float32), n) for n in ("s", "b"))
    for k, bad in enumerate(([0, 2, float("nan")], [0, 2.5, -1])):
        shape = numpy_helper.from_array(np.array(bad, np.float32), "shape")
        nodes = [helper.make_node("Reshape", ["x", "shape"], ["r"], name="reshape"),
                 helper.make_node("InstanceNormalization", ["r", "s", "b"], ["n"], name="norm"),
                 helper.make_node("Shape", ["x"], ["xs"], name="xshape"),
                 helper.make_node("Reshape", ["n", "xs"], ["y"], name="back")]
        (tmp_path / f"gn{k}").mkdir()
        assert_refused(tmp_path / f"gn{k}", small_model(nodes, [shape, s, b]).SerializeToString(), "ngi.convert: error:")
    sizes = numpy_helper.from_array(np.array([1, 2, float("nan"), 16], np.float32), "sizes")
    nodes = [helper.make_node("Resize", ["x", "", "", "sizes"], ["y"], name="resize", mode="nearest")]
    (tmp_path / "resize").mkdir()
    assert_refused(tmp_path / "resize", small_model(nodes, [sizes]).SerializeToString(), "node 'resize' (Resize)")

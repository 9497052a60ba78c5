#!/usr/bin/env python3
"""Writes the seed corpus of the ONNX converter's fuzzer (fuzz/corpus/onnx_convert/*.onnx): small models that reach
every mapping of ngi.onnx_import -- convolutions with batch norm and each activation, a strided encoder-decoder with
a skip concatenation, an item-list MLP of MatMul/Gemm, per-channel and scalar arithmetic, a Constant node, Clip then
Exp, Dropout/Identity, two computed tensors added and multiplied, a zero Pad before a Conv and an AveragePool -- and,
when PyTorch is installed, a block of depthwise / dilated / grouped convolutions, PixelShuffle, average pooling and
nearest upsampling, and three of ngi's
networks as torch.onnx.export writes them (the pix2pix U-Net, seed 001's AO MLP, seed 002's Neural GI with its
frequency encoding and nan_to_num pattern). Run from the repo root:

    PYTHONPATH=build/python /usr/bin/python3 fuzz/make_onnx_seeds.py
"""
import io
import os
import warnings

import numpy as np
from onnx import TensorProto, helper, numpy_helper

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "onnx_convert")
rng = np.random.default_rng(51)


def init(name, shape, lo=-0.5, hi=0.5):
    return numpy_helper.from_array(rng.uniform(lo, hi, shape).astype(np.float32), name)


def model(nodes, inits, input_dims, opset=13):
    graph = helper.make_graph(nodes, "seed", [helper.make_tensor_value_info("x", TensorProto.FLOAT, list(input_dims))],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [None] * len(input_dims))], inits)
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)], producer_name="make_onnx_seeds")


def conv_bn_relu_tanh():
    n = [helper.make_node("Conv", ["x", "w1", "b1"], ["c1"], pads=[1, 1, 1, 1], kernel_shape=[3, 3]),
         helper.make_node("BatchNormalization", ["c1", "s", "t", "m", "v"], ["bn"], epsilon=1e-5),
         helper.make_node("Relu", ["bn"], ["r"]),
         helper.make_node("Conv", ["r", "w2"], ["c2"]),
         helper.make_node("Tanh", ["c2"], ["y"])]
    i = [init("w1", (8, 3, 3, 3)), init("b1", (8,)), init("s", (8,), 0.5, 1.5), init("t", (8,)),
         init("m", (8,)), init("v", (8,), 0.5, 2.0), init("w2", (3, 8, 1, 1))]
    return model(n, i, (1, 3, 16, 16))


def encoder_decoder():
    n = [helper.make_node("Conv", ["x", "we"], ["e"], strides=[2, 2], pads=[1, 1, 1, 1]),
         helper.make_node("LeakyRelu", ["e"], ["le"], alpha=0.2),
         helper.make_node("ConvTranspose", ["le", "wd", "bd"], ["d"], strides=[2, 2], pads=[1, 1, 1, 1]),
         helper.make_node("Relu", ["d"], ["rd"]),
         helper.make_node("Concat", ["rd", "x"], ["cat"], axis=1),
         helper.make_node("Conv", ["cat", "wo"], ["o"], pads=[1, 1, 1, 1]),
         helper.make_node("Sigmoid", ["o"], ["y"])]
    i = [init("we", (8, 4, 4, 4)), init("wd", (8, 4, 4, 4)), init("bd", (4,)), init("wo", (3, 8, 3, 3))]
    return model(n, i, (1, 4, 16, 16), opset=17)


def item_mlp():
    n = [helper.make_node("MatMul", ["x", "w1"], ["h"]),
         helper.make_node("Add", ["h", "b1"], ["hb"]),
         helper.make_node("Relu", ["hb"], ["r"]),
         helper.make_node("Gemm", ["r", "w2", "b2"], ["g"], transB=1),
         helper.make_node("Clip", ["g", "", "cmax"], ["c"]),
         helper.make_node("Exp", ["c"], ["y"])]
    i = [init("w1", (6, 16)), init("b1", (16,)), init("w2", (3, 16)), init("b2", (3,)),
         numpy_helper.from_array(np.array(88.0, np.float32), "cmax")]
    return model(n, i, (64, 6))


def arithmetic():
    n = [helper.make_node("Constant", [], ["k"], value=numpy_helper.from_array(
             np.array([0.5, 2.0], np.float32).reshape(1, 2, 1, 1))),
         helper.make_node("Mul", ["x", "k"], ["a"]),
         helper.make_node("Add", ["a", "one"], ["b"]),
         helper.make_node("Sub", ["b", "ch"], ["c"]),
         helper.make_node("Div", ["c", "two"], ["d"]),
         helper.make_node("Clip", ["d", "zero"], ["e"]),
         helper.make_node("Dropout", ["e"], ["f"]),
         helper.make_node("Identity", ["f"], ["g"]),
         helper.make_node("Conv", ["g", "w1"], ["p"], pads=[1, 1, 1, 1]),
         helper.make_node("Conv", ["g", "w2"], ["q"]),
         helper.make_node("Add", ["p", "q"], ["s"]),
         helper.make_node("Mul", ["s", "q"], ["y"])]
    i = [numpy_helper.from_array(np.array(1.0, np.float32), "one"), init("ch", (1, 2, 1, 1)),
         numpy_helper.from_array(np.array(2.0, np.float32), "two"),
         numpy_helper.from_array(np.array(0.0, np.float32), "zero"), init("w1", (3, 2, 3, 3)), init("w2", (3, 2, 1, 1))]
    return model(n, i, (1, 2, 8, 8), opset=9 + 4)


def torch_seeds():
    """ngi's own networks as torch.onnx.export writes them (skipped without PyTorch)."""
    try:
        import torch  # noqa: PLC0415 (optional: the hand-made seeds need only onnx)
    except ImportError:
        print("make_onnx_seeds: no PyTorch, only the hand-made seeds")
        return {}
    from ngi import neural_gi  # noqa: PLC0415
    from ngi.reference_models import ao_mlp, build_generator  # noqa: PLC0415

    def export(module, example, opset):
        f = io.BytesIO()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            torch.onnx.export(module.eval(), example, f, opset_version=opset)
        return f.getvalue()

    class Blocks(torch.nn.Module):
        """Depthwise, dilated and grouped convolutions, PixelShuffle, average pooling, nearest upsampling."""

        def __init__(self):
            super().__init__()
            self.dw = torch.nn.Conv2d(4, 4, 3, padding=1, groups=4)
            self.dil = torch.nn.Conv2d(4, 8, 3, padding=2, dilation=2)
            self.pool = torch.nn.AvgPool2d(2)
            self.shuffle = torch.nn.PixelShuffle(2)
            self.up = torch.nn.ConvTranspose2d(2, 4, 4, stride=2, padding=1, groups=2)

        def forward(self, x):
            y = self.dil(torch.relu(self.dw(x)))
            z = self.shuffle(self.pool(y))                       # 8 -> 2 channels at the input's size
            u = torch.nn.functional.interpolate(self.pool(z), scale_factor=2, mode="nearest")
            return torch.cat([self.up(torch.nn.functional.avg_pool2d(u, 2)), x], 1)

    class PoolNormBlocks(torch.nn.Module):
        """Max pooling (padded), squeeze-excitation (global average pool, broadcast multiply), ReduceMean, instance
        and group normalization, GELU (Erf), Softplus, a reflect Pad (shape arithmetic for its pads) and bilinear
        resizing."""

        def __init__(self):
            super().__init__()
            self.conv = torch.nn.Conv2d(4, 8, 3, padding=1)
            self.norm = torch.nn.InstanceNorm2d(8, affine=True)
            self.group = torch.nn.GroupNorm(2, 8)
            self.fc1 = torch.nn.Conv2d(8, 2, 1)
            self.fc2 = torch.nn.Conv2d(2, 8, 1)

        def forward(self, x):
            y = torch.nn.functional.gelu(self.norm(self.conv(torch.nn.functional.max_pool2d(x, 3, 1, 1))))
            s = torch.sigmoid(self.fc2(torch.relu(self.fc1(torch.nn.functional.adaptive_avg_pool2d(y, 1)))))
            y = self.group(torch.nn.functional.pad(y * s + y.mean((2, 3), keepdim=True), (1, 1, 1, 1), mode="reflect"))
            return torch.nn.functional.interpolate(torch.nn.functional.softplus(y), scale_factor=2, mode="bilinear")

    torch.manual_seed(51)
    return {
        "blocks_op13": export(Blocks(), torch.randn(1, 4, 16, 16), 13),
        "pool_norm_blocks_op17": export(PoolNormBlocks(), torch.randn(1, 4, 16, 16), 17),
        "pix2pix_ngf2_5levels_op13": export(build_generator("pix2pix_unet", 3, 3, 2, 5), torch.randn(1, 3, 32, 32), 13),
        "ao_mlp_op17": export(ao_mlp(8, 4), torch.randn(3, 48), 17),
        "neural_gi_small_op13": export(neural_gi.NeuralGI(buffer_channels=2, ngf=2, num_downs=5, mlp_width=8,
                                                          mlp_depth=2, skip_layer=1), torch.randn(1, 18, 32, 32), 13),
    }


def padded():
    pads = numpy_helper.from_array(np.array([0, 0, 1, 1, 0, 0, 1, 1], np.int64), "pads")
    n = [helper.make_node("Pad", ["x", "pads"], ["p"]),
         helper.make_node("Conv", ["p", "w"], ["c"]),
         helper.make_node("Pad", ["c", "pads"], ["q"]),
         helper.make_node("AveragePool", ["q"], ["y"], kernel_shape=[3, 3])]
    return model(n, [init("w", (3, 2, 3, 3)), pads], (1, 2, 8, 8))


def main():
    os.makedirs(OUT, exist_ok=True)
    seeds = {"conv_bn_relu_tanh": conv_bn_relu_tanh().SerializeToString(),
             "encoder_decoder_op17": encoder_decoder().SerializeToString(),
             "item_mlp": item_mlp().SerializeToString(),
             "arithmetic_constant": arithmetic().SerializeToString(),
             "pad_conv_pool": padded().SerializeToString()}
    seeds.update(torch_seeds())
    for name, data in seeds.items():
        with open(os.path.join(OUT, name + ".onnx"), "wb") as f:
            f.write(data)
        print(f"{name}.onnx: {len(data)} bytes")


if __name__ == "__main__":
    main()

"""The networks seed 002's trainer trains: the Neural GI network with its scene box (ngi.neural_gi.NeuralGI, the
reference ngi is tested against) and the two baselines of the paper, each with its exactly equivalent NeuralGI
(ngi runs only the neural_gi family, so a baseline is exported as a NeuralGI that computes the same function).

--no-buffer: the MLP on [I, Gamma(I)] without the CNN neural buffer (Table 4's "MLP only"); as a NeuralGI, a
1-channel U-Net (ngf 8, num_downs 5) whose channel the MLP gives zero weight.
--unet-only: the paper's "[72]-net", ngi's pix2pix U-Net alone (linear, 3 channels, exp decoding); as a NeuralGI,
the U-Net as the buffer (C_B 3) and an MLP of 6 ReLU units that passes it through.
"""

import torch
import torch.nn as nn

import ngi.neural_gi as ng


class SceneNeuralGI(ng.NeuralGI):
    """NeuralGI whose config() also carries the scene box and the sky convention (export_model stores config()
    under the file's "training" object)."""

    scene = None

    def config(self):
        c = super().config()
        if self.scene is not None:
            c.update(self.scene)
        return c


class IndirectFromRaw(nn.Module):
    """A baseline's forward and render as NeuralGI's: indirect = exp decoding of raw_output; final = direct + it."""

    def forward(self, inputs):
        return ng.decode_indirect(self.raw_output(inputs))

    def render(self, inputs, direct):
        indirect = self(inputs)
        return ng.sanitize_radiance(direct) + indirect, indirect


class NoBufferGI(IndirectFromRaw):
    """The baseline without the neural buffer: R on [I, Gamma(I)] (378 channels), exp decoding."""

    def __init__(self, mlp_width=ng.DEFAULT_MLP_WIDTH, mlp_depth=ng.DEFAULT_MLP_DEPTH,
                 skip_layer=ng.DEFAULT_SKIP_LAYER):
        super().__init__()
        self.mlp = ng.RenderingMLP(ng.ENCODED_CHANNELS, mlp_width, mlp_depth, skip_layer)

    def check_inputs(self, inputs):
        if inputs.dim() != 4 or inputs.shape[1] != ng.INPUT_CHANNELS:
            raise ValueError(f"inputs must be [N, {ng.INPUT_CHANNELS}, H, W], got {tuple(inputs.shape)}")

    def raw_output(self, inputs):
        self.check_inputs(inputs)
        return self.mlp(ng.positional_encoding(inputs))


def no_buffer_as_neural_gi(net, seed=0):
    """An exactly equivalent SceneNeuralGI: a 1-channel U-Net (ngf 8, num_downs 5) whose output the MLP weighs
    by 0 (first layer and the re-injection layer), every MLP weight copied."""
    torch.manual_seed(seed)
    m = net.mlp
    full = SceneNeuralGI(buffer_channels=1, ngf=8, num_downs=5, mlp_width=m.output.in_channels,
                         mlp_depth=len(m.layers), skip_layer=m.skip_layer)
    e = ng.ENCODED_CHANNELS
    with torch.no_grad():
        for i, (src, dst) in enumerate(zip(m.layers, full.mlp.layers)):
            dst.bias.copy_(src.bias)
            if i == 0:
                dst.weight.zero_()
                dst.weight[:, :e] = src.weight
            elif i == m.skip_layer:  # input [h, z] with z = [Gamma, B]
                w = src.weight.shape[1] - e
                dst.weight.zero_()
                dst.weight[:, :w + e] = src.weight
            else:
                dst.weight.copy_(src.weight)
        full.mlp.output.load_state_dict(m.output.state_dict())
    return full


class UnetOnlyGI(IndirectFromRaw):
    """The paper's "[72]-net" baseline: ngi's pix2pix U-Net alone (linear output, 3 channels) on the same 18 inputs,
    no encoding, no MLP; exp decoding as NeuralGI's, so the loss, data and schedule are the same."""

    def __init__(self, ngf=ng.DEFAULT_NGF, num_downs=ng.DEFAULT_NUM_DOWNS):
        super().__init__()
        if num_downs < 5:
            raise ValueError(f"num_downs must be >= 5 (UnetGenerator's fixed outer levels), got {num_downs}")
        self.ngf, self.num_downs = ngf, num_downs
        self.buffer = ng.LinearUnetGenerator(ng.INPUT_CHANNELS, 3, num_downs, ngf)

    def check_inputs(self, inputs):
        m = 2 ** self.num_downs
        if inputs.dim() != 4 or inputs.shape[1] != ng.INPUT_CHANNELS or inputs.shape[2] % m or inputs.shape[3] % m:
            raise ValueError(f"inputs must be [N, {ng.INPUT_CHANNELS}, H, W] with H, W multiples of {m}, "
                             f"got {tuple(inputs.shape)}")

    def raw_output(self, inputs):
        self.check_inputs(inputs)
        return self.buffer(inputs)


# The U-Net baseline's MLP in its neural_gi file: 6 ReLU units carry +B and -B, the output takes their difference.
UNET_PASS_WIDTH = 6


def unet_as_neural_gi(net):
    """An exactly equivalent SceneNeuralGI: buffer = the U-Net (C_B 3), MLP = 1 hidden layer of 6 units that passes
    the buffer through unchanged: h = relu([B, -B]), raw = h[0:3] - h[3:6] = B (weights 0 / +-1 and zero biases
    are exact in F16, and relu(b) - relu(-b) = b exactly), so the file runs the baseline in ngi as it trained."""
    full = SceneNeuralGI(buffer_channels=3, ngf=net.ngf, num_downs=net.num_downs, mlp_width=UNET_PASS_WIDTH,
                         mlp_depth=1, skip_layer=None)
    e = ng.ENCODED_CHANNELS
    with torch.no_grad():
        full.buffer.load_state_dict(net.buffer.state_dict())
        first, out = full.mlp.layers[0], full.mlp.output
        first.weight.zero_()
        first.bias.zero_()
        out.weight.zero_()
        out.bias.zero_()
        for c in range(3):
            first.weight[c, e + c, 0, 0] = 1.0
            first.weight[3 + c, e + c, 0, 0] = -1.0
            out.weight[c, c, 0, 0] = 1.0
            out.weight[c, 3 + c, 0, 0] = -1.0
    return full


def build(config):
    torch.manual_seed(config["seed"])
    a = config["arch"]
    if config.get("unet_only"):
        return UnetOnlyGI(a["ngf"], a["num_downs"])
    if config["no_buffer"]:
        return NoBufferGI(a["mlp_width"], a["mlp_depth"], a["skip_layer"] or None)
    return SceneNeuralGI(a["buffer_channels"], a["ngf"], a["num_downs"], a["mlp_width"], a["mlp_depth"],
                         a["skip_layer"] or None)

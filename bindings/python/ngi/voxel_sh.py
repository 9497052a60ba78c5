"""Seed 004's networks (voxel attributes -> SH coefficients), the same math as ngi's voxel_sh runner
(host/src/models/voxel_sh_model.cpp, docs/MODEL_FORMAT.md "voxel_sh").

Every network maps standardized inputs x' [..., V, 10] (one scene: V occupied voxels) to standardized
coefficients y' [..., V, 27]; hidden activations are tanh (seed 004: "tanh to predict negative numbers"), the last
layer is linear. `VoxelSh` wraps a network with the standardization to map raw attributes to SH in lighting
units, as Model::run does.

- "mlp":    10 -> hidden... -> 27, per voxel.
- "set":    phi (10 -> 128 -> 128 per voxel), max and mean over the scene's voxels, rho on
            [h | max | mean] (384 -> 256 -> 128 -> 27): the set network the seed notes recommend (section 3).
- "resnet": seed 004's "Rasnet-10": 10 -> W, then `blocks` residual blocks h = h + tanh(Linear(h)), W -> 27.
            One linear per block: "Rasnet-10" read as 10 residual layers; each block's branch is bounded
            (|tanh| < 1), so h grows at most by 1 per block and needs no normalization, and it halves the cost of
            the two-linear block (Linear, tanh, Linear) at equal depth.

Tensor names (state_dict keys) are the model file's: layers.<i>, phi.<i>, rho.<i>, input, blocks.<i>, output.
"""

import torch
import torch.nn.functional as F
from torch import nn

from ngi import _constants

INPUTS = 10
OUTPUTS = 27
ARCHITECTURES = ("mlp", "set", "resnet")
# Standardized inputs beyond +-INPUT_BOUND are replaced by it, NaN by 0: ngi's kVoxelShInputBound
# (host/src/models/voxel_sh_model.hpp), through the generated ngi._constants.
INPUT_BOUND = _constants.VOXEL_SH_INPUT_BOUND
DEFAULT_WIDTHS = {"mlp": {"hidden": [128, 128, 128]},
                  "set": {"phi": [128, 128], "rho": [256, 128]},
                  "resnet": {"width": 128, "blocks": 10}}


class MLP(nn.Module):
    def __init__(self, hidden):
        super().__init__()
        widths = [INPUTS] + list(hidden) + [OUTPUTS]
        self.layers = nn.ModuleList(nn.Linear(a, b) for a, b in zip(widths[:-1], widths[1:]))

    def forward(self, x):
        for layer in self.layers[:-1]:
            x = torch.tanh(layer(x))
        return self.layers[-1](x)


class SetNet(nn.Module):
    def __init__(self, phi, rho):
        super().__init__()
        p = [INPUTS] + list(phi)
        self.phi = nn.ModuleList(nn.Linear(a, b) for a, b in zip(p[:-1], p[1:]))
        r = [3 * p[-1]] + list(rho) + [OUTPUTS]
        self.rho = nn.ModuleList(nn.Linear(a, b) for a, b in zip(r[:-1], r[1:]))

    def pooled(self, x):
        """(per-voxel features h [..., V, P], the scene's [max | mean] [..., 2P])."""
        h = x
        for layer in self.phi:
            h = torch.tanh(layer(h))
        return h, torch.cat([h.max(dim=-2).values, h.mean(dim=-2)], dim=-1)

    def forward(self, x):
        h, g = self.pooled(x)
        # rho.0 on [h | max | mean], computed as W[:, :P] h + (W[:, P:] g + b): the pooled part is one product per
        # scene (the same split ngi makes), a third of the multiply-adds of the broadcast concat.
        p = h.shape[-1]
        w = self.rho[0].weight
        z = torch.tanh(F.linear(h, w[:, :p]) + F.linear(g, w[:, p:], self.rho[0].bias).unsqueeze(-2))
        for layer in self.rho[1:-1]:
            z = torch.tanh(layer(z))
        return self.rho[-1](z)

    def forward_concat(self, x):
        """The literal form (broadcast, concatenate, rho): equal to forward() up to rounding; for tests."""
        h, g = self.pooled(x)
        z = torch.cat([h, g.unsqueeze(-2).expand(*h.shape[:-1], g.shape[-1])], dim=-1)
        for layer in self.rho[:-1]:
            z = torch.tanh(layer(z))
        return self.rho[-1](z)


class ResNet(nn.Module):
    def __init__(self, width, blocks):
        super().__init__()
        self.input = nn.Linear(INPUTS, width)
        self.blocks = nn.ModuleList(nn.Linear(width, width) for _ in range(blocks))
        self.output = nn.Linear(width, OUTPUTS)

    def forward(self, x):
        h = torch.tanh(self.input(x))
        for block in self.blocks:
            h = h + torch.tanh(block(h))
        return self.output(h)


def widths_of(architecture, **overrides):
    """The width fields of `architecture` (DEFAULT_WIDTHS with the non-None overrides that apply to it)."""
    if architecture not in ARCHITECTURES:
        raise ValueError(f"architecture must be one of {ARCHITECTURES}, got {architecture!r}")
    w = {k: (list(v) if isinstance(v, list) else v) for k, v in DEFAULT_WIDTHS[architecture].items()}
    w.update({k: v for k, v in overrides.items() if v is not None and k in w})
    return w


def build(architecture, **widths):
    """The network of `architecture` with the given width fields (hidden; phi, rho; width, blocks)."""
    w = widths_of(architecture, **widths)
    if architecture == "mlp":
        return MLP(w["hidden"])
    if architecture == "set":
        return SetNet(w["phi"], w["rho"])
    return ResNet(w["width"], w["blocks"])


def from_config(config):
    """The (untrained) network a voxel_sh model-file config describes."""
    keys = {"mlp": ("hidden",), "set": ("phi", "rho"), "resnet": ("width", "blocks")}[config["architecture"]]
    return build(config["architecture"], **{k: config[k] for k in keys})


def parameter_count(net):
    return sum(p.numel() for p in net.parameters())


def l2_weights(net):
    """Sum of the squared entries of every weight matrix (biases excluded): the ||W||^2 of seed 004's Eq. 31."""
    return sum((m.weight ** 2).sum() for m in net.modules() if isinstance(m, nn.Linear))


class Standardization(nn.Module):
    """x' = 2 (x - lo) / (hi - lo) - 1 per input channel (0 where hi == lo), computed as s x + t with s, t rounded
    to the module's dtype, as ngi does on the device; y = mean + std y' per coefficient."""

    def __init__(self, input_lo, input_hi, output_mean, output_std):
        super().__init__()
        lo = torch.as_tensor(input_lo, dtype=torch.float64)
        hi = torch.as_tensor(input_hi, dtype=torch.float64)
        span = hi - lo
        s = torch.where(span > 0, 2.0 / torch.where(span > 0, span, torch.ones_like(span)), torch.zeros_like(span))
        t = torch.where(span > 0, -2.0 * lo / torch.where(span > 0, span, torch.ones_like(span)) - 1.0,
                        torch.zeros_like(span))
        self.register_buffer("in_scale", s.float())
        self.register_buffer("in_shift", t.float())
        self.register_buffer("out_mean", torch.as_tensor(output_mean, dtype=torch.float64).float())
        self.register_buffer("out_std", torch.as_tensor(output_std, dtype=torch.float64).float())

    def inputs(self, x):
        return x * self.in_scale.to(x.dtype) + self.in_shift.to(x.dtype)

    def outputs(self, y):
        return self.out_mean.to(y.dtype) + self.out_std.to(y.dtype) * y

    def targets(self, y):
        return (y - self.out_mean.to(y.dtype)) / self.out_std.to(y.dtype)


def guard(x):
    """ngi's input guard on standardized inputs: NaN -> 0, values beyond +-INPUT_BOUND by more than 1/1024 of the
    range's width -> +-INPUT_BOUND (Elementwise::sanitize). Returns (guarded x, number of replaced values)."""
    tol = 2 * INPUT_BOUND / 1024
    nan, high, low = torch.isnan(x), x > INPUT_BOUND + tol, x < -INPUT_BOUND - tol
    y = torch.where(nan, torch.zeros_like(x), x)
    y = torch.where(high, torch.full_like(x, INPUT_BOUND), y)
    y = torch.where(low, torch.full_like(x, -INPUT_BOUND), y)
    return y, int((nan | high | low).sum())


class VoxelSh(nn.Module):
    """Raw attributes [V, 10] -> SH [V, 27] in lighting units: what ngi's Model::run computes for a model file."""

    def __init__(self, net, standardization):
        super().__init__()
        self.net = net
        self.std = standardization

    def forward(self, raw):
        x, _ = guard(self.std.inputs(raw))
        return self.std.outputs(self.net(x))

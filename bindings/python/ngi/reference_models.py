"""PyTorch reference implementations of the generators ngi runs.

Both architectures are re-implemented module for module, so their
state_dict keys, layer order and in-place activations match upstream:
  * UnetGenerator / UnetSkipConnectionBlock - junyanz/pytorch-CycleGAN-and-pix2pix,
    models/networks.py, with norm='batch'
  * G - CreativeCodingLab/DeepIllumination, model.py (its typos fixed)

Only dropout differs from upstream: nn.Dropout draws from torch's RNG, which
no other implementation can reproduce. Here every Dropout is either an
identity (dropout "off") or SeededDropout, the counter-based hash that ngi's
kernel computes bit for bit (dropout "seeded", ngi.dropout), see docs/MODEL_FORMAT.md.

Also the float64 reference of the "mlp" family (run_mlp_reference), seed 001's
ambient-occlusion MLP as PyTorch trains it (ao_mlp), and load_generator, which
builds the reference generator of a model file. The other families' networks:
ngi.neural_gi (Neural GI), ngi.voxel_sh (voxel SH).
"""

import copy
import math

import numpy as np
import torch
import torch.nn as nn

from .dropout import DROPOUT_P, dropout_keep_mask


# --------------------------------------------------------------------------
# Seeded dropout (the hash itself is ngi.dropout's)
# --------------------------------------------------------------------------

class DropoutSites:
    """Hands out dropout site numbers in execution order; reset before each forward."""

    def __init__(self, seed, p=DROPOUT_P):
        self.seed = seed
        self.p = p
        self.next_site = 0

    def reset(self):
        self.next_site = 0

    def take(self):
        site = self.next_site
        self.next_site += 1
        return site


class SeededDropout(nn.Module):
    """Inverted dropout whose mask is a hash of (seed, site, element index)."""

    def __init__(self, sites):
        super().__init__()
        self.sites = sites

    def forward(self, x):
        site = self.sites.take()
        keep = dropout_keep_mask(self.sites.seed, site, x.numel(), self.sites.p)
        keep = torch.from_numpy(keep).reshape(x.shape)
        return torch.where(keep, x / (1 - self.sites.p), torch.zeros_like(x))


def make_dropout(sites):
    """Stand-in for nn.Dropout(0.5): identity when dropout is off (sites is None)."""
    return nn.Identity() if sites is None else SeededDropout(sites)


def make_sites(dropout, seed):
    if dropout not in ("off", "seeded"):
        raise ValueError(f"dropout must be 'off' or 'seeded', got {dropout!r}")
    return DropoutSites(seed) if dropout == "seeded" else None


# --------------------------------------------------------------------------
# junyanz pix2pix U-Net
# --------------------------------------------------------------------------

class UnetSkipConnectionBlock(nn.Module):
    """One U-Net level: x -> cat([x, up(submodule(down(x)))]) (no concat when outermost).

    The submodule sits inside this block's nn.Sequential `model`, so parameter
    names nest as model.1.model.3.model.3... exactly like upstream.
    """

    def __init__(self, outer_nc, inner_nc, input_nc=None, submodule=None, outermost=False,
                 innermost=False, use_dropout=False, sites=None):
        super().__init__()
        self.outermost = outermost
        # Upstream: use_bias = (norm_layer is InstanceNorm2d). ngi supports
        # BatchNorm only, so convs never carry a bias - not even the outermost
        # downconv, which has no norm after it.
        use_bias = False
        if input_nc is None:
            input_nc = outer_nc
        downconv = nn.Conv2d(input_nc, inner_nc, kernel_size=4, stride=2, padding=1, bias=use_bias)
        # In place: the block's input x is overwritten, so the skip half of
        # torch.cat([x, ...]) below carries LeakyReLU(x), not x.
        downrelu = nn.LeakyReLU(0.2, True)
        downnorm = nn.BatchNorm2d(inner_nc)
        uprelu = nn.ReLU(True)
        upnorm = nn.BatchNorm2d(outer_nc)

        if outermost:
            upconv = nn.ConvTranspose2d(inner_nc * 2, outer_nc, kernel_size=4, stride=2, padding=1)
            model = [downconv, submodule, uprelu, upconv, nn.Tanh()]
        elif innermost:
            upconv = nn.ConvTranspose2d(inner_nc, outer_nc, kernel_size=4, stride=2, padding=1, bias=use_bias)
            model = [downrelu, downconv, uprelu, upconv, upnorm]
        else:
            upconv = nn.ConvTranspose2d(inner_nc * 2, outer_nc, kernel_size=4, stride=2, padding=1,
                                        bias=use_bias)
            model = [downrelu, downconv, downnorm, submodule, uprelu, upconv, upnorm]
            if use_dropout:
                model.append(make_dropout(sites))
        self.model = nn.Sequential(*model)

    def forward(self, x):
        if self.outermost:
            return self.model(x)
        return torch.cat([x, self.model(x)], 1)


class UnetGenerator(nn.Module):
    """junyanz UnetGenerator with norm='batch'; netG 'unet_256' is num_downs=8.

    use_dropout=True (pix2pix's default) puts a Dropout after the upnorm of
    the num_downs-5 blocks just outside the innermost one. Those execute
    innermost-first, so dropout site 0 is the deepest.
    """

    def __init__(self, input_nc, output_nc, num_downs, ngf=64, use_dropout=True, dropout="off", dropout_seed=0):
        super().__init__()
        self.sites = make_sites(dropout, dropout_seed)
        block = UnetSkipConnectionBlock(ngf * 8, ngf * 8, innermost=True)
        for _ in range(num_downs - 5):
            block = UnetSkipConnectionBlock(ngf * 8, ngf * 8, submodule=block, use_dropout=use_dropout,
                                            sites=self.sites)
        block = UnetSkipConnectionBlock(ngf * 4, ngf * 8, submodule=block)
        block = UnetSkipConnectionBlock(ngf * 2, ngf * 4, submodule=block)
        block = UnetSkipConnectionBlock(ngf, ngf * 2, submodule=block)
        self.model = UnetSkipConnectionBlock(output_nc, ngf, input_nc=input_nc, submodule=block, outermost=True)

    def forward(self, x):
        if self.sites is not None:
            self.sites.reset()
        return self.model(x)


# --------------------------------------------------------------------------
# DeepIllumination G
# --------------------------------------------------------------------------

class DeepIlluminationG(nn.Module):
    """CreativeCodingLab/DeepIllumination `G(n_channel_input, n_channel_output, n_filters)`.

    Quirks kept from upstream: every conv/deconv has a bias even when a
    BatchNorm follows; the BatchNorm modules are shared (batch_norm8 serves
    encoders 4-7 and decoders 1-4, batch_norm4 encoder 3 and decoder 5,
    batch_norm2 encoder 2 and decoder 6); the in-place LeakyReLU makes every
    encoder skip carry LeakyReLU(encoder); skips are concatenated after the
    decoder output, cat(decoder, encoder); one Dropout module runs on
    decoders 1-3 (sites 0, 1, 2).
    """

    def __init__(self, n_channel_input, n_channel_output, n_filters, dropout="off", dropout_seed=0):
        super().__init__()
        f = n_filters
        self.conv1 = nn.Conv2d(n_channel_input, f, 4, 2, 1)
        self.conv2 = nn.Conv2d(f, f * 2, 4, 2, 1)
        self.conv3 = nn.Conv2d(f * 2, f * 4, 4, 2, 1)
        self.conv4 = nn.Conv2d(f * 4, f * 8, 4, 2, 1)
        self.conv5 = nn.Conv2d(f * 8, f * 8, 4, 2, 1)
        self.conv6 = nn.Conv2d(f * 8, f * 8, 4, 2, 1)
        self.conv7 = nn.Conv2d(f * 8, f * 8, 4, 2, 1)
        self.conv8 = nn.Conv2d(f * 8, f * 8, 4, 2, 1)

        self.deconv1 = nn.ConvTranspose2d(f * 8, f * 8, 4, 2, 1)
        self.deconv2 = nn.ConvTranspose2d(f * 8 * 2, f * 8, 4, 2, 1)
        self.deconv3 = nn.ConvTranspose2d(f * 8 * 2, f * 8, 4, 2, 1)
        self.deconv4 = nn.ConvTranspose2d(f * 8 * 2, f * 8, 4, 2, 1)
        self.deconv5 = nn.ConvTranspose2d(f * 8 * 2, f * 4, 4, 2, 1)
        self.deconv6 = nn.ConvTranspose2d(f * 4 * 2, f * 2, 4, 2, 1)
        self.deconv7 = nn.ConvTranspose2d(f * 2 * 2, f, 4, 2, 1)
        self.deconv8 = nn.ConvTranspose2d(f * 2, n_channel_output, 4, 2, 1)

        self.batch_norm = nn.BatchNorm2d(f)
        self.batch_norm2 = nn.BatchNorm2d(f * 2)
        self.batch_norm4 = nn.BatchNorm2d(f * 4)
        self.batch_norm8 = nn.BatchNorm2d(f * 8)

        self.leaky_relu = nn.LeakyReLU(0.2, True)
        self.relu = nn.ReLU(True)
        self.sites = make_sites(dropout, dropout_seed)
        self.dropout = make_dropout(self.sites)
        self.tanh = nn.Tanh()

    def forward(self, input):
        if self.sites is not None:
            self.sites.reset()
        encoder1 = self.conv1(input)
        encoder2 = self.batch_norm2(self.conv2(self.leaky_relu(encoder1)))
        encoder3 = self.batch_norm4(self.conv3(self.leaky_relu(encoder2)))
        encoder4 = self.batch_norm8(self.conv4(self.leaky_relu(encoder3)))
        encoder5 = self.batch_norm8(self.conv5(self.leaky_relu(encoder4)))
        encoder6 = self.batch_norm8(self.conv6(self.leaky_relu(encoder5)))
        encoder7 = self.batch_norm8(self.conv7(self.leaky_relu(encoder6)))
        encoder8 = self.conv8(self.leaky_relu(encoder7))

        decoder1 = self.dropout(self.batch_norm8(self.deconv1(self.relu(encoder8))))
        decoder1 = torch.cat((decoder1, encoder7), 1)
        decoder2 = self.dropout(self.batch_norm8(self.deconv2(self.relu(decoder1))))
        decoder2 = torch.cat((decoder2, encoder6), 1)
        decoder3 = self.dropout(self.batch_norm8(self.deconv3(self.relu(decoder2))))
        decoder3 = torch.cat((decoder3, encoder5), 1)
        decoder4 = self.batch_norm8(self.deconv4(self.relu(decoder3)))
        decoder4 = torch.cat((decoder4, encoder4), 1)
        decoder5 = self.batch_norm4(self.deconv5(self.relu(decoder4)))
        decoder5 = torch.cat((decoder5, encoder3), 1)
        decoder6 = self.batch_norm2(self.deconv6(self.relu(decoder5)))
        decoder6 = torch.cat((decoder6, encoder2), 1)
        decoder7 = self.batch_norm(self.deconv7(self.relu(decoder6)))
        decoder7 = torch.cat((decoder7, encoder1), 1)
        decoder8 = self.deconv8(self.relu(decoder7))
        return self.tanh(decoder8)


# --------------------------------------------------------------------------
# Running a reference
# --------------------------------------------------------------------------

def build_generator(family, input_nc, output_nc, ngf, num_downs, dropout="off", dropout_seed=0):
    """A generator of `family` with PyTorch's default initialization."""
    if family == "pix2pix_unet":
        return UnetGenerator(input_nc, output_nc, num_downs, ngf, dropout=dropout, dropout_seed=dropout_seed)
    if family == "deepillumination":
        if num_downs != 8:
            raise ValueError("deepillumination has exactly 8 downsamplings")
        return DeepIlluminationG(input_nc, output_nc, ngf, dropout=dropout, dropout_seed=dropout_seed)
    raise ValueError(f"unknown family {family!r}")


def set_bn_mode(model, bn_mode):
    """running: eval-mode BatchNorm. per_image: training-mode BatchNorm, i.e. with
    batch 1 each image is normalized by its own per-channel mean and biased
    variance over HxW. Dropout is unaffected: it is never an nn.Dropout here."""
    if bn_mode not in ("running", "per_image"):
        raise ValueError(f"bn_mode must be 'running' or 'per_image', got {bn_mode!r}")
    model.train(bn_mode == "per_image")


def run_reference(model, x, bn_mode, dtype=torch.float64):
    """Forward `x` through a copy of `model` in `dtype`; `model` itself is not touched.

    The copy matters for per_image: training-mode BatchNorm updates its
    running statistics during forward, which must not leak into exported weights.
    """
    reference = copy.deepcopy(model).to(dtype)
    set_bn_mode(reference, bn_mode)
    with torch.no_grad():
        return reference(x.to(dtype))


def load_generator(tensors, config):
    """The reference generator of a model file (ngi.model_file.read_model's tensors and config), its weights
    as float32 (exact for F16 files). bn_mode is not applied: pass config["bn_mode"] to run_reference."""
    model = build_generator(config["family"], config["input_nc"], config["output_nc"], config["ngf"],
                            config["num_downs"], config["dropout"], config["dropout_seed"])
    state = {name: torch.from_numpy(np.asarray(array).astype(np.float32)) for name, array in tensors.items()}
    missing, unexpected = model.load_state_dict(state, strict=False)
    if unexpected or any(not name.endswith("num_batches_tracked") for name in missing):
        raise ValueError(f"model file does not match its config: missing {missing}, unexpected {unexpected}")
    return model


# --------------------------------------------------------------------------
# The "mlp" family (docs/MODEL_FORMAT.md)
# --------------------------------------------------------------------------

MLP_ACTIVATIONS = {
    "none": lambda x, s: x,
    "relu": lambda x, s: torch.relu(x),
    "leaky_relu": lambda x, s: torch.nn.functional.leaky_relu(x, s),
    "tanh": lambda x, s: torch.tanh(x),
    "sigmoid": lambda x, s: torch.sigmoid(x),
    "exp": lambda x, s: torch.exp(torch.clamp(x, max=88.0)),
}


def encode_frequencies(x, encoding):
    """The mlp input encoding (docs/CONVENTIONS.md section 13): x [n, C] -> [n, encoded width]; no encoding (None
    or 0 bands) returns x."""
    if not encoding or encoding["bands"] == 0:
        return x
    parts = [x] if encoding["include_input"] else []
    scales = [2.0 ** (encoding["first_exponent"] + b) * (math.pi if encoding["pi"] else 1.0)
              for b in range(encoding["bands"])]
    if encoding["order"] == "band":
        for s in scales:
            parts += [torch.sin(s * x), torch.cos(s * x)]
        return torch.cat(parts, dim=1)
    per_comp = []
    for c in range(x.shape[1]):
        for s in scales:
            per_comp += [torch.sin(s * x[:, c:c + 1]), torch.cos(s * x[:, c:c + 1])]
    return torch.cat(parts + per_comp, dim=1)


def run_mlp_reference(tensors, config, x):
    """An "mlp" model in float64: x [n, input_nc] (array or tensor) -> [n, last layer's out] float64 tensor.

    tensors: name -> array or tensor (layers.<i>.weight [out, in], layers.<i>.bias [out]), converted to float64;
    config: the model's config (layers with activation and slope, the optional encoding).
    """
    h = encode_frequencies(torch.as_tensor(x).double(), config.get("encoding"))
    for i, layer in enumerate(config["layers"]):
        w = torch.as_tensor(tensors[f"layers.{i}.weight"]).double()
        b = torch.as_tensor(tensors[f"layers.{i}.bias"]).double()
        h = MLP_ACTIVATIONS[layer.get("activation", "none")](h @ w.t() + b, layer.get("slope", 0.01))
    return h


AO_INPUTS = 48  # 16 ring normals x 3 (docs/CONVENTIONS.md section 15)


def ao_mlp(hidden_x, hidden_y):
    """Seed 001's ambient-occlusion network as training builds it (ngi_train.ao.train): 48 -> hidden_x tanh ->
    hidden_y tanh -> 1. An nn.Sequential, so its state_dict keys are 0/2/4.weight|bias; the trainer folds the input
    and output scaling into them and writes an "mlp" family file (layers.0..2), which run_mlp_reference runs."""
    return nn.Sequential(nn.Linear(AO_INPUTS, hidden_x), nn.Tanh(), nn.Linear(hidden_x, hidden_y), nn.Tanh(),
                         nn.Linear(hidden_y, 1))

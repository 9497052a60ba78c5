"""The two networks of pix2pix: the U-Net generator ngi runs and the PatchGAN discriminator that trains it.

Generator: ngi.reference_models.UnetGenerator, the module-for-module copy of junyanz's
UnetGenerator(norm='batch') that the C++ library is tested against, so the trained state_dict is exactly what
`ngi.model_file.write_model` stores and `ngi generate` runs. For training its dropout sites (nn.Identity there
when dropout is "off") become nn.Dropout(0.5), pix2pix's default; they hold no parameters, so the state_dict
keys do not change.

Discriminator: junyanz NLayerDiscriminator (models/networks.py) with n_layers = 3, BatchNorm, LeakyReLU 0.2
and no sigmoid (the loss is BCEWithLogitsLoss), the 70x70 PatchGAN. Its input is the generator input
concatenated with an image (12 + 3 = 15 channels surround, 10 + 3 = 13 single view); which region it sees
is decided in gan.py.

Both are initialized like pix2pix's init_weights(init_type='normal', init_gain=0.02).
"""

import torch.nn as nn

import ngi.reference_models as reference_models


def build_generator(input_nc, output_nc, ngf, num_downs, use_dropout=True):
    """junyanz UnetGenerator with nn.Dropout(0.5) at its dropout sites (when use_dropout)."""
    g = reference_models.UnetGenerator(input_nc, output_nc, num_downs, ngf, use_dropout=use_dropout, dropout="off")
    if use_dropout:
        for module in g.modules():
            if isinstance(module, reference_models.UnetSkipConnectionBlock) and len(module.model) == 8:
                assert isinstance(module.model[7], nn.Identity)
                module.model[7] = nn.Dropout(reference_models.DROPOUT_P)
    return g


def inference_generator(state_dict, input_nc, output_nc, ngf, num_downs, dropout="off", dropout_seed=0):
    """The generator as ngi runs it: dropout off (identity) or seeded (ngi's hash), weights from state_dict."""
    g = reference_models.UnetGenerator(input_nc, output_nc, num_downs, ngf, dropout=dropout,
                                       dropout_seed=dropout_seed)
    g.load_state_dict(state_dict)
    return g


def dropout_site_count(num_downs):
    return max(0, num_downs - 5)


class NLayerDiscriminator(nn.Module):
    """junyanz PatchGAN: C(ndf) s2 -> LReLU, then n_layers-1 x [C s2, BN, LReLU], C s1, BN, LReLU, C(1) s1.

    All kernels 4x4 with padding 1; with BatchNorm only the first and the last conv have a bias. With
    n_layers = 3 each output logit sees a 70x70 input patch; an input of H x W gives (H/8 - 2) x (W/8 - 2)
    logits, so H and W must be at least 24.
    """

    def __init__(self, input_nc, ndf=64, n_layers=3):
        super().__init__()
        kw, padw = 4, 1
        sequence = [nn.Conv2d(input_nc, ndf, kernel_size=kw, stride=2, padding=padw), nn.LeakyReLU(0.2, True)]
        nf_mult = 1
        for n in range(1, n_layers):
            nf_mult_prev, nf_mult = nf_mult, min(2 ** n, 8)
            sequence += [nn.Conv2d(ndf * nf_mult_prev, ndf * nf_mult, kernel_size=kw, stride=2, padding=padw,
                                   bias=False),
                         nn.BatchNorm2d(ndf * nf_mult), nn.LeakyReLU(0.2, True)]
        nf_mult_prev, nf_mult = nf_mult, min(2 ** n_layers, 8)
        sequence += [nn.Conv2d(ndf * nf_mult_prev, ndf * nf_mult, kernel_size=kw, stride=1, padding=padw, bias=False),
                     nn.BatchNorm2d(ndf * nf_mult), nn.LeakyReLU(0.2, True)]
        sequence += [nn.Conv2d(ndf * nf_mult, 1, kernel_size=kw, stride=1, padding=padw)]
        self.model = nn.Sequential(*sequence)

    def forward(self, x):
        return self.model(x)


def min_discriminator_size(n_layers):
    """Smallest input side that leaves the PatchGAN at least one output logit."""
    # One logit needs 3 pixels before the two stride-1 convs (each loses one); each stride-2 conv halves.
    return 3 * 2 ** n_layers


def init_weights(net, gain=0.02):
    """pix2pix init_weights(init_type='normal'): conv weights ~ N(0, gain), BatchNorm weights ~ N(1, gain),
    biases 0. Draws from torch's global RNG (seed it first)."""
    def init(m):
        name = m.__class__.__name__
        if hasattr(m, "weight") and ("Conv" in name or "Linear" in name):
            nn.init.normal_(m.weight.data, 0.0, gain)
            if getattr(m, "bias", None) is not None:
                nn.init.constant_(m.bias.data, 0.0)
        elif "BatchNorm2d" in name:
            nn.init.normal_(m.weight.data, 1.0, gain)
            nn.init.constant_(m.bias.data, 0.0)
    net.apply(init)
    return net


def parameter_count(net):
    return sum(p.numel() for p in net.parameters())

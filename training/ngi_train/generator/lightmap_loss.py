"""The output side of the pipeline in PyTorch, differentiable: what a generator's output becomes in ngi (decode, the
indirect mode's direct + indirect, compose, tone map) and the losses on it.

Every function mirrors a kernel of kernels/compose.cl for the model output range [-1, 1] and the Reinhard transfer
(docs/CONVENTIONS.md section 8); training/tests/test_training.py checks them against ngi's own pipeline on a frame.

Output modes (the model file's `output_mode`, docs/MODEL_FORMAT.md):
  lightmap  the thesis: the decoded output is the whole front lightmap (direct + indirect)
  indirect  the decoded output is indirect light (>= 0: the inverse Reinhard of [0, 1]), and the lightmap is the
            frame's direct light plus it, so a network that predicts nothing still gives direct light alone
"""

import torch

from ngi import _constants
from ngi_train.generator import data

OUTPUT_MODES = ("lightmap", "indirect")
LIGHT_MAX = _constants.LIGHT_MAX  # compose.cl LIGHT_MAX: the decoded output stops at the largest half float
FLT_MAX = 3.4028234663852886e38
# y is clamped below 1 (exactly representable in float32) so that y / (1 - y) stays finite, as does its gradient;
# the cap at LIGHT_MAX then applies as in the kernel.
_Y_MAX = 1.0 - 2.0 ** -20


def check_mode(mode):
    if mode not in OUTPUT_MODES:
        raise ValueError(f"output_mode must be one of {OUTPUT_MODES}, got {mode!r}")


def decode(v):
    """decode_lightmap: v in [-1, 1] -> y in [0, 1] -> y / (1 - y), capped at LIGHT_MAX (NaN -> 0)."""
    y = torch.nan_to_num((v + 1.0) * 0.5, nan=0.0).clamp(0.0, _Y_MAX)
    return (y / (1.0 - y)).clamp(max=LIGHT_MAX)


def encode(x):
    """encode_lightmap: linear light (>= 0) -> x / (1 + x) in [0, 1] -> [-1, 1]."""
    return x / (1.0 + x) * 2.0 - 1.0


def clean_light(t):
    """compose.cl clean_light: NaN -> 0, negative -> 0, +Inf -> FLT_MAX."""
    return torch.nan_to_num(t, nan=0.0, posinf=FLT_MAX, neginf=0.0).clamp(min=0.0)


def lightmap(v, direct, mode):
    """The front lightmap ngi makes from the generator's front output v [.., 3, N, N] (linear)."""
    check_mode(mode)
    light = decode(v)
    return light if mode == "lightmap" else clean_light(direct) + light


def final_image(light, albedo, emission, env):
    """compose_final: lightmap x albedo (NaN -> 0, clamped to [0, 1]) + emission + env."""
    a = torch.nan_to_num(albedo, nan=0.0).clamp(0.0, 1.0)
    return clean_light(light) * a + clean_light(emission) + clean_light(env)


def tonemap(x):
    """tonemap with the defaults `ngi lightmap` scores with: ACES (input capped at 1e4), clamp, sRGB OETF."""
    x = torch.nan_to_num(x, nan=0.0).clamp(0.0, 1e4)
    x = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
    x = x.clamp(0.0, 1.0)
    # The OETF's power branch at x >= 0.0031308 only (its derivative at 0 is infinite).
    high = 1.055 * torch.clamp(x, min=0.0031308) ** (1.0 / 2.4) - 0.055
    return torch.where(x <= 0.0031308, 12.92 * x, high).clamp(0.0, 1.0)


def display_final(light, front):
    """The tone-mapped final image of a lightmap, with the front planes of data.FRONT_PLANES ([.., 15, N, N])."""
    f = data.FRONT
    return tonemap(final_image(light, front[..., f["albedo"], :, :], front[..., f["emission"], :, :],
                               front[..., f["env"], :, :]))

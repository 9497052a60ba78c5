"""Seed 002, "Neural Global Illumination" (Gao, Mu, Xu): the network, its inputs and its loss, in PyTorch.

    inputs I [N, 18, H, W] --(Eq. 3, per component)--> Gamma(I) [N, 360, H, W]
    inputs I --(U-Net C, linear output)--> neural buffer B [N, C_B, H, W]                       (section 3.3)
    z = [I, Gamma(I), B] [N, 378 + C_B, H, W] --(MLP R, per pixel, 1 x 1 convolutions)--> o [N, 3, H, W]   (3.4)
    indirect L* = exp(min(o, 88))  (never negative)       final = L_d + L*                      (section 3.1)
    loss = mean | log(final + 1/e) - log(reference + 1/e) |                                      (Eq. 5 / 6)

The model of ngi's "neural_gi" family (docs/MODEL_FORMAT.md): export_model writes it as an ngi model file that
ngi::Model runs as one graph on the device. Tests: training/tests/test_neural_gi_model.py; parity with ngi:
tests/parity/make_neural_gi_parity.py.

Input channels (`assemble_inputs`; section 3.2 adapted to ngi's Lambertian voxel renderer: no specular albedo, no
roughness, no radiance cues, which would all equal the direct light or a constant)

| channels | quantity                  | encoding                                                                    |
|----------|---------------------------|-----------------------------------------------------------------------------|
| 0-2      | position p (x, y, z)      | scene box -> [-1, 1]: 2 (p - bbox_min) / (bbox_max - bbox_min) - 1, clamped  |
| 3-5      | world normal n_p          | unit vector                                                                 |
| 6-8      | diffuse albedo (R, G, B)  | clamped to [0, 1]                                                           |
| 9-11     | view direction omega_v    | unit vector from the camera to the point                                    |
| 12-14    | direct light L_d (R, G, B)| log(1 + L_d), L_d clamped to [0, RADIANCE_MAX]                              |
| 15-17    | light direction omega_e   | unit vector from the point to the area light's centre                       |

NaN becomes 0 everywhere (a zero vector stays zero after normalization); +-inf becomes the nearest bound.

Positional encoding (Eq. 3), the exact feature order (the C++ side must produce the same order): the 18 raw
channels first, then for each band b = 0..9 (scale s_b = 2^(b - 1) * pi, i.e. 2^-1 pi ... 2^8 pi) the sines of all
18 channels followed by the cosines of all 18 channels:

    [x_0..x_17, sin(s_0 x_0)..sin(s_0 x_17), cos(s_0 x_0)..cos(s_0 x_17), sin(s_1 x_0).., ..., cos(s_9 x_17)]

i.e. channel 18 + 36 b + c is sin(s_b x_c) and 18 + 36 b + 18 + c is cos(s_b x_c): 18 + 2 * 10 * 18 = 378
channels. This is ngi's frequency encoding `{bands 10, first_exponent -1, pi, include_input, order "band"}`
(docs/CONVENTIONS.md section 13, "BandMajor", which names this paper's Eq. 3 as that setting), computed by
ngi.reference_models.encode_frequencies; s_b is the float64 2^(b-1) pi rounded to float32 and multiplied with the
float32 input.

MLP R (after DeepSDF, Park et al. 2019, as the paper's section 3.4 says): `depth` = 8 hidden 1 x 1 convolutions of
`width` = 256 with ReLU, numbered 0..7; hidden layer `skip_layer` = 4 (the fifth) takes [h_3, z] (the output of
hidden layer 3, i.e. of the fourth hidden layer, then the MLP input z again), so its input width is 256 + 378 + C_B;
then a linear 1 x 1 convolution 256 -> 3 (`mlp.output`). No activation after it (the paper's Fig. 3b); the
non-negativity comes from the decoding.

The perceptual term of Eq. 5 (LPIPS on VGG features) is left out: its pre-trained VGG weights cannot be downloaded
here, and the paper's own Table 4 has the variant without it at higher PSNR (39.71 vs 37.82 dB on Kitchen).
"""

import math
import time

import torch
import torch.nn as nn

from ngi import _constants
from ngi.reference_models import UnetGenerator, encode_frequencies

FAMILY = "neural_gi"
INPUT_CHANNELS = 18
# Eq. 3 with L = 9: gamma_l(x) = (sin(2^(l-1) pi x), cos(2^(l-1) pi x)), l = 0..L. Read literally the exponent
# l - 1 runs from -1 to L - 1 = 8: L + 1 = 10 bands whose first one (2^-1 pi x = pi x / 2) is one half period over
# x in [-1, 1], so that band alone still tells -1 from 1 (sin(pi x / 2) is monotonic there). We keep this literal
# reading rather than NeRF's 2^l (exponents 0..9): the paper writes l - 1 on purpose, and it is what
# CONVENTIONS section 13 already fixes for this seed.
PE_L = 9
ENCODING = {"bands": PE_L + 1, "first_exponent": -1, "pi": True, "include_input": True, "order": "band"}
ENCODED_CHANNELS = INPUT_CHANNELS + 2 * ENCODING["bands"] * INPUT_CHANNELS  # 378

# Loss epsilon of Eq. 6.
LOG_EPSILON = 1.0 / math.e
# Bound of the radiances (direct input, reference): only replaces +inf and absurd values, keeps log1p(L_d) <= 69
# and L_d + exp(88) < 3.4e38, i.e. every sum in the forward pass and the loss finite in float32. Real HDR values
# (65504 and far beyond) pass unchanged. The C++ value (kNeuralGiRadianceMax, which kernels/neural_gi.cl is built
# with), through the generated ngi._constants.
RADIANCE_MAX = _constants.NEURAL_GI_RADIANCE_MAX
# exp's argument bound: ngi's "exp" activation is exp(min(x, 88)) (CONVENTIONS section 13), finite in float32
# (kActExpMax).
EXP_CLAMP = _constants.ACT_EXP_MAX

# Defaults (see NeuralGI for why).
DEFAULT_BUFFER_CHANNELS = 16
DEFAULT_NGF = 32
DEFAULT_NUM_DOWNS = 6
DEFAULT_MLP_WIDTH = 256
DEFAULT_MLP_DEPTH = 8
DEFAULT_SKIP_LAYER = 4
DECODE = "exp"


# --------------------------------------------------------------------------
# Inputs
# --------------------------------------------------------------------------

def _check_image(name, t):
    if not torch.is_tensor(t) or t.dim() != 4 or t.shape[1] != 3:
        shape = tuple(t.shape) if torch.is_tensor(t) else type(t).__name__
        raise ValueError(f"{name} must be a [N, 3, H, W] tensor, got {shape}")


def _unit(v):
    """Unit vectors along dim 1; zero stays zero. NaN components count as 0. An infinite component dominates every
    finite one, so a vector with infinities keeps only their signs ((inf, 5, -inf) -> (1, 0, -1) / sqrt 2).
    Dividing by the largest |component| before the norm keeps the squares from overflowing in float32."""
    v = torch.nan_to_num(v.float(), nan=0.0)
    infinite = torch.isinf(v)
    v = torch.where(infinite.any(dim=1, keepdim=True), torch.sign(v) * infinite, v)
    largest = v.abs().amax(dim=1, keepdim=True)
    v = torch.where(largest > 0, v / largest.clamp_min(torch.finfo(torch.float32).tiny), v)
    norm = torch.linalg.vector_norm(v, dim=1, keepdim=True)
    return torch.where(norm > 0, v / norm.clamp_min(1e-30), v)


def sanitize_radiance(radiance):
    """Linear radiance with NaN -> 0 and values clamped to [0, RADIANCE_MAX] (float32)."""
    return torch.nan_to_num(radiance.float(), nan=0.0, posinf=RADIANCE_MAX, neginf=0.0).clamp(0.0, RADIANCE_MAX)


def normalize_position(position, bbox_min, bbox_max):
    """World positions [N, 3, H, W] -> the scene box mapped to [-1, 1], clamped there, NaN -> 0. An axis of zero
    extent maps to 0 (the box has no information along it)."""
    lo = torch.as_tensor(bbox_min, dtype=torch.float32).reshape(1, 3, 1, 1)
    hi = torch.as_tensor(bbox_max, dtype=torch.float32).reshape(1, 3, 1, 1)
    if not (torch.isfinite(lo).all() and torch.isfinite(hi).all() and (hi >= lo).all()):
        raise ValueError(f"bad scene box: min {lo.flatten().tolist()}, max {hi.flatten().tolist()}")
    extent = hi - lo
    p = torch.nan_to_num(position.float(), nan=0.0, posinf=RADIANCE_MAX, neginf=-RADIANCE_MAX)
    scaled = torch.where(extent > 0, 2.0 * (p - lo) / extent.clamp_min(1e-30) - 1.0, torch.zeros_like(p))
    # NaN can only come from a NaN position, which was zeroed above: its normalized value is clamped like any other.
    return scaled.clamp(-1.0, 1.0)


def assemble_inputs(position, normal, albedo, view_dir, direct, light_dir, bbox_min, bbox_max):
    """The network input [N, 18, H, W] float32 (channel table in the module docstring) from [N, 3, H, W] buffers:
    world position, world normal, albedo, view direction (camera -> point), linear direct light L_d, direction to
    the light's centre (point -> light), and the scene's bounding box (3 numbers each)."""
    buffers = {"position": position, "normal": normal, "albedo": albedo, "view_dir": view_dir, "direct": direct,
               "light_dir": light_dir}
    for name, t in buffers.items():
        _check_image(name, t)
    shapes = {tuple(t.shape) for t in buffers.values()}
    if len(shapes) != 1:
        raise ValueError(f"the six buffers differ in shape: { {k: tuple(t.shape) for k, t in buffers.items()} }")
    albedo = torch.nan_to_num(albedo.float(), nan=0.0, posinf=1.0, neginf=0.0).clamp(0.0, 1.0)
    # log(1 + L_d): 0 for unlit pixels (the same value NaN sanitizes to), compresses HDR direct light into the
    # range where the encoding's low bands still resolve it (65504 -> 11.1).
    log_direct = torch.log1p(sanitize_radiance(direct))
    return torch.cat([normalize_position(position, bbox_min, bbox_max), _unit(normal), albedo, _unit(view_dir),
                      log_direct, _unit(light_dir)], dim=1)


def positional_encoding(inputs):
    """Eq. 3 with the raw inputs first: [N, 18, H, W] -> [N, 378, H, W] (order in the module docstring).
    encode_frequencies concatenates along dim 1 and, in band order, applies sin / cos to the whole tensor, so it
    takes the [N, C, H, W] images as they are."""
    return encode_frequencies(inputs, ENCODING)


# --------------------------------------------------------------------------
# The networks
# --------------------------------------------------------------------------

class LinearUnetGenerator(UnetGenerator):
    """ngi's pix2pix U-Net with the final tanh removed: the neural buffer is a free feature vector, not an image in
    [-1, 1]. The tanh module (the outermost block's last element, parameterless) becomes an identity, so the
    state_dict keys are exactly UnetGenerator's. Dropout is off (identity), BatchNorm as in pix2pix."""

    def __init__(self, input_nc, output_nc, num_downs, ngf):
        super().__init__(input_nc, output_nc, num_downs, ngf, use_dropout=False, dropout="off")
        outer = self.model.model
        if not isinstance(outer[-1], nn.Tanh):
            raise RuntimeError("UnetGenerator's outermost block no longer ends in nn.Tanh; update LinearUnetGenerator")
        outer[-1] = nn.Identity()


class RenderingMLP(nn.Module):
    """Per-pixel MLP as 1 x 1 convolutions: layers.<i> (i = 0..depth-1, ReLU), then output (linear, 3 channels).
    layers.<skip_layer> takes [h, z]: the previous hidden output, then the MLP input z again (DeepSDF)."""

    def __init__(self, in_channels, width=DEFAULT_MLP_WIDTH, depth=DEFAULT_MLP_DEPTH, skip_layer=DEFAULT_SKIP_LAYER,
                 out_channels=3):
        super().__init__()
        if depth < 1 or width < 1:
            raise ValueError(f"depth and width must be positive, got depth {depth}, width {width}")
        if skip_layer is not None and not 1 <= skip_layer < depth:
            raise ValueError(f"skip_layer must be in [1, {depth - 1}] (or None), got {skip_layer}")
        self.skip_layer = skip_layer
        layers = []
        for i in range(depth):
            fan_in = in_channels if i == 0 else width + (in_channels if i == skip_layer else 0)
            layers.append(nn.Conv2d(fan_in, width, kernel_size=1))
        self.layers = nn.ModuleList(layers)
        self.output = nn.Conv2d(width, out_channels, kernel_size=1)

    def forward(self, z):
        h = z
        for i, layer in enumerate(self.layers):
            if i == self.skip_layer:
                h = torch.cat([h, z], dim=1)
            h = torch.relu(layer(h))
        return self.output(h)


def decode_indirect(raw):
    """MLP output -> indirect radiance L* = exp(min(raw, 88)) >= 0.

    Why exp: the loss compares log(L_d + L* + 1/e), so the MLP's output lives in the loss's own log domain: HDR
    indirect light from 1e-3 to 1e4 is raw in [-7, 9], which a linear last layer reaches with ordinary weights; a
    softplus would need raw values as large as the radiance itself and its gradient in log space shrinks as
    1 / radiance. exp is never negative, as indirect light must not be (exp(raw) - 1/e, also suggested, reaches
    -1/e). The clamp is ngi's "exp" activation (CONVENTIONS section 13): finite for every finite input; a NaN raw
    (only from NaN weights or inputs, which assemble_inputs removes) is mapped to 0 so the output is never NaN."""
    return torch.nan_to_num(torch.exp(torch.clamp(raw, max=EXP_CLAMP)), nan=0.0)


class NeuralGI(nn.Module):
    """C (U-Net, linear output) + Eq. 3 + R (DeepSDF MLP) + exp decoding; forward(inputs) -> indirect L*.

    Defaults, for ngi's 64 x 64 and 128 x 128 frames:
      * num_downs 6: sides must be multiples of 2^6 = 64; at 64 x 64 the bottleneck is 1 x 1 (the U-Net sees the
        whole frame, as the paper's 8-level U-Net does at 256 x 256), at 128 x 128 it is 2 x 2. num_downs 5 (the
        smallest UnetGenerator builds) serves multiples of 32, 7 multiples of 128.
      * ngf 32, the ngi ladder's width (the seed's storage figure of 55.9 MB is consistent with ngf ~ 32 at 8 levels).
      * C_B = 16: the buffer carries screen-space context (where light lands off-pixel) next to 378 per-pixel
        channels; 16 is > 5 x the RGB it informs and adds only 16 x 256 weights to R's first layer. The seed notes
        suggest ~32; it is a parameter (config "buffer_channels").
    """

    def __init__(self, buffer_channels=DEFAULT_BUFFER_CHANNELS, ngf=DEFAULT_NGF, num_downs=DEFAULT_NUM_DOWNS,
                 mlp_width=DEFAULT_MLP_WIDTH, mlp_depth=DEFAULT_MLP_DEPTH, skip_layer=DEFAULT_SKIP_LAYER):
        super().__init__()
        if num_downs < 5:
            raise ValueError(f"num_downs must be >= 5 (UnetGenerator's fixed outer levels), got {num_downs}")
        if buffer_channels < 1:
            raise ValueError(f"buffer_channels must be positive, got {buffer_channels}")
        self.buffer_channels = buffer_channels
        self.ngf = ngf
        self.num_downs = num_downs
        self.buffer = LinearUnetGenerator(INPUT_CHANNELS, buffer_channels, num_downs, ngf)
        self.mlp = RenderingMLP(ENCODED_CHANNELS + buffer_channels, mlp_width, mlp_depth, skip_layer)

    @property
    def size_multiple(self):
        return 2 ** self.num_downs

    def check_inputs(self, inputs):
        if inputs.dim() != 4 or inputs.shape[1] != INPUT_CHANNELS:
            raise ValueError(f"inputs must be [N, {INPUT_CHANNELS}, H, W], got {tuple(inputs.shape)}")
        h, w = inputs.shape[2:]
        m = self.size_multiple
        if h % m or w % m or h == 0 or w == 0:
            raise ValueError(f"the U-Net with num_downs {self.num_downs} needs H and W to be positive multiples of "
                             f"2^{self.num_downs} = {m}, got {h} x {w}")

    def raw_output(self, inputs):
        """The MLP's linear RGB output (before decoding)."""
        self.check_inputs(inputs)
        buffer = self.buffer(inputs)
        z = torch.cat([positional_encoding(inputs), buffer], dim=1)
        return self.mlp(z)

    def forward(self, inputs):
        """Indirect radiance L* [N, 3, H, W] >= 0."""
        return decode_indirect(self.raw_output(inputs))

    def render(self, inputs, direct):
        """(final = L_d + L*, L*): `direct` is the linear L_d the inputs were assembled from [N, 3, H, W]."""
        indirect = self(inputs)
        return sanitize_radiance(direct) + indirect, indirect

    def config(self):
        """Everything needed to rebuild the model (`from_config`) and for the C++ side to run it."""
        mlp = self.mlp
        return {
            "family": FAMILY,
            "input_channels": INPUT_CHANNELS,
            "inputs": ["position", "normal", "albedo", "view_dir", "log1p_direct", "light_dir"],
            "encoding": dict(ENCODING, L=PE_L, encoded_channels=ENCODED_CHANNELS),
            "buffer": {"family": "pix2pix_unet", "output": "linear", "buffer_channels": self.buffer_channels,
                       "ngf": self.ngf, "num_downs": self.num_downs, "norm": "batch", "dropout": "off"},
            "mlp": {"in_channels": ENCODED_CHANNELS + self.buffer_channels, "width": mlp.output.in_channels,
                    "depth": len(mlp.layers), "skip_layer": mlp.skip_layer, "activation": "relu",
                    "out_channels": mlp.output.out_channels},
            "decode": DECODE,
            "exp_clamp": EXP_CLAMP,
            "loss": {"pixel": "l1_log", "epsilon": LOG_EPSILON, "perceptual": None},
        }

    @classmethod
    def from_config(cls, config):
        if config.get("family") != FAMILY:
            raise ValueError(f"not a {FAMILY} config: family {config.get('family')!r}")
        if config["input_channels"] != INPUT_CHANNELS or config["encoding"]["bands"] != ENCODING["bands"] \
                or config["decode"] != DECODE:
            raise ValueError("config's inputs, encoding or decoding differ from this code's")
        b, m = config["buffer"], config["mlp"]
        return cls(b["buffer_channels"], b["ngf"], b["num_downs"], m["width"], m["depth"], m["skip_layer"])


def parameter_count(module):
    return sum(p.numel() for p in module.parameters())


def parameter_counts(model):
    """{"buffer": U-Net, "mlp": R, "total"}."""
    return {"buffer": parameter_count(model.buffer), "mlp": parameter_count(model.mlp),
            "total": parameter_count(model)}


# --------------------------------------------------------------------------
# Export: an ngi model file (docs/MODEL_FORMAT.md "neural_gi")
# --------------------------------------------------------------------------

INPUT_LAYOUT = ["position.x", "position.y", "position.z", "normal.x", "normal.y", "normal.z", "albedo.r", "albedo.g",
                "albedo.b", "view.x", "view.y", "view.z", "log1p_direct.r", "log1p_direct.g", "log1p_direct.b",
                "light_dir.x", "light_dir.y", "light_dir.z"]
# What assemble_inputs produces: directions and positions in [-1, 1], albedo in [0, 1], log1p(direct) in
# [0, log1p(RADIANCE_MAX) = 69.1]. ngi's input guard replaces NaN and values beyond it.
INPUT_RANGE = [-1.0, 70.0]


def file_config(model, bn_mode="per_image", source="", scene_box=None, training=None):
    """The metadata an ngi model file stores for `model` (flat U-Net fields as the generators' files have them,
    the encoding as the mlp family's, the MLP under "neural_gi"), with the nested config() and `training` (a dict of
    the run's settings) kept under "training". scene_box: ((min x, y, z), (max x, y, z)), the box assemble_inputs
    normalized positions with; ngi needs it to assemble inputs from frames (NeuralGiRenderer)."""
    if bn_mode not in ("per_image", "running"):
        raise ValueError(f"bn_mode must be per_image or running, got {bn_mode!r}")
    c = model.config()
    enc = c["encoding"]
    return {
        "format_version": 1, "family": FAMILY, "input_nc": INPUT_CHANNELS, "output_nc": 3,
        "ngf": c["buffer"]["ngf"], "num_downs": c["buffer"]["num_downs"], "norm": "batch", "bn_mode": bn_mode,
        "bn_eps": 1e-5, "dropout": "off", "input_layout": INPUT_LAYOUT, "input_range": INPUT_RANGE,
        "output_range": [0.0, RADIANCE_MAX],
        "encoding": {k: enc[k] for k in ("bands", "first_exponent", "pi", "include_input", "order")},
        "neural_gi": dict({"buffer_channels": c["buffer"]["buffer_channels"], "mlp_width": c["mlp"]["width"],
                           "mlp_depth": c["mlp"]["depth"], "skip_layer": c["mlp"]["skip_layer"] or 0,
                           "decode": DECODE},
                          **({"scene_box": {"min": [float(v) for v in scene_box[0]],
                                            "max": [float(v) for v in scene_box[1]]}} if scene_box is not None else {})),
        "source": source, "training": dict(c, **(training or {})),
    }


def export_model(model, path, bn_mode="per_image", half=True, source="", scene_box=None, training=None):
    """Write `model` as an ngi model file: every parameter and batch-norm statistic under its PyTorch name
    (num_batches_tracked, a training counter, is left out), F16 when `half`; config from file_config."""
    from ngi import model_file  # numpy only; imported here so that the model code does not need it
    tensors = {k: v for k, v in model.state_dict().items() if not k.endswith("num_batches_tracked")}
    model_file.write_model(path, tensors, file_config(model, bn_mode, source, scene_box, training), half=half)


# --------------------------------------------------------------------------
# Loss
# --------------------------------------------------------------------------

def log_l1_loss(prediction, target, epsilon=LOG_EPSILON):
    """Eq. 6: mean over pixels and channels of |log(a + eps) - log(b + eps)|, eps = 1/e; a = L_d + L* predicted,
    b = the reference (full GI). The mean (not the sum) keeps the scale independent of the resolution and batch.

    Robust to HDR and zeros: both sides are clamped to [0, RADIANCE_MAX] (the reference's NaN -> 0, +inf -> the
    bound), so the logs are of numbers in [eps, 1e30], finite in float32 (1e6 -> 13.8, 0 -> -1). A NaN prediction is
    left NaN on purpose: it is a bug upstream (decode_indirect never yields one) and must not train silently."""
    if prediction.shape != target.shape:
        raise ValueError(f"prediction {tuple(prediction.shape)} and target {tuple(target.shape)} differ")
    a = prediction.float().clamp(0.0, RADIANCE_MAX)
    b = sanitize_radiance(target)
    return (torch.log(a + epsilon) - torch.log(b + epsilon)).abs().mean()


# --------------------------------------------------------------------------
# Measurements: python3 -m ngi.neural_gi
# --------------------------------------------------------------------------

def measure(sizes=(64, 128), repeats=3, **kwargs):
    """Parameter counts and the best-of-`repeats` forward time (eval mode, no grad, batch 1) per side length."""
    torch.manual_seed(0)
    model = NeuralGI(**kwargs).eval()
    result = {"config": model.config(), "parameters": parameter_counts(model), "forward_seconds": {}}
    with torch.no_grad():
        for n in sizes:
            x = torch.rand(1, INPUT_CHANNELS, n, n) * 2 - 1
            model(x)  # warm-up (allocations)
            best = math.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                model(x)
                best = min(best, time.perf_counter() - t0)
            result["forward_seconds"][n] = best
    return result


def main():
    import argparse
    import json
    parser = argparse.ArgumentParser(description="parameter counts and CPU forward times of NeuralGI")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--buffer-channels", type=int, default=DEFAULT_BUFFER_CHANNELS)
    parser.add_argument("--ngf", type=int, default=DEFAULT_NGF)
    parser.add_argument("--num-downs", type=int, default=DEFAULT_NUM_DOWNS)
    parser.add_argument("--mlp-width", type=int, default=DEFAULT_MLP_WIDTH)
    parser.add_argument("--mlp-depth", type=int, default=DEFAULT_MLP_DEPTH)
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 128])
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    result = measure(args.sizes, buffer_channels=args.buffer_channels, ngf=args.ngf, num_downs=args.num_downs,
                     mlp_width=args.mlp_width, mlp_depth=args.mlp_depth)
    p = result["parameters"]
    print(f"parameters: buffer (U-Net) {p['buffer']:,}, MLP {p['mlp']:,}, total {p['total']:,}")
    for n, s in result["forward_seconds"].items():
        print(f"forward {n} x {n}, {args.threads} thread(s): {s * 1000:.1f} ms")
    print(json.dumps(result["config"], indent=1))


if __name__ == "__main__":
    main()

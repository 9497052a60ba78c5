#!/usr/bin/python3
"""Convert a PyTorch generator checkpoint into an ngi model file (.safetensors).

The file is a Hugging Face safetensors file written by hand (the `safetensors`
package is not a dependency): an 8-byte little-endian header length, a JSON
header padded with spaces to a multiple of 8 bytes, then the raw little-endian
tensor data. The ngi configuration travels as a JSON string in
`__metadata__["ngi"]`. docs/MODEL_FORMAT.md is the specification.

Two generator families are understood, each from the checkpoint layout its
upstream training code writes:
  * pix2pix_unet     - junyanz/pytorch-CycleGAN-and-pix2pix UnetGenerator,
                       `<epoch>_net_G.pth` = torch.save(net.state_dict())
  * deepillumination - CreativeCodingLab/DeepIllumination G,
                       `netG_model_epoch_<n>.pth` =
                       torch.save({'epoch', 'state_dict_G', 'optimizer_G'})

Usage:
  /usr/bin/python3 tools/ngi_convert.py IN.pth OUT.safetensors \\
      --family pix2pix_unet --bn-mode per_image [--input-nc 12 --output-nc 3 \\
      --ngf 64 --num-downs 8] [--dropout off|seeded --dropout-seed S] [--half]
"""

import argparse
import inspect
import json
import os
import pickle
import struct
import sys

import numpy as np
import torch

FORMAT_VERSION = 1
FAMILIES = ("pix2pix_unet", "deepillumination")
BN_MODES = ("running", "per_image")
DROPOUT_MODES = ("off", "seeded")

# Hyper-parameters both upstream generators hard-code; they are written into
# the config anyway so the C++ side never has to assume them.
DROPOUT_P = 0.5      # nn.Dropout(0.5)
BN_EPS = 1e-05       # nn.BatchNorm2d default, not overridden upstream
LEAKY_SLOPE = 0.2    # nn.LeakyReLU(0.2, True)
# Both families are trained on images scaled to [-1, 1] and end in a Tanh.
VALUE_RANGE = [-1, 1]

METADATA_KEY = "__metadata__"
_NUMPY_DTYPES = {"F32": np.dtype("<f4"), "F16": np.dtype("<f2")}


class ConversionError(ValueError):
    """A checkpoint or option that cannot become a valid ngi model file."""


# --------------------------------------------------------------------------
# safetensors I/O
# --------------------------------------------------------------------------

def write_model(path, tensors, config, half=False):
    """Write `tensors` (name -> np.ndarray | torch.Tensor) and `config` to `path`.

    Tensors are stored in the iteration order of `tensors`, contiguously, as
    F32 (or F16 with half=True). The config dict is stored as a JSON string in
    __metadata__["ngi"], because safetensors metadata values must be strings.
    """
    dtype_name = "F16" if half else "F32"
    dtype = _NUMPY_DTYPES[dtype_name]
    header = {}
    blobs = []
    offset = 0
    for name, value in tensors.items():
        if name == METADATA_KEY:
            raise ConversionError(f"'{METADATA_KEY}' is reserved and cannot be a tensor name")
        if isinstance(value, torch.Tensor):
            value = value.detach().cpu().numpy()
        # np.array (unlike ascontiguousarray) keeps 0-d tensors 0-d. Overflow
        # warnings are silenced because the isfinite check below reports it by name.
        with np.errstate(over="ignore"):
            array = np.array(value, dtype=dtype, order="C")
        # Checked after the cast: a finite float32 above 65504 becomes inf in F16.
        if not np.isfinite(array).all():
            raise ConversionError(
                f"tensor '{name}' has non-finite values as {dtype_name}"
                f" (max |value| before the cast: {np.max(np.abs(np.asarray(value, np.float64)))})")
        data = array.tobytes()
        header[name] = {"dtype": dtype_name,
                        "shape": list(array.shape),
                        "data_offsets": [offset, offset + len(data)]}
        blobs.append(data)
        offset += len(data)
    header[METADATA_KEY] = {"ngi": json.dumps(config)}

    header_bytes = json.dumps(header, separators=(",", ":")).encode("utf-8")
    # Padding keeps the data section 8-byte aligned for readers that mmap it.
    header_bytes += b" " * (-len(header_bytes) % 8)
    with open(path, "wb") as f:
        f.write(struct.pack("<Q", len(header_bytes)))
        f.write(header_bytes)
        for data in blobs:
            f.write(data)


def read_model(path):
    """Read an ngi model file; returns (tensors: dict name -> np.ndarray, config: dict).

    Arrays keep their stored dtype (float32 or float16), in file order.
    """
    with open(path, "rb") as f:
        raw = f.read()
    if len(raw) < 8:
        raise ConversionError(f"{path}: too short to be a safetensors file")
    (header_len,) = struct.unpack_from("<Q", raw, 0)
    if 8 + header_len > len(raw):
        raise ConversionError(f"{path}: header length {header_len} exceeds the file size")
    header = json.loads(raw[8:8 + header_len].decode("utf-8"))
    data = memoryview(raw)[8 + header_len:]

    metadata = header.pop(METADATA_KEY, {})
    if "ngi" not in metadata:
        raise ConversionError(f"{path}: no __metadata__.ngi config; not an ngi model file")
    config = json.loads(metadata["ngi"])

    tensors = {}
    for name, entry in header.items():
        if entry["dtype"] not in _NUMPY_DTYPES:
            raise ConversionError(f"{path}: tensor '{name}' has unsupported dtype {entry['dtype']}")
        dtype = _NUMPY_DTYPES[entry["dtype"]]
        begin, end = entry["data_offsets"]
        count = int(np.prod(entry["shape"], dtype=np.int64))
        if not 0 <= begin <= end <= len(data) or end - begin != count * dtype.itemsize:
            raise ConversionError(f"{path}: tensor '{name}' has bad data_offsets {entry['data_offsets']}")
        tensors[name] = np.frombuffer(data[begin:end], dtype=dtype).reshape(entry["shape"]).copy()
    return tensors, config


# --------------------------------------------------------------------------
# Expected state_dict layout of each family
# --------------------------------------------------------------------------

def _batch_norm(shapes, prefix, channels):
    # num_batches_tracked is deliberately absent: it only matters for training.
    for suffix in ("weight", "bias", "running_mean", "running_var"):
        shapes[prefix + suffix] = (channels,)


def _pix2pix_shapes(input_nc, output_nc, ngf, num_downs):
    """Tensor name -> shape of junyanz's UnetGenerator with norm='batch', in state_dict order.

    Each UnetSkipConnectionBlock is an nn.Sequential called `model`, and a
    block's submodule sits at index 1 (outermost) or 3 (others) of it, hence
    names like model.model.1.model.3.model.1.weight.
    """
    # (outer_nc, inner_nc) of each block, outermost first.
    levels = [(output_nc, ngf), (ngf, ngf * 2), (ngf * 2, ngf * 4), (ngf * 4, ngf * 8)]
    levels += [(ngf * 8, ngf * 8)] * (num_downs - 4)
    innermost = num_downs - 1
    shapes = {}

    def block(level, prefix):
        outer, inner = levels[level]
        # ConvTranspose2d weights are (in, out, kh, kw); Conv2d are (out, in, kh, kw).
        if level == 0:
            # [downconv, submodule, uprelu, upconv, tanh]; the downconv has no
            # bias (use_bias is False for BatchNorm), the upconv keeps its default bias.
            shapes[prefix + "0.weight"] = (inner, input_nc, 4, 4)
            block(1, prefix + "1.model.")
            shapes[prefix + "3.weight"] = (inner * 2, outer, 4, 4)
            shapes[prefix + "3.bias"] = (outer,)
        elif level == innermost:
            # [downrelu, downconv, uprelu, upconv, upnorm]: no down-norm.
            shapes[prefix + "1.weight"] = (inner, outer, 4, 4)
            shapes[prefix + "3.weight"] = (inner, outer, 4, 4)
            _batch_norm(shapes, prefix + "4.", outer)
        else:
            # [downrelu, downconv, downnorm, submodule, uprelu, upconv, upnorm(, dropout)]
            shapes[prefix + "1.weight"] = (inner, outer, 4, 4)
            _batch_norm(shapes, prefix + "2.", inner)
            block(level + 1, prefix + "3.model.")
            shapes[prefix + "5.weight"] = (inner * 2, outer, 4, 4)
            _batch_norm(shapes, prefix + "6.", outer)

    block(0, "model.model.")
    return shapes


def _deepillumination_shapes(input_nc, output_nc, ngf):
    """Tensor name -> shape of DeepIllumination's G, in state_dict order."""
    encoder_nc = [input_nc, ngf, ngf * 2, ngf * 4] + [ngf * 8] * 5
    decoder_nc = [ngf * 8] * 4 + [ngf * 4, ngf * 2, ngf, output_nc]
    shapes = {}
    for k in range(1, 9):
        shapes[f"conv{k}.weight"] = (encoder_nc[k], encoder_nc[k - 1], 4, 4)
        shapes[f"conv{k}.bias"] = (encoder_nc[k],)
    for k in range(1, 9):
        # Decoder k > 1 reads cat(decoder k-1, its encoder skip): twice the channels.
        in_nc = ngf * 8 if k == 1 else 2 * decoder_nc[k - 2]
        shapes[f"deconv{k}.weight"] = (in_nc, decoder_nc[k - 1], 4, 4)
        shapes[f"deconv{k}.bias"] = (decoder_nc[k - 1],)
    for name, channels in (("batch_norm", ngf), ("batch_norm2", ngf * 2),
                           ("batch_norm4", ngf * 4), ("batch_norm8", ngf * 8)):
        _batch_norm(shapes, name + ".", channels)
    return shapes


def expected_shapes(config):
    """Tensor name -> shape that `config` requires, in upstream state_dict order."""
    if config["family"] == "pix2pix_unet":
        return _pix2pix_shapes(config["input_nc"], config["output_nc"], config["ngf"], config["num_downs"])
    return _deepillumination_shapes(config["input_nc"], config["output_nc"], config["ngf"])


# --------------------------------------------------------------------------
# Config
# --------------------------------------------------------------------------

def make_config(family, *, bn_mode, input_nc=12, output_nc=3, ngf=64, num_downs=8,
                dropout="off", dropout_seed=0, input_layout=(), source=""):
    """Validate the options and return the complete ngi config dict."""
    if family not in FAMILIES:
        raise ConversionError(f"family must be one of {FAMILIES}, got {family!r}")
    if bn_mode not in BN_MODES:
        raise ConversionError(f"bn_mode must be one of {BN_MODES}, got {bn_mode!r}")
    if dropout not in DROPOUT_MODES:
        raise ConversionError(f"dropout must be one of {DROPOUT_MODES}, got {dropout!r}")
    for name, value in (("input_nc", input_nc), ("output_nc", output_nc), ("ngf", ngf)):
        if not isinstance(value, int) or value < 1:
            raise ConversionError(f"{name} must be a positive integer, got {value!r}")
    if family == "deepillumination" and num_downs != 8:
        raise ConversionError(f"deepillumination has exactly 8 downsamplings, got num_downs={num_downs}")
    if family == "pix2pix_unet" and (not isinstance(num_downs, int) or num_downs < 5):
        # junyanz's UnetGenerator hard-wires four outer blocks plus an innermost one.
        raise ConversionError(f"pix2pix_unet needs num_downs >= 5, got {num_downs!r}")
    if not isinstance(dropout_seed, int) or not 0 <= dropout_seed < 2 ** 32:
        raise ConversionError(f"dropout_seed must be a uint32, got {dropout_seed!r}")
    input_layout = list(input_layout)
    if input_layout and len(input_layout) != input_nc:
        raise ConversionError(f"input_layout names {len(input_layout)} channels but input_nc is {input_nc}")
    return {
        "format_version": FORMAT_VERSION,
        "family": family,
        "input_nc": input_nc,
        "output_nc": output_nc,
        "ngf": ngf,
        "num_downs": num_downs,
        "norm": "batch",
        "bn_mode": bn_mode,
        "bn_eps": BN_EPS,
        "dropout": dropout,
        "dropout_p": DROPOUT_P,
        "dropout_seed": dropout_seed,
        "leaky_slope": LEAKY_SLOPE,
        "input_layout": input_layout,
        "input_range": VALUE_RANGE,
        "output_range": VALUE_RANGE,
        "source": source,
    }


# --------------------------------------------------------------------------
# Checkpoint loading and validation
# --------------------------------------------------------------------------

def _torch_load(pth_path):
    """torch.load on the CPU, refusing arbitrary pickled code wherever torch can."""
    if "weights_only" not in inspect.signature(torch.load).parameters:
        # torch < 1.13 has no safe loader at all.
        print("ngi_convert: warning: this torch cannot load without unpickling arbitrary code; "
              "only convert checkpoints you trust", file=sys.stderr)
        return torch.load(pth_path, map_location="cpu")
    try:
        return torch.load(pth_path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as error:
        # torch 1.x's weights_only unpickler rejects plain floats (pytorch
        # issue 94670, fixed in 2.0), and DeepIllumination checkpoints hold
        # the optimizer's lr and betas. torch >= 2 rejecting a file means it
        # holds more than weights: refuse it.
        if int(torch.__version__.split(".")[0]) >= 2:
            raise ConversionError(f"{pth_path}: refused by torch.load(weights_only=True): {error}") from None
        print(f"ngi_convert: warning: torch {torch.__version__} cannot load {pth_path} with weights_only=True; "
              "loading it with full unpickling - only convert checkpoints you trust", file=sys.stderr)
        return torch.load(pth_path, map_location="cpu", weights_only=False)


def load_state_dict(pth_path):
    """Load a generator state_dict from either upstream checkpoint layout.

    Returns (state_dict, description of the layout found).
    """
    checkpoint = _torch_load(pth_path)
    if not isinstance(checkpoint, dict):
        raise ConversionError(
            f"{pth_path}: expected a state_dict or a DeepIllumination checkpoint dict, "
            f"got {type(checkpoint).__name__}")
    if "state_dict_G" in checkpoint:
        return checkpoint["state_dict_G"], f"DeepIllumination checkpoint, epoch {checkpoint.get('epoch', '?')}"
    return checkpoint, "state_dict"


def _format_names(names):
    return "".join(f"\n    {name}" for name in names)


def validate_state_dict(state_dict, config):
    """Check `state_dict` against `config`; return name -> float32 np.ndarray in canonical order.

    Drops num_batches_tracked and a DataParallel `module.` prefix. Every
    problem found is reported at once, by tensor name.
    """
    tensors = {}
    for key, value in state_dict.items():
        if not isinstance(value, torch.Tensor):
            raise ConversionError(f"entry '{key}' is a {type(value).__name__}, not a tensor; "
                                  "is this a generator state_dict?")
        name = key[len("module."):] if key.startswith("module.") else key
        if name.endswith("num_batches_tracked"):
            continue
        tensors[name] = value

    shapes = expected_shapes(config)
    missing = [name for name in shapes if name not in tensors]
    unexpected = [name for name in tensors if name not in shapes]
    problems = []
    if missing:
        problems.append(f"missing {len(missing)} tensor(s):{_format_names(missing)}")
    if unexpected:
        problems.append(f"unexpected {len(unexpected)} tensor(s):{_format_names(unexpected)}")
    for name, shape in shapes.items():
        if name in tensors and tuple(tensors[name].shape) != shape:
            problems.append(f"tensor '{name}' has shape {tuple(tensors[name].shape)}, expected {shape}")
    if missing and len(missing) == len(shapes):
        problems.append("none of the expected tensors is present: wrong --family?")
    if problems:
        arch = (f"{config['family']} input_nc={config['input_nc']} output_nc={config['output_nc']} "
                f"ngf={config['ngf']} num_downs={config['num_downs']}")
        raise ConversionError(f"checkpoint does not match {arch}:\n  " + "\n  ".join(problems))

    result = {}
    for name in shapes:
        tensor = tensors[name]
        if not tensor.is_floating_point():
            raise ConversionError(f"tensor '{name}' has dtype {tensor.dtype}, expected a floating-point type")
        array = tensor.detach().to(torch.float32).numpy()
        bad = np.count_nonzero(~np.isfinite(array))
        if bad:
            raise ConversionError(f"tensor '{name}' has {bad} non-finite value(s) (NaN or Inf)")
        result[name] = array
    return result


def convert_checkpoint(pth_path, out_path, family, *, half=False, **options):
    """Convert `pth_path` to the ngi model file `out_path`; returns the config written.

    `options` are make_config's keyword arguments (bn_mode is required).
    """
    state_dict, layout = load_state_dict(pth_path)
    options.setdefault("source", f"{os.path.basename(pth_path)} ({layout}), converted by ngi_convert.py")
    config = make_config(family, **options)
    tensors = validate_state_dict(state_dict, config)
    write_model(out_path, tensors, config, half=half)
    return config


def main(argv=None):
    parser = argparse.ArgumentParser(description="Convert a PyTorch generator checkpoint to an ngi model file.")
    parser.add_argument("input", help="checkpoint: junyanz <epoch>_net_G.pth or DeepIllumination netG_model_epoch_<n>.pth")
    parser.add_argument("output", help="ngi model file to write (.safetensors)")
    parser.add_argument("--family", required=True, choices=FAMILIES)
    parser.add_argument("--bn-mode", required=True, choices=BN_MODES,
                        help="running: eval-mode BatchNorm; per_image: each image normalized by its own "
                             "statistics, as pix2pix's test.py (no --eval) and DeepIllumination's test.py run it")
    parser.add_argument("--input-nc", type=int, default=12)
    parser.add_argument("--output-nc", type=int, default=3)
    parser.add_argument("--ngf", type=int, default=64)
    parser.add_argument("--num-downs", type=int, default=8)
    parser.add_argument("--dropout", choices=DROPOUT_MODES, default="off")
    parser.add_argument("--dropout-seed", type=int, default=0)
    parser.add_argument("--input-layout", default="",
                        help="comma-separated input channel names, e.g. albedo.r,albedo.g,...")
    parser.add_argument("--source", help="free text stored in the config (default: input file name)")
    parser.add_argument("--half", action="store_true", help="store tensors as F16 instead of F32")
    args = parser.parse_args(argv)

    options = {"bn_mode": args.bn_mode, "input_nc": args.input_nc, "output_nc": args.output_nc,
               "ngf": args.ngf, "num_downs": args.num_downs, "dropout": args.dropout,
               "dropout_seed": args.dropout_seed,
               "input_layout": [name for name in args.input_layout.split(",") if name]}
    if args.source is not None:
        options["source"] = args.source
    try:
        config = convert_checkpoint(args.input, args.output, args.family, half=args.half, **options)
    except ConversionError as error:
        print(f"ngi_convert: error: {error}", file=sys.stderr)
        return 1
    print(f"ngi_convert: wrote {args.output} ({config['family']}, bn_mode={config['bn_mode']}, "
          f"dropout={config['dropout']}, {'F16' if args.half else 'F32'}, "
          f"{os.path.getsize(args.output)} bytes)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Convert a PyTorch generator checkpoint into an ngi model file (.safetensors).

The file format (ngi.model_file, docs/MODEL_FORMAT.md) is written without the
`safetensors` package. Two generator families are understood, each from the
checkpoint layout its upstream training code writes:
  * pix2pix_unet     - junyanz/pytorch-CycleGAN-and-pix2pix UnetGenerator,
                       `<epoch>_net_G.pth` = torch.save(net.state_dict())
  * deepillumination - CreativeCodingLab/DeepIllumination G,
                       `netG_model_epoch_<n>.pth` =
                       torch.save({'epoch', 'state_dict_G', 'optimizer_G'})

An ONNX file (model.onnx, e.g. from torch.onnx.export) becomes a model of
family "graph" instead (ngi.onnx_import; needs Debian's python3-onnx):
  /usr/bin/python3 -m ngi.convert model.onnx OUT.safetensors [--half]

Usage (with <build>/python on PYTHONPATH):
  /usr/bin/python3 -m ngi.convert IN.pth OUT.safetensors \\
      --family pix2pix_unet --bn-mode per_image [--input-nc 12 --output-nc 3 \\
      --ngf 64 --num-downs 8] [--dropout off|seeded --dropout-seed S] [--output-mode lightmap|indirect] [--half]
"""

import argparse
import inspect
import math
import os
import pickle
import stat
import sys

import numpy as np

from .model_file import (BN_MODES, DROPOUT_MODES, FAMILIES, OUTPUT_MODES, ConversionError, check_input_file,
                         check_output_file, expected_shapes, make_config, write_model)

# --------------------------------------------------------------------------
# Checkpoint loading and validation
# --------------------------------------------------------------------------

def _torch_load(pth_path):
    """torch.load on the CPU, refusing arbitrary pickled code wherever torch can."""
    check_input_file(pth_path)  # before torch opens it: a FIFO would block, /dev/zero fill the memory
    import torch  # noqa: PLC0415 (imported where needed: the ONNX path does not need torch)

    def load(**kwargs):
        try:
            return torch.load(pth_path, map_location="cpu", **kwargs)
        except Exception as error:  # noqa: BLE001 (zipfile's, pickle's and torch's errors on a file that is not one)
            if isinstance(error, pickle.UnpicklingError) and kwargs.get("weights_only"):
                raise  # the safe loader's refusal: decided below
            first_line = (str(error).splitlines() or [type(error).__name__])[0]
            raise ConversionError(f"{pth_path} is not a readable PyTorch checkpoint (truncated or corrupt?): "
                                  f"{first_line}") from None

    if "weights_only" not in inspect.signature(torch.load).parameters:
        # torch < 1.13 has no safe loader at all.
        print("ngi.convert: warning: this torch cannot load without unpickling arbitrary code; "
              "only convert checkpoints you trust", file=sys.stderr)
        return load()
    try:
        return load(weights_only=True)
    except pickle.UnpicklingError as error:
        # torch 1.x's weights_only unpickler rejects plain floats (pytorch
        # issue 94670, fixed in 2.0), and DeepIllumination checkpoints hold
        # the optimizer's lr and betas. torch >= 2 rejecting a file means it
        # holds more than weights: refuse it.
        if int(torch.__version__.split(".")[0]) >= 2:
            raise ConversionError(f"{pth_path}: refused by torch.load(weights_only=True): {error}") from None
        print(f"ngi.convert: warning: torch {torch.__version__} cannot load {pth_path} with weights_only=True; "
              "loading it with full unpickling - only convert checkpoints you trust", file=sys.stderr)
        return load(weights_only=False)


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
    import torch  # noqa: PLC0415

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
    check_output_file(out_path)  # before the work; write_model checks it again
    state_dict, layout = load_state_dict(pth_path)
    options.setdefault("source", f"{os.path.basename(pth_path)} ({layout}), converted by ngi.convert")
    config = make_config(family, **options)
    tensors = validate_state_dict(state_dict, config)
    write_model(out_path, tensors, config, half=half)
    return config


def _is_onnx(path):
    """An .onnx name, or a file that is not a PyTorch checkpoint (zip or pickle) but starts like ONNX's protobuf."""
    if path.lower().endswith(".onnx"):
        return True
    try:
        # Only a regular file is opened here (a FIFO would block); anything else goes on to the checkpoint path,
        # whose file check names it.
        if not stat.S_ISREG(os.stat(path).st_mode):
            return False
        with open(path, "rb") as f:
            head = f.read(2)
    except OSError:
        return False
    return head[:1] == b"\x08" and head != b"PK"  # field 1 (ir_version), varint: every ONNX ModelProto's start


def _float_pair(text):
    """'LO,HI' -> (lo, hi): two finite float32 numbers with lo < hi (argparse type)."""
    parts = text.split(",")
    try:
        lo, hi = (float(v) for v in parts) if len(parts) == 2 else (None, None)
    except ValueError:
        lo = hi = None
    if lo is None or not (math.isfinite(lo) and math.isfinite(hi) and abs(lo) <= 3.4e38 and abs(hi) <= 3.4e38
                          and lo < hi):
        raise argparse.ArgumentTypeError(f"'{text}' is not LO,HI with finite LO < HI")
    return lo, hi


def onnx_main(argv):
    parser = argparse.ArgumentParser(prog="python3 -m ngi.convert",
                                     description="Import an ONNX model as an ngi model file (family \"graph\"; "
                                                 "docs/MODEL_FORMAT.md). Needs python3-onnx.")
    parser.add_argument("input", help="ONNX file, e.g. from torch.onnx.export (eval mode, fixed input shape)")
    parser.add_argument("output", help="ngi model file to write (.safetensors)")
    parser.add_argument("--source", help="free text stored in the config (default: input file name)")
    parser.add_argument("--half", action="store_true", help="store tensors as F16 instead of F32")
    parser.add_argument("--input-range", metavar="LO,HI", type=_float_pair,
                        help="the value range the network's inputs were trained in (the surround pipeline scales its "
                             "features into it; without one the model runs on tensors only: Model.run, ngi generate)")
    args = parser.parse_args(argv)
    from .onnx_import import import_onnx  # noqa: PLC0415 (the onnx package is needed on this path only)
    try:
        config = import_onnx(args.input, args.output, half=args.half, source=args.source,
                             input_range=args.input_range)
    except ConversionError as error:
        print(f"ngi.convert: error: {error}", file=sys.stderr)
        return 1
    graph = config["graph"]
    print(f"ngi.convert: wrote {args.output} (graph, {len(graph['nodes'])} nodes from {config['onnx']['nodes']} "
          f"ONNX nodes, layout {graph['layout']}, {config['input_nc']} -> {config['output_nc']} channels, "
          f"{'F16' if args.half else 'F32'}, {os.path.getsize(args.output)} bytes)", file=sys.stderr)
    return 0


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    positional = [a for a in argv if not a.startswith("-")]
    if positional and _is_onnx(positional[0]):
        return onnx_main(argv)
    parser = argparse.ArgumentParser(prog="python3 -m ngi.convert",
                                     description="Convert a PyTorch generator checkpoint to an ngi model file.")
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
    parser.add_argument("--output-mode", choices=OUTPUT_MODES, default="lightmap",
                        help="what the generator was trained to predict: lightmap (the front view's direct + "
                             "indirect light, the thesis's) or indirect (indirect light only; the pipeline adds the "
                             "frame's direct light); pix2pix_unet only")
    parser.add_argument("--source", help="free text stored in the config (default: input file name)")
    parser.add_argument("--half", action="store_true", help="store tensors as F16 instead of F32")
    args = parser.parse_args(argv)

    options = {"bn_mode": args.bn_mode, "input_nc": args.input_nc, "output_nc": args.output_nc,
               "ngf": args.ngf, "num_downs": args.num_downs, "dropout": args.dropout,
               "dropout_seed": args.dropout_seed, "output_mode": args.output_mode,
               "input_layout": [name for name in args.input_layout.split(",") if name]}
    if args.source is not None:
        options["source"] = args.source
    try:
        config = convert_checkpoint(args.input, args.output, args.family, half=args.half, **options)
    except ConversionError as error:
        print(f"ngi.convert: error: {error}", file=sys.stderr)
        return 1
    print(f"ngi.convert: wrote {args.output} ({config['family']}, bn_mode={config['bn_mode']}, "
          f"dropout={config['dropout']}, output_mode={config['output_mode']}, {'F16' if args.half else 'F32'}, "
          f"{os.path.getsize(args.output)} bytes)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

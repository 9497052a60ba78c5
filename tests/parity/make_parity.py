#!/usr/bin/python3
"""Generate the PyTorch parity data that ngi's C++ parity test compares against.

For each case: build a small generator with random weights, save it as the
upstream training code would (.pth), convert it with ngi.convert,
check the converted file holds exactly the model's weights, and run the
reference forward pass on a random input.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 tests/parity/make_parity.py --out DIR
Writes DIR/<case>.safetensors, DIR/<case>_input.npy, DIR/<case>_expected.npy
and DIR/cases.json. Deterministic: the same torch/numpy give identical bytes.
"""

import argparse
import json
import math
import os
import tempfile
import time

import numpy as np
import torch

import ngi.convert as convert
import ngi.model_file as model_file
import ngi.reference_models as reference_models

HERE = os.path.dirname(os.path.abspath(__file__))

# Small architectures: the C++ test runs every case on a 2-core CPU OpenCL device.
ARCHITECTURES = {
    "pix2pix_unet": {"input_nc": 12, "output_nc": 3, "ngf": 8, "num_downs": 6, "height": 64, "width": 128},
    "deepillumination": {"input_nc": 12, "output_nc": 3, "ngf": 8, "num_downs": 8, "height": 256, "width": 256},
    # The shipped surround model's architecture at its real size: channel counts (K up to 4096) where a driver
    # bug hidden by ngf 8 shows (issue 13: rusticl was off by 0.25 here while every ngf 8 case agreed).
    "pix2pix_ngf32": {"family": "pix2pix_unet", "input_nc": 12, "output_nc": 3, "ngf": 32, "num_downs": 7,
                      "height": 128, "width": 256},
}

CASES = [
    {"name": "pix2pix_running", "family": "pix2pix_unet", "bn_mode": "running", "dropout": "off",
     "dropout_seed": 0, "half": False, "seed": 1},
    {"name": "pix2pix_per_image", "family": "pix2pix_unet", "bn_mode": "per_image", "dropout": "off",
     "dropout_seed": 0, "half": False, "seed": 2},
    {"name": "pix2pix_per_image_dropout", "family": "pix2pix_unet", "bn_mode": "per_image", "dropout": "seeded",
     "dropout_seed": 1234, "half": False, "seed": 3},
    {"name": "pix2pix_fp16", "family": "pix2pix_unet", "bn_mode": "running", "dropout": "off",
     "dropout_seed": 0, "half": True, "seed": 4},
    {"name": "deepillumination_running", "family": "deepillumination", "bn_mode": "running", "dropout": "off",
     "dropout_seed": 0, "half": False, "seed": 5},
    {"name": "deepillumination_per_image", "family": "deepillumination", "bn_mode": "per_image",
     "dropout": "seeded", "dropout_seed": 7, "half": False, "seed": 6},
    {"name": "pix2pix_ngf32_per_image", "family": "pix2pix_unet", "arch": "pix2pix_ngf32", "bn_mode": "per_image",
     "dropout": "off", "dropout_seed": 0, "half": True, "seed": 8},
]

# The shipped models themselves (models/*.safetensors, trained weights): PyTorch runs the file's weights.
SHIPPED = [
    {"name": "shipped_surround", "file": "models/surround.safetensors", "height": 128, "width": 256, "seed": 9},
    {"name": "shipped_single_view", "file": "models/single_view.safetensors", "height": 64, "width": 64, "seed": 10},
]
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


def randomize_weights(model, generator):
    """Random weights that keep activations O(1) through the whole network.

    Fixed-std weights would make deep activations explode or vanish in
    running mode (nothing renormalizes them), leaving an all-saturated or
    all-zero output that tests nothing. He-style scaling by the number of
    inputs that reach one output avoids that: k*k*C_in for a 4x4 stride-2
    conv, but only (k/stride)^2*C_in = 4*C_in for the transposed conv.
    """
    def normal(tensor, std):
        tensor.copy_(torch.randn(tensor.shape, generator=generator) * std)

    def uniform(tensor, low, high):
        tensor.copy_(low + (high - low) * torch.rand(tensor.shape, generator=generator))

    with torch.no_grad():
        for module in model.modules():
            if isinstance(module, torch.nn.ConvTranspose2d):
                normal(module.weight, math.sqrt(2.0 / (module.weight.shape[0] * 4)))
            elif isinstance(module, torch.nn.Conv2d):
                normal(module.weight, math.sqrt(2.0 / module.weight[0].numel()))
            elif isinstance(module, torch.nn.BatchNorm2d):
                uniform(module.weight, 0.5, 1.5)
                normal(module.bias, 0.2)
                normal(module.running_mean, 0.2)
                uniform(module.running_var, 0.5, 2.0)
                continue
            else:
                continue
            if module.bias is not None:
                normal(module.bias, 0.1)


def round_to_half(model):
    """Round every float tensor to the nearest float16, as an F16 model file stores it."""
    with torch.no_grad():
        for tensor in model.state_dict().values():
            if tensor.is_floating_point():
                tensor.copy_(tensor.half().float())


def save_upstream_checkpoint(model, family, directory):
    """torch.save the model the way its upstream training code does; returns the path."""
    if family == "pix2pix_unet":
        # junyanz BaseModel.save_networks: torch.save(net.state_dict(), '<epoch>_net_G.pth')
        path = os.path.join(directory, "latest_net_G.pth")
        torch.save(model.state_dict(), path)
    else:
        # DeepIllumination train.py save_checkpoint
        path = os.path.join(directory, "netG_model_epoch_1.pth")
        optimizer = torch.optim.Adam(model.parameters(), lr=0.0002, betas=(0.5, 0.999))
        torch.save({"epoch": 1, "state_dict_G": model.state_dict(), "optimizer_G": optimizer.state_dict()}, path)
    return path


def check_converted(path, model, case, arch):
    """The converted file must hold the model's weights bit for bit (as F16 when half)."""
    tensors, config = model_file.read_model(path)
    expected = {name: value.numpy() for name, value in model.state_dict().items()
                if not name.endswith("num_batches_tracked")}
    if list(tensors) != list(expected):
        raise AssertionError(f"{case['name']}: converted tensor names differ from the state_dict")
    for name, array in tensors.items():
        if array.dtype != (np.float16 if case["half"] else np.float32):
            raise AssertionError(f"{case['name']}: '{name}' stored as {array.dtype}")
        if not np.array_equal(array.astype(np.float32), expected[name]):
            raise AssertionError(f"{case['name']}: '{name}' changed in conversion")
    for key in ("family", "bn_mode", "dropout", "dropout_seed", "input_nc", "output_nc", "ngf", "num_downs"):
        if config[key] != {**case, **arch}[key]:
            raise AssertionError(f"{case['name']}: config {key} = {config[key]!r}")


def make_case(case, out_dir, work_dir):
    arch = dict(ARCHITECTURES[case.get("arch", case["family"])])
    arch.pop("family", None)
    generator = torch.Generator().manual_seed(case["seed"])
    model = reference_models.build_generator(case["family"], arch["input_nc"], arch["output_nc"], arch["ngf"],
                                             arch["num_downs"], case["dropout"], case["dropout_seed"])
    randomize_weights(model, generator)
    if case["half"]:
        # The expected output then uses exactly the weights the F16 file holds,
        # so the comparison can stay as tight as for F32 files.
        round_to_half(model)

    checkpoint = save_upstream_checkpoint(model, case["family"], work_dir)
    model_name = f"{case['name']}.safetensors"
    argv = [checkpoint, os.path.join(out_dir, model_name), "--family", case["family"],
            "--bn-mode", case["bn_mode"], "--input-nc", str(arch["input_nc"]),
            "--output-nc", str(arch["output_nc"]), "--ngf", str(arch["ngf"]),
            "--num-downs", str(arch["num_downs"]), "--dropout", case["dropout"],
            "--dropout-seed", str(case["dropout_seed"]), "--source", f"tests/parity/make_parity.py {case['name']}"]
    if case["half"]:
        argv.append("--half")
    if convert.main(argv) != 0:
        raise RuntimeError(f"{case['name']}: conversion failed")
    check_converted(os.path.join(out_dir, model_name), model, case, arch)

    shape = (1, arch["input_nc"], arch["height"], arch["width"])
    x = torch.rand(shape, generator=generator) * 2 - 1
    # float64 forward: the expected values carry no float32 rounding noise of
    # their own, so the C++ result is compared against the exact answer.
    y = reference_models.run_reference(model, x, case["bn_mode"]).to(torch.float32)

    input_file, expected_file = f"{case['name']}_input.npy", f"{case['name']}_expected.npy"
    np.save(os.path.join(out_dir, input_file), x.numpy())
    np.save(os.path.join(out_dir, expected_file), y.numpy())

    values = y.abs()
    print(f"{case['name']:28s} output {tuple(y.shape)}  max|y| {values.max().item():.4f}  "
          f"mean|y| {values.mean().item():.4f}  |y|>0.99: {int((values > 0.99).sum())}/{y.numel()}")
    return {"name": case["name"], "model": model_name, "input": input_file, "expected": expected_file,
            "family": case["family"], "bn_mode": case["bn_mode"], "dropout": case["dropout"],
            "dtype": "F16" if case["half"] else "F32"}


def make_shipped_case(case, out_dir):
    """PyTorch's float64 output of a shipped model file on a random input of the size it was trained at."""
    path = os.path.join(REPO, case["file"])
    tensors, config = model_file.read_model(path)
    model = reference_models.load_generator(tensors, config)
    generator = torch.Generator().manual_seed(case["seed"])
    x = torch.rand((1, config["input_nc"], case["height"], case["width"]), generator=generator) * 2 - 1
    y = reference_models.run_reference(model, x, config["bn_mode"]).to(torch.float32)
    input_file, expected_file = f"{case['name']}_input.npy", f"{case['name']}_expected.npy"
    np.save(os.path.join(out_dir, input_file), x.numpy())
    np.save(os.path.join(out_dir, expected_file), y.numpy())
    print(f"{case['name']:28s} output {tuple(y.shape)}  max|y| {y.abs().max().item():.4f}")
    return {"name": case["name"], "model": path, "input": input_file, "expected": expected_file,
            "family": config["family"], "bn_mode": config["bn_mode"], "dropout": config["dropout"], "dtype": "F16"}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="directory to write the parity data into")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as work_dir:
        cases = [make_case(case, args.out, work_dir) for case in CASES]
    cases += [make_shipped_case(case, args.out) for case in SHIPPED]
    with open(os.path.join(args.out, "cases.json"), "w") as f:
        json.dump(cases, f, indent=2)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {args.out} in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()

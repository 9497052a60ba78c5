#!/usr/bin/python3
"""Generate PyTorch parity data for ngi's "pixel_cnn" model family (docs/MODEL_FORMAT.md "pixel_cnn").

For each case: a stack of torch.nn.Conv2d layers (odd kernels, padding k // 2, bias or not) with activations and
random weights, saved as an ngi model file, and its float64 output on a random [1, C, H, W] input.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 tests/parity/make_pixel_cnn_parity.py --out DIR
Writes DIR/<case>.safetensors, DIR/<case>_input.npy, DIR/<case>_expected.npy and DIR/cases.json. Deterministic.
"""

import argparse
import json
import os

import numpy as np
import torch

import ngi.model_file as model_file

# (out, kernel, activation, bias): a 1 x 1 head, 3 x 3 and 5 x 5 bodies, odd sizes, a leaky slope, F16 weights.
CASES = [
    {"name": "per_pixel", "inputs": 12, "layers": [(16, 1, "relu", True), (3, 1, "tanh", True)],
     "h": 9, "w": 13, "half": False, "seed": 1},
    {"name": "spatial", "inputs": 5, "layers": [(7, 3, "leaky_relu", True), (9, 5, "sigmoid", False),
                                                 (2, 3, "none", True)], "h": 17, "w": 11, "half": False, "seed": 2},
    {"name": "spatial_fp16", "inputs": 3, "layers": [(8, 3, "relu", False), (8, 3, "relu", True),
                                                      (3, 1, "none", True)], "h": 32, "w": 24, "half": True, "seed": 3},
    {"name": "one_pixel", "inputs": 1, "layers": [(3, 5, "tanh", True)], "h": 1, "w": 1, "half": False, "seed": 4},
]
SLOPE = 0.15
ACTIVATIONS = {"none": lambda x: x, "relu": torch.relu, "tanh": torch.tanh, "sigmoid": torch.sigmoid,
               "leaky_relu": lambda x: torch.nn.functional.leaky_relu(x, SLOPE)}


def make_case(case, out_dir):
    torch.manual_seed(case["seed"])
    tensors, layers, modules = {}, [], []
    in_c = case["inputs"]
    for i, (out_c, k, act, bias) in enumerate(case["layers"]):
        conv = torch.nn.Conv2d(in_c, out_c, k, padding=k // 2, bias=bias).double()
        with torch.no_grad():
            if case["half"]:  # the file stores F16: the reference uses exactly the stored values
                conv.weight.copy_(conv.weight.half().double())
                if bias:
                    conv.bias.copy_(conv.bias.half().double())
        tensors[f"layers.{i}.weight"] = conv.weight.detach().float().numpy()
        if bias:
            tensors[f"layers.{i}.bias"] = conv.bias.detach().float().numpy()
        layer = {"out": out_c, "kernel": k, "activation": act}
        if act == "leaky_relu":
            layer["slope"] = SLOPE
        layers.append(layer)
        modules.append((conv, ACTIVATIONS[act]))
        in_c = out_c
    config = {"format_version": 1, "family": "pixel_cnn", "input_nc": case["inputs"], "output_nc": in_c,
              "layers": layers, "source": f"tests/parity/make_pixel_cnn_parity.py {case['name']}"}
    model_name = f"{case['name']}.safetensors"
    model_file.write_model(os.path.join(out_dir, model_name), tensors, config, half=case["half"])

    x = torch.rand((1, case["inputs"], case["h"], case["w"])) * 2 - 1
    y = x.double()
    with torch.no_grad():
        for conv, act in modules:
            y = act(conv(y))
    input_file, expected_file = f"{case['name']}_input.npy", f"{case['name']}_expected.npy"
    np.save(os.path.join(out_dir, input_file), x.numpy())
    np.save(os.path.join(out_dir, expected_file), y.float().numpy())
    print(f"{case['name']:14s} input {tuple(x.shape)} output {tuple(y.shape)} max|y| {y.abs().max().item():.4f}")
    return {"name": case["name"], "model": model_name, "input": input_file, "expected": expected_file,
            "dtype": "F16" if case["half"] else "F32"}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    cases = [make_case(c, args.out) for c in CASES]
    with open(os.path.join(args.out, "cases.json"), "w") as f:
        json.dump(cases, f, indent=2)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {args.out}")


if __name__ == "__main__":
    main()

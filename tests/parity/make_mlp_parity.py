#!/usr/bin/python3
"""Generate PyTorch parity data for ngi's "mlp" model family (docs/MODEL_FORMAT.md).

For each case: an MLP with random weights, saved as an ngi model file, and its
float64 output on a random input (per-pixel NCHW images and [N, C] point lists),
computed by ngi.reference_models.run_mlp_reference (the frequency encoding written
from its definition in docs/CONVENTIONS.md section 13, linear layers, activations);
and every shipped AO model (models/ao_*.safetensors) as it is.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 tests/parity/make_mlp_parity.py --out DIR
Writes DIR/<case>.safetensors, DIR/<case>_input.npy, DIR/<case>_expected.npy
and DIR/cases.json. Deterministic.
"""

import argparse
import json
import math
import os

import numpy as np
import torch

import ngi.model_file as model_file
import ngi.reference_models as reference_models

HERE = os.path.dirname(os.path.abspath(__file__))

# seed 001's sizes (48 inputs, tanh), encodings in both orders, a width beyond the fused kernel (dense path).
CASES = [
    {"name": "ao_16x8", "inputs": 48, "layers": [(16, "tanh"), (8, "tanh"), (1, "none")], "encoding": None,
     "shape": "points", "n": 777, "half": False, "seed": 1},
    {"name": "ao_64x32_fp16", "inputs": 48, "layers": [(64, "tanh"), (32, "tanh"), (1, "none")], "encoding": None,
     "shape": "points", "n": 513, "half": True, "seed": 2},
    {"name": "band_encoded", "inputs": 5, "layers": [(24, "relu"), (17, "sigmoid"), (3, "exp")],
     "encoding": {"bands": 4, "first_exponent": -1, "pi": True, "include_input": True, "order": "band"},
     "shape": "image", "h": 9, "w": 13, "half": False, "seed": 3},
    {"name": "component_encoded_wide", "inputs": 3, "layers": [(200, "leaky_relu"), (129, "leaky_relu"), (4, "none")],
     "encoding": {"bands": 3, "first_exponent": 0, "pi": True, "include_input": False, "order": "component"},
     "shape": "image", "h": 8, "w": 8, "half": False, "seed": 4},
]


def make_case(case, out_dir):
    g = torch.Generator().manual_seed(case["seed"])
    enc = case["encoding"]
    width = case["inputs"] if not enc else (case["inputs"] if enc["include_input"] else 0) + 2 * enc["bands"] * case["inputs"]
    tensors, layers, weights = {}, [], {}
    in_f = width
    for i, (out_f, act) in enumerate(case["layers"]):
        bound = 1.0 / math.sqrt(in_f)  # nn.Linear's default init range
        w = (torch.rand((out_f, in_f), generator=g, dtype=torch.float64) * 2 - 1) * bound * 1.7
        b = (torch.rand((out_f,), generator=g, dtype=torch.float64) * 2 - 1) * bound
        if case["half"]:  # the file stores F16: the reference uses exactly the stored values
            w, b = w.half().double(), b.half().double()
        tensors[f"layers.{i}.weight"] = w.float().numpy()
        tensors[f"layers.{i}.bias"] = b.float().numpy()
        weights[f"layers.{i}.weight"], weights[f"layers.{i}.bias"] = w, b  # float64: the exact reference
        layer = {"out": out_f, "activation": act}
        if act == "leaky_relu":
            layer["slope"] = 0.1
        layers.append(layer)
        in_f = out_f
    config = {"format_version": 1, "family": "mlp", "input_nc": case["inputs"], "layers": layers,
              "source": f"tests/parity/make_mlp_parity.py {case['name']}"}
    if enc:
        config["encoding"] = enc
    model_name = f"{case['name']}.safetensors"
    model_file.write_model(os.path.join(out_dir, model_name), tensors, config, half=case["half"])

    if case["shape"] == "points":
        x = torch.rand((case["n"], case["inputs"]), generator=g) * 2 - 1
        items = x.double()
    else:
        x = torch.rand((1, case["inputs"], case["h"], case["w"]), generator=g) * 2 - 1
        items = x.double().reshape(case["inputs"], -1).t()
    h = reference_models.run_mlp_reference(weights, config, items)
    if case["shape"] == "points":
        y = h.float()
    else:
        y = h.t().reshape(1, -1, case["h"], case["w"]).float()
    input_file, expected_file = f"{case['name']}_input.npy", f"{case['name']}_expected.npy"
    np.save(os.path.join(out_dir, input_file), x.numpy())
    np.save(os.path.join(out_dir, expected_file), y.numpy())
    print(f"{case['name']:26s} input {tuple(x.shape)} output {tuple(y.shape)} max|y| {y.abs().max().item():.4f}")
    return {"name": case["name"], "model": model_name, "input": input_file, "expected": expected_file,
            "dtype": "F16" if case["half"] else "F32", "widest": max([width] + [o for o, _ in case["layers"]])}


def shipped_case(path, out_dir, seed):
    """A shipped model file (models/ao_*.safetensors) as it is: PyTorch float64 on its stored (F16) weights, input
    an [n, 48] list of random unit normals (16 per row, seed 001's input)."""
    tensors, config = model_file.read_model(path)
    name = "shipped_" + os.path.basename(path).replace(".safetensors", "")
    g = torch.Generator().manual_seed(seed)
    x = torch.randn((301, config["input_nc"] // 3, 3), generator=g, dtype=torch.float64)
    x = (x / x.norm(dim=2, keepdim=True)).reshape(301, -1).float()
    h = reference_models.run_mlp_reference(tensors, config, x)
    model_name = os.path.basename(path)
    with open(path, "rb") as src, open(os.path.join(out_dir, model_name), "wb") as dst:
        dst.write(src.read())
    np.save(os.path.join(out_dir, f"{name}_input.npy"), x.numpy())
    np.save(os.path.join(out_dir, f"{name}_expected.npy"), h.float().numpy())
    print(f"{name:26s} input {tuple(x.shape)} output {tuple(h.shape)}")
    return {"name": name, "model": model_name, "input": f"{name}_input.npy", "expected": f"{name}_expected.npy",
            "dtype": "F16", "widest": max([config["input_nc"]] + [l["out"] for l in config["layers"]])}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    cases = [make_case(c, args.out) for c in CASES]
    models = os.path.join(HERE, "..", "..", "models")
    for i, f in enumerate(sorted(f for f in os.listdir(models) if f.startswith("ao_") and f.endswith(".safetensors"))):
        cases.append(shipped_case(os.path.join(models, f), args.out, 100 + i))
    with open(os.path.join(args.out, "cases.json"), "w") as f:
        json.dump(cases, f, indent=2)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {args.out}")


if __name__ == "__main__":
    main()

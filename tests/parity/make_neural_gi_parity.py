#!/usr/bin/python3
"""Generate PyTorch parity data for ngi's "neural_gi" model family (seed 002, docs/MODEL_FORMAT.md).

For each case: an ngi.neural_gi.NeuralGI with random weights (He-scaled so that activations stay O(1) through the
U-Net and the 8-layer MLP and the exp-decoded output spans orders of magnitude), exported with
ngi.neural_gi.export_model, and its float64 output (indirect light) on inputs assembled by
ngi.neural_gi.assemble_inputs from random G-buffers. Batch norm: per-image statistics (train mode, batch 1) or the
running statistics (eval mode). F16 cases compute the reference from the F16-rounded weights the file stores.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 tests/parity/make_neural_gi_parity.py --out DIR
Writes DIR/<case>.safetensors, DIR/<case>_input.npy, DIR/<case>_expected.npy and DIR/cases.json. Deterministic.
"""

import argparse
import json
import math
import os

import numpy as np
import torch

import ngi.neural_gi as neural_gi

CASES = [
    # The paper's MLP (8 x 256, re-injection at layer 4) on a small U-Net, F16 weights as shipped models have.
    {"name": "paper_mlp_f16", "buffer_channels": 16, "ngf": 8, "num_downs": 5, "width": 256, "depth": 8, "skip": 4,
     "h": 32, "w": 64, "bn_mode": "per_image", "half": True, "seed": 1},
    # Narrow, odd widths (not tile multiples), F32, per-image statistics.
    {"name": "narrow_f32", "buffer_channels": 5, "ngf": 4, "num_downs": 5, "width": 37, "depth": 6, "skip": 3,
     "h": 32, "w": 32, "bn_mode": "per_image", "half": False, "seed": 2},
    # No re-injection, running statistics (BN folded into the convolutions), a 64 x 64 frame over 6 levels.
    {"name": "no_skip_running", "buffer_channels": 8, "ngf": 8, "num_downs": 6, "width": 48, "depth": 3,
     "skip": None, "h": 64, "w": 64, "bn_mode": "running", "half": False, "seed": 3},
]


def randomize(model, g):
    """He-scaled weights (a transposed 4 x 4 stride-2 convolution sums 4 taps per input channel); biases, batch-norm
    affine and running statistics away from the identity; the output layer scaled so that the MLP's raw output has
    a spread of ~1.5 (exp-decoded: light over a few orders of magnitude)."""
    def rand(shape, lo, hi):
        return torch.rand(shape, generator=g, dtype=torch.float64) * (hi - lo) + lo
    with torch.no_grad():
        for name, m in model.named_modules():
            if isinstance(m, torch.nn.Conv2d):
                fan_in = m.in_channels * m.kernel_size[0] * m.kernel_size[1]
                std = 1.5 / math.sqrt(m.in_channels) if name == "mlp.output" else math.sqrt(2.0 / fan_in)
            elif isinstance(m, torch.nn.ConvTranspose2d):
                std = math.sqrt(2.0 / (m.in_channels * 4))
            elif isinstance(m, torch.nn.BatchNorm2d):
                m.weight.copy_(rand(m.weight.shape, 0.5, 1.5))
                m.bias.copy_(rand(m.bias.shape, -0.1, 0.1))
                m.running_mean.copy_(torch.randn(m.running_mean.shape, generator=g, dtype=torch.float64) * 0.2)
                m.running_var.copy_(rand(m.running_var.shape, 0.5, 2.0))
                continue
            else:
                continue
            m.weight.copy_(torch.randn(m.weight.shape, generator=g, dtype=torch.float64) * std)
            if m.bias is not None:
                m.bias.copy_(rand(m.bias.shape, -0.1, 0.1))


def random_inputs(h, w, g):
    """Assembled inputs [1, 18, h, w] from random G-buffers (a scene box of 16 m, direct light up to ~50)."""
    def unit():
        v = torch.randn((1, 3, h, w), generator=g)
        return v / v.norm(dim=1, keepdim=True)
    position = torch.rand((1, 3, h, w), generator=g) * 16.0
    albedo = torch.rand((1, 3, h, w), generator=g)
    direct = torch.rand((1, 3, h, w), generator=g) ** 3 * 50.0
    return neural_gi.assemble_inputs(position, unit(), albedo, unit(), direct, unit(), [0, 0, 0], [16, 16, 16])


def make_case(case, out_dir):
    g = torch.Generator().manual_seed(case["seed"])
    torch.manual_seed(case["seed"])
    model = neural_gi.NeuralGI(case["buffer_channels"], case["ngf"], case["num_downs"], case["width"], case["depth"],
                               case["skip"])
    randomize(model, g)
    model_name = f"{case['name']}.safetensors"
    neural_gi.export_model(model, os.path.join(out_dir, model_name), bn_mode=case["bn_mode"], half=case["half"],
                           source=f"tests/parity/make_neural_gi_parity.py {case['name']}",
                           scene_box=((0, 0, 0), (16, 16, 16)))
    model = model.double()
    if case["half"]:  # the reference uses exactly the stored values
        with torch.no_grad():
            for t in list(model.parameters()) + list(model.buffers()):
                if t.is_floating_point():
                    t.copy_(t.half().double())
    model.train(case["bn_mode"] == "per_image")  # train mode, batch 1: per-image statistics (no dropout here)
    x = random_inputs(case["h"], case["w"], g)
    with torch.no_grad():
        y = model(x.double()).float()
    input_file, expected_file = f"{case['name']}_input.npy", f"{case['name']}_expected.npy"
    np.save(os.path.join(out_dir, input_file), x.numpy())
    np.save(os.path.join(out_dir, expected_file), y.numpy())
    print(f"{case['name']:18s} input {tuple(x.shape)} output {tuple(y.shape)} indirect in "
          f"[{y.min().item():.3g}, {y.max().item():.3g}], median {y.median().item():.3g}")
    return {"name": case["name"], "model": model_name, "input": input_file, "expected": expected_file,
            "dtype": "F16" if case["half"] else "F32", "bn_mode": case["bn_mode"]}


def bad_files(out_dir, good_case):
    """Broken variants of a good file, each with a fragment the loader's error must contain."""
    from ngi import model_file
    tensors, config = model_file.read_model(os.path.join(out_dir, good_case["model"]))
    bad = []

    def write(name, t, c, expect):
        model_file.write_model(os.path.join(out_dir, name), t, c)
        bad.append({"model": name, "expect": expect})

    t = dict(tensors)
    del t["mlp.layers.2.bias"]
    write("bad_missing.safetensors", t, config, "missing tensors: mlp.layers.2.bias")
    t = dict(tensors)
    t["mlp.extra.weight"] = np.zeros((2, 2), np.float32)
    write("bad_extra.safetensors", t, config, "unexpected tensors: mlp.extra.weight")
    c = json.loads(json.dumps(config))
    c["neural_gi"]["skip_layer"] = 2  # the file's layer 4 takes the re-injected input, not layer 2
    write("bad_skip.safetensors", tensors, c, "shape mismatch: mlp.layers.2.weight")
    c = json.loads(json.dumps(config))
    c["neural_gi"]["decode"] = "softplus"
    write("bad_decode.safetensors", tensors, c, "neural_gi.decode")
    c = json.loads(json.dumps(config))
    c["output_nc"] = 4
    write("bad_output.safetensors", tensors, c, "output_nc")
    c = json.loads(json.dumps(config))
    c["neural_gi"]["skip_layer"] = c["neural_gi"]["mlp_depth"]
    write("bad_skip_range.safetensors", tensors, c, "neural_gi.skip_layer")
    c = json.loads(json.dumps(config))
    del c["neural_gi"]
    write("bad_no_section.safetensors", tensors, c, "field 'neural_gi' must be an object")
    t = {k: v for k, v in tensors.items() if not k.startswith("buffer.model.model.1.")}
    write("bad_buffer.safetensors", t, config, "missing tensors: model.model.1.")
    c = json.loads(json.dumps(config))
    c["neural_gi"]["scene_box"] = {"min": [0, 0, 0], "max": [1, -1, 1]}
    write("bad_box.safetensors", tensors, c, "neural_gi.scene_box")
    # Loads, but cannot run on frames (no scene box to normalize positions with): NeuralGiRenderer refuses it.
    c = json.loads(json.dumps(config))
    del c["neural_gi"]["scene_box"]
    model_file.write_model(os.path.join(out_dir, "no_box.safetensors"), tensors, c)
    return bad


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    torch.set_num_threads(1)
    cases = [make_case(c, args.out) for c in CASES]
    with open(os.path.join(args.out, "cases.json"), "w") as f:
        json.dump({"cases": cases, "bad": bad_files(args.out, cases[0])}, f, indent=2)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {args.out}")


if __name__ == "__main__":
    main()

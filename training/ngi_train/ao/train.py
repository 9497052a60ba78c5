#!/usr/bin/python3
"""Train seed 001's ambient-occlusion MLP (48 -> X tanh -> Y tanh -> 1) on one object and export it for ngi.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.ao.train --data DATA --size 16x8 \\
        --out models/ao_sculpture_16x8.safetensors

DATA is an `ngi ao-data` folder. As the seed (section 3): 512 random pixels from each of the 128 orbit views
(65,536 samples), input = 16 normals on a circle around the pixel (sampling.py), target = its AO; split
50/25/25 at random; inputs and targets min-max scaled to [-1, 1] (MATLAB's default), the scaling folded into the
first and last layers of the exported file; mean squared error. The seed used MATLAB's scaled conjugate
gradient; here full-batch L-BFGS (also a second-order full-batch method, in PyTorch), with early stopping on
the validation split: stop after `--max-fail` checks without a new best, keep the best weights.

Writes the model (F16 unless --f32) and prints one JSON line with the test-split MSE, the training time and
the iteration count; the same facts go into the file's metadata under "training". Interruptible (Ctrl-C keeps
the best weights so far and exports them).
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

import ngi.model_file as model_file
import ngi.reference_models as reference_models

from ngi_train import ngi_paths
from ngi_train.ao import sampling


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True)
    ap.add_argument("--size", required=True, help="hidden widths XxY, e.g. 16x8")
    ap.add_argument("--out", required=True)
    ap.add_argument("--radius", type=float, default=3.0, help="ring radius in pixels at the data's resolution")
    ap.add_argument("--normals", choices=sorted(sampling.NORMAL_FILE), default="smooth",
                    help="which normals the ring reads: smooth (normal.npy) or the voxel face normals")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--max-iters", type=int, default=3000)
    ap.add_argument("--check-every", type=int, default=10, help="L-BFGS iterations between validation checks")
    ap.add_argument("--max-fail", type=int, default=20, help="checks without improvement before stopping")
    ap.add_argument("--f32", action="store_true")
    a = ap.parse_args(argv)
    torch.set_num_threads(2)
    torch.manual_seed(a.seed)
    hx, hy = (int(v) for v in a.size.lower().split("x"))
    meta = json.loads((Path(a.data) / "ao_data.json").read_text())

    X, y, _ = sampling.sample(a.data, a.radius, seed=a.seed, normals=a.normals)
    perm = np.random.default_rng(a.seed).permutation(len(y))
    n_tr, n_va = len(y) // 2, len(y) // 4
    tr, va, te = perm[:n_tr], perm[n_tr:n_tr + n_va], perm[n_tr + n_va:]
    # MATLAB mapminmax: per input feature [min, max] of the training split -> [-1, 1]; same for the target.
    xmin, xmax = X[tr].min(0), X[tr].max(0)
    xscale = np.where(xmax > xmin, 2.0 / np.maximum(xmax - xmin, 1e-12), 1.0)
    ymin, ymax = float(y[tr].min()), float(y[tr].max())
    yscale = 2.0 / max(ymax - ymin, 1e-12)
    Xs = torch.from_numpy(((X - xmin) * xscale - 1.0).astype(np.float32))
    ys = torch.from_numpy(((y - ymin) * yscale - 1.0).astype(np.float32))[:, None]

    net = reference_models.ao_mlp(hx, hy)
    opt = torch.optim.LBFGS(net.parameters(), lr=1.0, max_iter=a.check_every, history_size=50,
                            line_search_fn="strong_wolfe")
    mse = torch.nn.MSELoss()

    def closure():
        opt.zero_grad()
        loss = mse(net(Xs[tr]), ys[tr])
        loss.backward()
        return loss

    best, best_state, fails, it = float("inf"), None, 0, 0
    bar = tqdm(total=a.max_iters, desc=f"ao {a.size}", unit="iter", **ngi_paths.progress_options())
    t0 = time.monotonic()
    try:
        while it < a.max_iters and fails < a.max_fail:
            opt.step(closure)
            it += a.check_every
            with torch.no_grad():
                val = mse(net(Xs[va]), ys[va]).item()
            if val < best * (1 - 1e-6):
                best, fails = val, 0
                best_state = {k: v.clone() for k, v in net.state_dict().items()}
            else:
                fails += 1
            bar.set_postfix({"val": f"{val:.4g}", "best": f"{best:.4g}"}, refresh=False)
            bar.update(it - bar.n)
    except KeyboardInterrupt:
        print("interrupted: exporting the best weights so far", file=sys.stderr)
    bar.close()
    seconds = time.monotonic() - t0
    net.load_state_dict(best_state)

    # Fold the scalings: net(x_s) with x_s = (x - xmin) * xscale - 1  ->  W1' = W1 diag(xscale),
    # b1' = b1 - W1 (xmin * xscale + 1); output ao = (z + 1) / yscale + ymin  ->  W3' = W3 / yscale,
    # b3' = (b3 + 1) / yscale + ymin.
    sd = {k: v.double() for k, v in net.state_dict().items()}
    xs_t, xm_t = torch.from_numpy(xscale).double(), torch.from_numpy(xmin).double()
    w0 = sd["0.weight"] * xs_t[None, :]
    b0 = sd["0.bias"] - sd["0.weight"] @ (xm_t * xs_t + 1.0)
    w2 = sd["4.weight"] / yscale
    b2 = (sd["4.bias"] + 1.0) / yscale + ymin
    tensors = {"layers.0.weight": w0, "layers.0.bias": b0, "layers.1.weight": sd["2.weight"],
               "layers.1.bias": sd["2.bias"], "layers.2.weight": w2, "layers.2.bias": b2}
    half = not a.f32

    def folded(x):  # the exported network (with the F16 rounding of the file), in float64
        t = {k: (v.half().double() if half else v.float().double()) for k, v in tensors.items()}
        h = torch.tanh(x @ t["layers.0.weight"].T + t["layers.0.bias"])
        h = torch.tanh(h @ t["layers.1.weight"].T + t["layers.1.bias"])
        return (h @ t["layers.2.weight"].T + t["layers.2.bias"])[:, 0]

    with torch.no_grad():
        Xd = torch.from_numpy(X).double()
        pred = folded(Xd).clamp(0, 1).numpy()
    test_mse = float(np.mean((pred[te] - y[te]) ** 2))
    val_mse = float(np.mean((pred[va] - y[va]) ** 2))
    train_mse = float(np.mean((pred[tr] - y[tr]) ** 2))
    report = {"size": a.size, "normals": a.normals, "radius_px": a.radius, "parameters": sum(p.numel() for p in net.parameters()), "samples": int(len(y)),
              "train_mse": train_mse, "val_mse": val_mse, "test_mse": test_mse, "iterations": it,
              "seconds": round(seconds, 1), "optimizer": "L-BFGS (strong Wolfe), full batch, early stopping",
              "max_fail": a.max_fail, "check_every": a.check_every, "seed": a.seed}
    config = {"format_version": 1, "family": "mlp", "input_nc": 48,
              "layers": [{"out": hx, "activation": "tanh"}, {"out": hy, "activation": "tanh"},
                         {"out": 1, "activation": "none"}],
              "input_range": [-1.0, 1.0],
              "ao": {"neighbours": sampling.RING, "radius_px": a.radius, "at_size": meta["n"],
                     "normals": a.normals, "sigma": meta["sigma"], "max_distance": meta["max_distance"],
                     "rays": meta["rays"], "scene": meta["scene"]},
              "source": f"ngi_train.ao.train --size {a.size} --data {Path(a.data).name}",
              "training": report}
    model_file.write_model(a.out, tensors, config, half=half)
    back = model_file.read_model(a.out)
    assert back[1]["ao"]["neighbours"] == sampling.RING, "metadata did not round-trip"
    print(json.dumps(report))


if __name__ == "__main__":
    main()

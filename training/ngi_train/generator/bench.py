#!/usr/bin/python3
"""Seconds per training step of a config at a face size, on random data (no dataset needed), and the projected
training time for the config's steps.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.bench \\
        --config training/configs/surround.json --n 128 --steps 8

One warm-up step, then --steps timed steps (G forward, D update, G update: what train.py does per frame).
Prints every step's time, the minimum (the machine's speed when nothing else runs) and the median.
"""

import argparse
import json
import statistics
import time

import torch

from ngi_train.generator import data, gan, networks, train


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", required=True)
    ap.add_argument("--n", type=int, default=128, help="face size N")
    ap.add_argument("--steps", type=int, default=8, help="timed steps")
    ap.add_argument("--threads", type=int, help="override the config's threads")
    args = ap.parse_args()
    cfg = train.load_config(args.config, {"threads": args.threads})
    if cfg["threads"]:
        torch.set_num_threads(cfg["threads"])
    train.check_sizes(cfg, args.n)
    torch.manual_seed(cfg["seed"])
    model = gan.Pix2Pix(cfg, args.n)
    h, w = data.input_hw(args.n, cfg["layout"])
    x = torch.rand(1, data.input_nc(cfg["layout"]), h, w) * 2 - 1
    y = torch.rand(1, 3, args.n, args.n) * 2 - 1
    times = []
    for i in range(args.steps + 1):
        t0 = time.perf_counter()
        model.step(x, y, i)
        times.append(time.perf_counter() - t0)
    timed = times[1:]
    med = statistics.median(timed)
    result = {"config": args.config, "layout": cfg["layout"], "n": args.n, "input": [h, w], "ngf": cfg["ngf"],
              "num_downs": cfg["num_downs"], "ndf": cfg["ndf"], "threads": torch.get_num_threads(),
              "G_params": networks.parameter_count(model.G), "D_params": networks.parameter_count(model.D),
              "warmup_s": round(times[0], 3), "step_s": [round(t, 3) for t in timed],
              "min_s": round(min(timed), 3), "median_s": round(med, 3), "steps": cfg["steps"],
              "projected_hours_at_min": round(min(timed) * cfg["steps"] / 3600, 2),
              "projected_hours_at_median": round(med * cfg["steps"] / 3600, 2)}
    print(json.dumps(result))


if __name__ == "__main__":
    main()

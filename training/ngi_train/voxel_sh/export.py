#!/usr/bin/python3
"""Export a voxel_sh network (seed 004) as an ngi model file (docs/MODEL_FORMAT.md "voxel_sh").

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.voxel_sh.export --work WORK --out model.safetensors

WORK is a train.py work folder: its checkpoint (at whatever step it is, e.g. after a Ctrl-C) is exported with the
standardization statistics of its training scenes and its grid. train.py calls export() itself at the end.
"""

import argparse
import sys
from pathlib import Path

import ngi.model_file as model_file
import ngi.voxel_sh as networks

from ngi_train import checkpoint
from ngi_train.voxel_sh import data


def export(net, architecture, widths, stats, grid, out, half=False, source="", training=None):
    """Writes `net` (an ngi.voxel_sh.build(architecture, **widths) module) with the statistics (data.Stats) and the grid
    to `out`, F16 with half; returns the config. Names and shapes are checked against the format."""
    config = model_file.make_voxel_sh_config(
        architecture, grid=list(grid), input_lo=stats.input_lo, input_hi=stats.input_hi,
        output_mean=stats.output_mean, output_std=stats.output_std, source=source, training=training,
        **{k: v for k, v in widths.items()})
    tensors = {k: v.detach().float().cpu() for k, v in net.state_dict().items()}
    model_file.write_voxel_sh_model(str(out), tensors, config, half=half)
    return config


def load_checkpoint(work):
    path = Path(work) / "checkpoint.pt"
    if not path.is_file():
        raise SystemExit(f"{work}: no checkpoint.pt (run train.py with --work {work} first)")
    return checkpoint.load(path)  # our own file (train.py); never load checkpoints you did not write


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", required=True, help="train.py work folder")
    ap.add_argument("--out", required=True)
    ap.add_argument("--half", action="store_true", help="store F16 weights")
    a = ap.parse_args(argv)
    state = load_checkpoint(a.work)
    cfg = state["config"]
    net = networks.build(cfg["arch"], **cfg["widths"])
    net.load_state_dict(state["model"])
    config = export(net, cfg["arch"], cfg["widths"], data.Stats.from_dict(state["stats"]), state["grid"], a.out,
                    half=a.half, source=f"ngi_train.voxel_sh.export --work {a.work} (step {state['step']})",
                    training={"step": state["step"], "train_seconds": round(state["train_seconds"], 1),
                              "train_scenes": state["train_scenes"], "test_scenes": state["test_scenes"]})
    print(f"wrote {a.out}: voxel_sh {config['architecture']}, step {state['step']}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

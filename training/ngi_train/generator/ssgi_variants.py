#!/usr/bin/python3
"""Writes SSGI rung files (model family "ssgi", no tensors) for a grid of gather settings, so a settings sweep can be
scored by engine_eval like any rung and rerun from this command alone.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.ssgi_variants --out runs/ssgi_variants \\
        --grid bounces=1,2 visibility_steps=0,8 thickness=0,1

Every combination of the grid's values (other settings keep the family's defaults, docs/MODEL_FORMAT.md "ssgi") is
written as OUT/<short name>.safetensors, e.g. b2_v8_t1 for bounces 2, visibility_steps 8, thickness 1 (names never
contain "surround": engine_eval's "below SSGI" column then stays the shipped ssgi_surround's). The written paths are
printed comma-separated, ready for engine_eval --rungs.
"""

import argparse
import itertools
from pathlib import Path

import ngi.model_file as model_file

# Short names of the settings in the file names.
SHORT = {"view": "", "cluster_level": "L", "bounces": "b", "near_factor": "n", "min_distance": "m",
         "visibility_steps": "v", "thickness": "t"}
INTEGER = {"cluster_level", "bounces", "visibility_steps"}


def parse_grid(items):
    """["bounces=1,2", ...] -> {"bounces": [1, 2], ...}, each key one of the gather's settings."""
    grid = {}
    for item in items:
        key, sep, values = item.partition("=")
        if not sep or key not in model_file.SSGI_GATHER_FIELDS or not values:
            raise SystemExit(f"ssgi_variants: '{item}' is not SETTING=V1,V2,... with SETTING one of "
                             f"{', '.join(model_file.SSGI_GATHER_FIELDS)}")
        try:
            grid[key] = [v if key == "view" else int(v) if key in INTEGER else float(v) for v in values.split(",")]
        except ValueError:
            raise SystemExit(f"ssgi_variants: '{item}': values must be {'integers' if key in INTEGER else 'numbers'}")
    return grid


def name_of(setting):
    """The file stem of one combination: b2_v8_t1 ("front" view: f_ prefix)."""
    parts = ["f"] if setting.get("view") == "front" else []
    for key, value in setting.items():
        if key != "view":
            parts.append(f"{SHORT[key]}{value:g}")
    return "_".join(parts) or "default"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True, help="folder the rung files are written to")
    ap.add_argument("--grid", nargs="+", required=True, help="SETTING=V1,V2,... (one per setting)")
    ap.add_argument("--source", default="ngi_train.generator.ssgi_variants", help="the files' source field")
    args = ap.parse_args(argv)
    grid = parse_grid(args.grid)
    args.out.mkdir(parents=True, exist_ok=True)
    paths = []
    for values in itertools.product(*grid.values()):
        setting = dict(zip(grid.keys(), values))
        path = args.out / f"{name_of(setting)}.safetensors"
        model_file.write_model(path, {}, {"format_version": 1, "family": "ssgi", **setting, "source": args.source})
        paths.append(str(path))
    print(",".join(paths))


if __name__ == "__main__":
    main()

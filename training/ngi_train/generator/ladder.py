#!/usr/bin/python3
"""Train and export the speed/accuracy ladder (training/configs/ladder.json): every rung a pix2pix U-Net trained
with the ladder's one recipe on the same frames, then exported as an ngi model file.

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.ladder \\
        --data 64=data/clean_n64 --data 32=data/clean_n32 \\
        --work runs/ladder --lane 0 &
    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.ladder \\
        --data 64=data/clean_n64 --data 32=data/clean_n32 \\
        --work runs/ladder --lane 1

A lane runs its rungs one after the other (train.py with the rung's config in WORK/configs, run folder
WORK/runs/<rung>; export.py --half --bn-mode B, B = the ladder file's "bn_mode", default auto: chosen on the recipe's
eval_split). Shipped rungs go to models/ladder/<rung>.safetensors, the
others to WORK/models/; every rung is also exported with F32 weights to WORK/fp32/ (the fp32-vs-fp16 rung of the
evaluation). Interrupting is safe: train.py resumes from its last checkpoint (every 500 steps) and a rung whose
exports are newer than its checkpoint is skipped.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

from ngi_train import ngi_paths

LADDER = ngi_paths.REPO / "training" / "configs" / "ladder.json"
RUNG_KEYS = {"name", "layout", "n", "ngf", "num_downs", "seed", "lane", "ship", "recipe"}


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def load_ladder(path=LADDER):
    """The ladder config, each rung checked for unknown keys and unique names."""
    ladder = json.loads(Path(path).read_text())
    try:
        ladder["path"] = Path(path).resolve().relative_to(ngi_paths.REPO).as_posix()
    except ValueError:
        ladder["path"] = Path(path).name
    names = set()
    for r in ladder["rungs"]:
        unknown = set(r) - RUNG_KEYS
        if unknown:
            raise ValueError(f"{path}: rung {r.get('name')}: unknown keys {sorted(unknown)}")
        if r["name"] in names:
            raise ValueError(f"{path}: rung name {r['name']} appears twice")
        names.add(r["name"])
    return ladder


def rung_config(ladder, rung):
    """train.py config of one rung: the recipe with the rung's own recipe keys (an ablation's), architecture and
    seed."""
    cfg = dict(ladder["recipe"])
    cfg.update(rung.get("recipe", {}))
    cfg.update({k: rung[k] for k in ("layout", "ngf", "num_downs", "seed") if k in rung})
    cfg["comment"] = f"ladder rung {rung['name']} ({ladder.get('path', 'training/configs/ladder.json')})"
    return cfg


def shipped_path(rung):
    return ngi_paths.REPO / "models" / "ladder" / f"{rung['name']}.safetensors"


def export_paths(rung, work):
    half = shipped_path(rung) if rung.get("ship") else work / "models" / f"{rung['name']}.safetensors"
    return half, work / "fp32" / f"{rung['name']}.safetensors"


def parse_data(items):
    out = {}
    for item in items:
        n, _, path = item.partition("=")
        if not n.isdigit() or not path:
            raise SystemExit(f"--data wants N=DIR, got {item!r}")
        out[int(n)] = Path(path)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ladder", type=Path, default=LADDER)
    ap.add_argument("--data", action="append", default=[], help="N=DIR: the dataset of face size N (repeat)")
    ap.add_argument("--work", type=Path, required=True, help="configs, run folders, unshipped exports")
    ap.add_argument("--lane", type=int, help="only this lane's rungs (default: all, in file order)")
    ap.add_argument("--only", help="comma-separated rung names")
    ap.add_argument("--device", default=None, help="ngi device for the merges (default: the library's)")
    args = ap.parse_args(argv)
    ladder = load_ladder(args.ladder)
    data = parse_data(args.data)
    only = set(args.only.split(",")) if args.only else None
    rungs = [r for r in ladder["rungs"] if (args.lane is None or r["lane"] == args.lane)
             and (only is None or r["name"] in only)]
    py = sys.executable
    for rung in rungs:
        if rung["n"] not in data:
            raise SystemExit(f"rung {rung['name']} needs the N = {rung['n']} dataset: --data {rung['n']}=DIR")
        dataset = data[rung["n"]]
        cfg_path = args.work / "configs" / f"{rung['name']}.json"
        cfg_path.parent.mkdir(parents=True, exist_ok=True)
        cfg_path.write_text(json.dumps(rung_config(ladder, rung), indent=1) + "\n")
        run = args.work / "runs" / rung["name"]
        half, fp32 = export_paths(rung, args.work)
        latest = run / "checkpoints" / "latest.pt"
        if latest.is_file() and all(p.is_file() and p.stat().st_mtime > latest.stat().st_mtime for p in (half, fp32)):
            log(f"ladder: {rung['name']}: exported, skipped")
            continue
        log(f"ladder: {rung['name']}: training ({dataset})")
        cmd = [py, "-m", "ngi_train.generator.train", "--config", str(cfg_path), "--dataset", str(dataset),
               "--run", str(run)]
        if args.device:
            cmd += ["--device", args.device]
        subprocess.run(cmd, check=True)
        for out, extra in ((half, ["--half"]), (fp32, [])):
            out.parent.mkdir(parents=True, exist_ok=True)
            cmd = [py, "-m", "ngi_train.generator.export", "--run", str(run), "--out", str(out), "--bn-mode",
                   ladder.get("bn_mode", "auto")] + extra
            if args.device:
                cmd += ["--device", args.device]
            subprocess.run(cmd, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""The planner on scenes in no training set: for each (scene, budget) run `python3 -m ngi.plan` and collect its
choice, the reasons and the validation on other frames of the scene (docs/RESULTS.md, "The planner").

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.plan_study \\
        --zoo models/zoo.json --work runs/plans \\
        --out docs/results/plan_study.json
    ... --vox-dir ../shared/scenes/vox --work runs/plans_vox --out docs/results/plan_vox.json   # issue 45

Plans already in --work are kept (a rerun only plans what is missing). With --vox-dir the cases are every .vox file
of that folder (read from there; evaluation only) with VOX_BUDGET, the README demo's budget and sample counts: the
question is whether the planner ever picks a rung that a cheaper one (direct light, SSGI) beats on frames it did not
calibrate on (each row's validation margins, choice_held and beaten_by).
"""

import argparse
import contextlib
import io
import json
import sys
from pathlib import Path

import ngi.plan as plan

CASES = [
    ("room:seed=204", ["--min-ssim", "0.85"]),
    ("room:seed=204", ["--max-ms", "100"]),
    ("street:seed=103", ["--min-ssim", "0.85"]),
    ("street:seed=103", ["--max-ms", "100"]),
    ("cave:seed=102", ["--min-ssim", "0.7"]),
    ("bleed:seed=102", ["--min-ssim", "0.8"]),
    ("backlit:seed=102", ["--min-psnr", "30"]),
    ("bleed:seed=102", ["--min-ssim", "0.99"]),
]


VOX_BUDGET = ["--max-ms", "300", "--frames", "3", "--validate", "2", "--spp", "512"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--zoo", default="models/zoo.json")
    ap.add_argument("--work", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--device", default="pocl")
    ap.add_argument("--vox-dir", type=Path, help="plan every .vox file of this folder instead of CASES")
    args = ap.parse_args(argv)
    args.work.mkdir(parents=True, exist_ok=True)
    cases = ([(str(f), VOX_BUDGET) for f in sorted(args.vox_dir.glob("*.vox"))] if args.vox_dir else CASES)
    rows = []
    for k, (scene, budget) in enumerate(cases):
        out = args.work / f"plan_{k}.json"
        if not out.is_file() and not (args.work / f"plan_{k}.failed").is_file():
            print(f"== {scene} {' '.join(budget)}", file=sys.stderr, flush=True)
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                rc = plan.main(["--scene", scene, "--zoo", args.zoo, "--device", args.device, "--out", str(out),
                                *budget])
            sys.stderr.write(err.getvalue())
            if rc != 0:
                (args.work / f"plan_{k}.failed").write_text(err.getvalue())
        failed = args.work / f"plan_{k}.failed"
        if failed.is_file():
            last = [line for line in failed.read_text().splitlines() if line.startswith("ngi.plan:")]
            rows.append({"scene": scene, "budget": " ".join(budget), "chosen": None,
                         "why": last[-1] if last else "ngi.plan failed"})
            continue
        p = plan.read_plan(out)  # strict: a plan left by an earlier run may have been edited since
        rows.append({"scene": Path(scene).name if args.vox_dir else scene, "budget": " ".join(budget),
                     "chosen": p["rung"], "why": p["why"], "switch": p.get("switch"), "validation": p["validation"],
                     "calibration": p["calibration"]["rungs"]})
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rows, indent=1) + "\n")
    for r in rows:
        v = r.get("validation") or {}
        print(f"{r['scene']:18s} {r['budget']:18s} -> {r['chosen']}  validation SSIM {v.get('ssim', float('nan')):.4f}"
              f" PSNR {v.get('psnr', float('nan')):.2f} kept {v.get('kept_quality_promise')} held "
              f"{v.get('choice_held')} beaten by {v.get('beaten_by')}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Tables, learning curves and a summary JSON of seed 002's runs (docs/RESULTS_NEURAL_GI.md is written from them).

    /usr/bin/python3 -m ngi_train.neural_gi.report --runs data/neural_gi_runs --results data/neural_gi_results \\
        --out docs/neural_gi

RUNS/<scene>/<variant>/ are train.py work folders (run.json, log.jsonl); RESULTS/<scene>__<variant>__<set>.json
are evaluate.py outputs, <set> one of heldout, moving_camera, moving_light. Variants: neural_gi (seed 1),
neural_gi_seed2, no_buffer, unet_only. Writes OUT/results.json (the summaries, no per-frame rows), OUT/tables.md and
OUT/curves.png. Every number is read from those files; nothing is typed in by hand.
"""

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

VARIANTS = {"neural_gi": "CNN + MLP (Neural GI), seed 1", "neural_gi_seed2": "CNN + MLP (Neural GI), seed 2",
            "no_buffer": "MLP without the CNN buffer", "unet_only": "U-Net alone (the paper's [72]-net)"}
SETS = ("heldout", "moving_camera", "moving_light")


def load_results(results):
    out = {}
    for p in sorted(Path(results).glob("*__*__*.json")):
        scene, variant, kind = p.stem.split("__")
        r = json.loads(p.read_text())
        out.setdefault(scene, {}).setdefault(variant, {})[kind] = {
            "frames": r["frames"], "n": r["n"], "engine": r["engine"], "summary": r["summary"],
            "temporal": {m: {k: v for k, v in t.items() if k != "mabd_per_step"} for m, t in r["temporal"].items()}
            if r.get("temporal") else None}
    return out


def load_runs(runs):
    out = {}
    for run_json in sorted(Path(runs).glob("*/*/run.json")):
        variant, scene = run_json.parent.name, run_json.parent.parent.name
        run = json.loads(run_json.read_text())
        log_path = run_json.parent / "log.jsonl"
        log = [json.loads(x) for x in log_path.read_text().splitlines() if x.strip()] if log_path.is_file() else []
        evals = [x for x in log if x.get("heldout_loss") is not None]
        last = log[-1] if log else {}
        out.setdefault(scene, {})[variant] = {
            "parameters": run["parameters"], "train_frames": run["train"], "heldout_frames": run["test"],
            "n": run["n"], "steps": last.get("step"), "train_seconds": last.get("seconds"),
            "curve": [{"step": x["step"], "heldout_loss": x["heldout_loss"], "train_eval_loss": x["train_eval_loss"]}
                      for x in evals]}
    return out


def fmt(v, digits):
    return "-" if v is None else f"{v:.{digits}f}"


def method_rows(variants):
    """(label, variant, method key in its evaluate.py summary) rows of a table, models first, then baselines."""
    rows = [(VARIANTS[v], v, "model") for v in VARIANTS if v in variants]
    any_variant = next(iter(variants))
    rows.append(("direct light only", any_variant, "direct_only"))
    return rows


def traced_rows(result, variant):
    """Rows of evaluate.py's path_traced_<spp> methods, fewest samples first."""
    keys = sorted((k for k in result["summary"] if k.startswith("path_traced_")),
                  key=lambda k: int(k.rsplit("_", 1)[1]) if k.rsplit("_", 1)[1].isdigit() else 0)
    return [(f"path tracing, {k.rsplit('_', 1)[1]} spp", variant, k) for k in keys]


def table_rows(variants, kind, temporal=False):
    """({variant: its results} of the variants evaluated on `kind` (with temporal metrics if asked), the table's
    (label, variant, method) rows: the networks, direct light, then path tracing at each sample count)."""
    present = {v: r for v, r in variants.items() if kind in r and (not temporal or r[kind]["temporal"])}
    if not present:
        return present, []
    rows = method_rows(present)
    return present, rows + traced_rows(present[rows[0][1]][kind], rows[0][1])


def quality_table(results, kind):
    lines = ["| scene | method | final MAE | final MSE | final PSNR dB | final SSIM | lighting PSNR dB | log-L1 |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for scene, variants in results.items():
        present, rows = table_rows(variants, kind)
        for label, v, method in rows:
            s = present[v][kind]["summary"][method]
            f, li = s["final"], s["lighting"]
            lines.append(f"| {scene} | {label} | {fmt(f['mae'], 4)} | {fmt(f['mse'], 5)} | {fmt(f['psnr'], 2)} | "
                         f"{fmt(f['ssim'], 4)} | {fmt(li['psnr'], 2)} | {fmt(s['log_l1'], 4)} |")
    return "\n".join(lines)


def temporal_table(results):
    lines = ["| scene | sequence | reference MABD | method | MABD | mean abs. MABD error | final PSNR dB | final SSIM |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for scene, variants in results.items():
        for kind in ("moving_camera", "moving_light"):
            present, rows = table_rows(variants, kind, temporal=True)
            if not rows:
                continue
            ref = present[rows[0][1]][kind]["temporal"]["reference"]["mabd"]
            for label, v, method in rows:
                t = present[v][kind]["temporal"][method]
                f = present[v][kind]["summary"][method]["final"]
                lines.append(f"| {scene} | {kind.replace('_', ' ')} | {fmt(ref, 5)} | {label} | {fmt(t['mabd'], 5)} | "
                             f"{fmt(t['mabd_error'], 5)} | {fmt(f['psnr'], 2)} | {fmt(f['ssim'], 4)} |")
    return "\n".join(lines)


def spread_table(results):
    """CNN + MLP vs the U-Net and vs the MLP alone, against the spread of the two CNN + MLP seeds (held-out)."""
    lines = ["| scene | metric | CNN + MLP seed 1 / seed 2 | seed spread | U-Net | MLP only | CNN + MLP (mean) - U-Net |"
             " beats the U-Net by more than the spread? |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for scene, v in results.items():
        need = ("neural_gi", "neural_gi_seed2", "unet_only")
        if not all(k in v and "heldout" in v[k] for k in need):
            continue
        for metric, digits, better in (("psnr", 2, 1), ("ssim", 4, 1), ("mae", 4, -1)):
            get = lambda k: v[k]["heldout"]["summary"]["model"]["final"][metric]  # noqa: E731
            a, b, u = get("neural_gi"), get("neural_gi_seed2"), get("unet_only")
            m = get("no_buffer") if "no_buffer" in v and "heldout" in v["no_buffer"] else None
            if None in (a, b, u):
                continue
            spread, diff = abs(a - b), (a + b) / 2 - u
            verdict = "yes" if better * diff > spread else "no"
            lines.append(f"| {scene} | final {metric.upper()} | {fmt(a, digits)} / {fmt(b, digits)} | "
                         f"{fmt(spread, digits)} | {fmt(u, digits)} | {fmt(m, digits)} | {diff:+.{digits}f} | "
                         f"{verdict} |")
    return "\n".join(lines)


def runs_table(runs):
    lines = ["| scene | variant | parameters | N | train / held-out frames | steps | training time (1 thread) |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for scene, variants in runs.items():
        for v, r in variants.items():
            t = r["train_seconds"]
            lines.append(f"| {scene} | {VARIANTS.get(v, v)} | {r['parameters']:,} | {r['n']} | {r['train_frames']} / "
                         f"{r['heldout_frames']} | {r['steps']} | {fmt(t / 60 if t else None, 1)} min |")
    return "\n".join(lines)


def plot_curves(runs, path):
    scenes = list(runs)
    fig, axes = plt.subplots(1, len(scenes), figsize=(6 * len(scenes), 4), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        for v, r in runs[scene].items():
            steps = [c["step"] for c in r["curve"]]
            line, = ax.plot(steps, [c["heldout_loss"] for c in r["curve"]], label=f"{VARIANTS.get(v, v)} held-out")
            ax.plot(steps, [c["train_eval_loss"] for c in r["curve"]], ls=":", color=line.get_color())
        ax.set_title(f"{scene}: log-L1 (solid: held-out, dotted: training frames)")
        ax.set_xlabel("step (1 image)")
        ax.set_ylabel("log-L1 (Eq. 6)")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", required=True, type=Path)
    ap.add_argument("--results", required=True, type=Path)
    ap.add_argument("--out", required=True, type=Path)
    a = ap.parse_args(argv)
    results, runs = load_results(a.results), load_runs(a.runs)
    if not results:
        raise SystemExit(f"{a.results}: no evaluate.py results (<scene>__<variant>__<set>.json)")
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / "results.json").write_text(json.dumps({"results": results, "runs": runs}, indent=1) + "\n")
    tables = ["## Held-out frames", quality_table(results, "heldout"),
              "## Sequences: temporal stability and path tracing at equal time", temporal_table(results),
              "## Sequences: quality (moving camera)", quality_table(results, "moving_camera"),
              "## Sequences: quality (moving light)", quality_table(results, "moving_light"),
              "## CNN + MLP against the U-Net, and the seed spread (held-out)", spread_table(results),
              "## Runs", runs_table(runs)]
    (a.out / "tables.md").write_text("\n\n".join(tables) + "\n")
    if runs:
        plot_curves(runs, a.out / "curves.png")
    print("\n\n".join(tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Markdown tables for docs/RESULTS_VOXEL_SH.md from experiment.sh's outputs: the voxel-level metrics
(evaluate.py's JSON), the frame-level metrics of every `ngi probe-gi` folder, and the training logs.

Usage: report.py WORK_DIR   (prints markdown to stdout)
"""
import json
import statistics
import sys
from pathlib import Path


def fmt(v, digits=4):
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


def main():
    work = Path(sys.argv[1])
    print("### Training runs\n")
    print("| model | architecture | parameters | steps | wall time | train MSE (std) | test MSE (std) |")
    print("|---|---|---|---|---|---|---|")
    for log in sorted((work / "runs").glob("*/log.jsonl")):
        rows = [json.loads(l) for l in log.read_text().splitlines() if l.strip()]
        run = json.loads((log.parent / "run.json").read_text()) if (log.parent / "run.json").is_file() else {}
        last = rows[-1]
        print(f"| {log.parent.name} | {run.get('config', {}).get('arch', '?')} | "
              f"{run.get('parameters', '?')} | {last['step']} | {last['seconds'] / 60:.1f} min | "
              f"{last['train_mse']:.3f} | {last['test_mse']:.3f} |")

    vm = json.loads((work / "voxel_metrics.json").read_text())
    for scene, r in vm["scenes"].items():
        print(f"\n### Voxel level: {scene} ({r['voxels']} voxels)\n")
        print(f"Predicting the training mean SH: SH MSE {r['predict_training_mean_sh_mse_std']:.3f} (standardized).\n")
        print("| method | SH MSE (std) | face irradiance rel. MSE | probe irradiance rel. MSE | ms per scene (PoCL) |")
        print("|---|---|---|---|---|")
        for name, m in r["methods"].items():
            ms = m.get("ms_per_scene", {})
            print(f"| {name} | {fmt(m.get('sh_mse_std'))} | {fmt(m['face_rel_mse'])} | {fmt(m['probe_rel_mse'])} | "
                  f"{fmt(ms.get('pocl'), 1) if ms else '–'} |")

    frames = sorted(p for p in (work / "frames").glob("*/metrics.json"))
    per_method = {}
    for f in frames:
        m = json.loads(f.read_text())
        if m["face"] < 64:
            continue
        for name, r in m["methods"].items():
            per_method.setdefault(name, []).append((f.parent.name, r))
    print("\n### Frames (128², tone-mapped final image and linear lightmap against the 1024-spp reference)\n")
    names = [f.parent.name for f in frames if json.loads(f.read_text())["face"] >= 64]
    print("| method | " + " | ".join(f"{n} SSIM / PSNR" for n in names) + " | mean SSIM | mean PSNR | "
          "lightmap PSNR (mean) | field ms | shade ms |")
    print("|---|" + "---|" * (len(names) + 5))
    for name, rows in per_method.items():
        cells, ssims, psnrs, lpsnrs = [], [], [], []
        for _, r in rows:
            s, p, lp = r["final_ldr"]["ssim"], r["final_ldr"]["psnr"], r["lightmap_linear"]["psnr"]
            cells.append(f"{s:.3f} / {p:.2f}")
            ssims.append(s)
            psnrs.append(p)
            lpsnrs.append(lp)
        fm = [r["field_ms"] for _, r in rows if r.get("field_ms") is not None]
        sm = [r["shade_ms"] for _, r in rows if r.get("shade_ms") is not None]
        print(f"| {name} | " + " | ".join(cells) + f" | {statistics.mean(ssims):.3f} | {statistics.mean(psnrs):.2f} | "
              f"{statistics.mean(lpsnrs):.2f} | {fmt(statistics.median(fm), 1) if fm else '–'} | "
              f"{fmt(statistics.median(sm), 1) if sm else '–'} |")
    for f in frames:
        m = json.loads(f.read_text())
        if m.get("noise_floor"):
            nf = m["noise_floor"]
            print(f"\nNoise floor ({f.parent.name}: a second 1024-spp reference against the first): final SSIM "
                  f"{nf['final_ldr']['ssim']:.3f}, PSNR {nf['final_ldr']['psnr']:.2f} dB; lightmap PSNR "
                  f"{nf['lightmap_linear']['psnr']:.2f} dB.")
        if m["face"] < 64:
            print(f"\n### Costs on {m['device']} ({f.parent.name}, {m['voxels']} voxels)\n")
            print("| method | field ms | shade ms |")
            print("|---|---|---|")
            for name, r in m["methods"].items():
                extra = f" (+ visibility {r['visibility_ms']:.0f} ms)" if "visibility_ms" in r else ""
                print(f"| {name} | {fmt(r.get('field_ms'), 1)}{extra} | {fmt(r.get('shade_ms'), 1)} |")


if __name__ == "__main__":
    main()

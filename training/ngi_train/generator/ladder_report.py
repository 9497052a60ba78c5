"""Tables and figures of the ladder evaluation (ladder_eval.py): OUT/ladder_tables.md (pasted into
docs/RESULTS.md, "The ladder") and OUT/ladder_pareto_<device>.png, OUT/ladder_temporal.png."""

import math
from pathlib import Path


KIND_LABEL = {"rung": "", "bn_variant": " (other BN mode)", "f32_variant": " (F32 weights)", "legacy": " (shipped before)",
              "direct": ""}


def fmt(v, spec, none="–"):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return none
    return format(v, spec)


def label(name, v):
    if v["kind"] == "direct":
        return "direct light only"
    return f"{name}"


def plt_module():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def pareto(points):
    keep = []
    for name, ms, q in points:
        dominated = any((m2 <= ms and q2 >= q) and (m2 < ms or q2 > q) for n2, m2, q2 in points if n2 != name)
        if not dominated:
            keep.append(name)
    return keep


def fronts(summary, device, metric, cost="lightmap_ms"):
    pts = []
    for name, v in summary["variants"].items():
        h = v.get("heldout")
        if not h:
            continue
        if v["kind"] == "direct":
            pts.append((name, 0.0, h["final"][metric]))
        elif device in v.get("speed", {}):
            pts.append((name, v["speed"][device][cost], h["final"][metric]))
    return pts, pareto(pts)


def plot_pareto(summary, device, path):
    plt = plt_module()
    fig, grid = plt.subplots(2, 2, figsize=(13, 10))
    for ax, (cost, metric) in zip(grid.flat, [(c, m) for c in ("lightmap_ms", "generator_ms") for m in ("psnr", "ssim")]):
        pts, front = fronts(summary, device, metric, cost)
        floor = 1.0 if cost == "lightmap_ms" else 0.5
        for name, ms, q in pts:
            v = summary["variants"][name]
            color = {"surround": "tab:blue", "single_view": "tab:orange", "none": "black"}[v["layout"]]
            marker = {"rung": "o", "bn_variant": "s", "legacy": "^", "direct": "*"}[v["kind"]]
            x = max(ms, floor)
            ax.scatter([x], [q], c=color, marker=marker, s=60 if name in front else 25,
                       edgecolors="k" if name in front else "none", zorder=3)
            ax.annotate(name.replace("single_view", "sv").replace("surround", "s"), (x, q), fontsize=6,
                        xytext=(3, 2), textcoords="offset points")
        fp = sorted((max(ms, floor), q) for name, ms, q in pts if name in front)
        ax.step([p[0] for p in fp], [p[1] for p in fp], where="post", color="gray", lw=1, zorder=1)
        ax.set_xscale("log")
        what = "whole ngi lightmap command" if cost == "lightmap_ms" else "generator alone"
        ax.set_xlabel(f"ms per frame, {what}, {device} (direct light only drawn at {floor:g} ms)")
        ax.set_ylabel(f"held-out final-image {metric.upper()}")
        ax.grid(alpha=0.3)
    fig.suptitle(f"Speed vs accuracy on {summary['speed_devices'].get(device, {}).get('name', device)}: blue surround-"
                 f"aware, orange single view; o as exported, s other BN mode, ^ shipped before; outlined = Pareto front",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_temporal(summary, temporal, names, path):
    plt = plt_module()
    seqs = ["moving_camera", "moving_sun"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    for ax, s in zip(axes, seqs):
        ref_drawn = False
        for name in names:
            t = (temporal.get(name) or {}).get(s)
            if not t:
                continue
            if not ref_drawn:
                ax.plot(t["brightness_reference"], "k-", lw=2, label="reference")
                ref_drawn = True
            ax.plot(t["brightness"], lw=1, label=name)
        ax.set_title(s.replace("_", " ") + " — mean of the tone-mapped final image per frame", fontsize=9)
        ax.set_xlabel("frame")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def tables(summary):
    V = summary["variants"]
    devices = list(summary["speed_devices"])
    L = []
    nf = summary.get("noise_floor", {}).get("64")
    if nf:
        L.append(f"Noise floor of the references (two independent {nf['reference_spp']}-spp renders of {nf['frames']} "
                 f"test frames against each other, `training/ngi_train/generator/noise_floor.py`): final SSIM "
                 f"{nf['final_ldr']['ssim']:.4f}, PSNR {nf['final_ldr']['psnr']:.2f} dB; lightmap PSNR "
                 f"{nf['lightmap_linear']['psnr']:.2f} dB. No score below can be resolved more finely than this.")
        L.append("")
    head = ["variant", "GFLOP", "device MiB"]
    for d in devices:
        head += [f"{d} generator ms", f"{d} lightmap ms"]
    head += ["final SSIM", "final PSNR", "lightmap PSNR", "moving camera SSIM", "moving sun SSIM"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---|" * len(head))
    order = sorted(V, key=lambda n: (V[n]["kind"] == "direct", V[n]["kind"] == "legacy", V[n]["layout"], -V[n]["n"],
                                     -V[n]["ngf"], n))
    for name in order:
        v = V[name]
        h = v.get("heldout")
        if not h:
            continue
        first = next(iter(v.get("speed", {}).values()), {})
        mem = first.get("memory_mib") or {}
        row = [label(name, v) + KIND_LABEL[v["kind"]], fmt(first.get("gflop", 0.0 if v["kind"] == "direct" else None), ".2f"),
               fmt(sum(mem.get(k, 0) for k in ("arena", "scratch", "weights")) if mem else None, ".1f")]
        for d in devices:
            s = v.get("speed", {}).get(d)
            row += [fmt(s and s["generator_ms"], ".1f"), fmt(s and s["lightmap_ms"], ".0f")]
        t = v.get("temporal") or {}
        row += [fmt(h["final"]["ssim"], ".4f"), fmt(h["final"]["psnr"], ".2f"), fmt(h["lightmap"]["psnr"], ".2f"),
                fmt(t.get("moving_camera", {}).get("ssim"), ".4f"), fmt(t.get("moving_sun", {}).get("ssim"), ".4f")]
        L.append("| " + " | ".join(row) + " |")
    L.append("")

    for d in devices:
        for cost, metric in [(c, m) for c in ("lightmap_ms", "generator_ms") for m in ("psnr", "ssim")]:
            pts, front = fronts(summary, d, metric, cost)
            fp = sorted((ms, q, n) for n, ms, q in pts if n in front)
            what = "whole-command" if cost == "lightmap_ms" else "generator"
            L.append(f"Pareto front on {d}, {what} ms vs held-out final {metric.upper()} ({len(fp)} of {len(pts)} "
                     f"variants; the rest are dominated): " +
                     " → ".join(f"{n} ({ms:.1f} ms, {q:.4f})" if metric == "ssim" else f"{n} ({ms:.1f} ms, {q:.2f} dB)"
                                for ms, q, n in fp))
            L.append("")

    L.append("Temporal stability (tone-mapped final images; *excess* = model − reference: flicker the model adds):")
    L.append("")
    L.append("| variant | moving camera: SSIM | PSNR | warp error (ref) | MABD (ref) | moving sun: SSIM | PSNR | "
             "MABD (ref) |")
    L.append("|---|---|---|---|---|---|---|---|")
    for name in order:
        t = V[name].get("temporal")
        if not t or "moving_camera" not in t:
            continue
        c, s = t["moving_camera"], t["moving_sun"]
        L.append(f"| {label(name, V[name])}{KIND_LABEL[V[name]['kind']]} | {c['ssim']:.4f} | {c['psnr']:.2f} | "
                 f"{c['warp_error']:.4f} ({c['warp_error_reference']:.4f}) | {c['mabd']:.4f} ({c['mabd_reference']:.4f}) | "
                 f"{s['ssim']:.4f} | {s['psnr']:.2f} | {s['mabd']:.4f} ({s['mabd_reference']:.4f}) |")
    L.append("")

    if summary.get("pairs"):
        L.append("Surround-aware minus single view, same frames (held-out final images):")
        L.append("")
        L.append("| pair | frames | SSIM difference | PSNR difference (dB) | surround higher SSIM on |")
        L.append("|---|---|---|---|---|")
        for k, p in summary["pairs"].items():
            L.append(f"| {k} | {p['frames']} | {p['ssim']:+.4f} | {p['psnr']:+.2f} | {p['a_higher_ssim']} |")
        L.append("")

    for sw in summary.get("switch", []):
        L.append(f"Per-frame switch {sw['surround']} → {sw['single_view']} below an outside light share t "
                 f"({sw['frames']} held-out frames; chosen t = {sw['chosen']['below_outside_light_share']}: the "
                 f"largest within {sw['tolerance']['ssim']} SSIM / {sw['tolerance']['psnr']} dB of the surround rung):")
        L.append("")
        head = ["t", "frames switched", "SSIM", "PSNR"] + [f"{d} lightmap ms" for d in devices]
        L.append("| " + " | ".join(head) + " |")
        L.append("|" + "---|" * len(head))
        for r in sw["thresholds"]:
            L.append("| " + " | ".join([f"{r['below']:g}", str(r["switched_frames"]), f"{r['ssim']:.4f}",
                                        f"{r['psnr']:.2f}"] + [fmt(r["ms"].get(d, {}).get("lightmap_ms"), ".0f")
                                                               for d in devices]) + " |")
        L.append("")
        for seq, r in sw.get("sequences", {}).items():
            L.append(f"On the {seq.replace('_', ' ')} sequence at t = {sw['chosen']['below_outside_light_share']}: "
                     f"{r['switched']} of {r['frames']} frames switched; SSIM {r['ssim']:.4f} (surround only "
                     f"{r['ssim_surround_only']:.4f}), PSNR {r['psnr']:.2f} dB ({r['psnr_surround_only']:.2f}).")
        L.append("")
    return "\n".join(L) + "\n"


def cards(zoo):
    """models/ladder/README.md: one model card per shipped ladder rung (from the zoo manifest)."""
    L = ["# The ladder's models (issue 12)", "",
         "Pix2pix U-Net generators of the speed/accuracy ladder, all trained here with one recipe "
         "(training/configs/ladder.json) on the same frames (configs/dataset_clean_n64.json, or its N = 32 twin), "
         "exported with F16 weights; each file's metadata records its architecture, input layout, value ranges, "
         "batch-norm mode and training provenance (docs/MODEL_FORMAT.md). Measured cost and accuracy of every variant: "
         "[models/zoo.json](../zoo.json); the comparison: [docs/RESULTS.md](../../docs/RESULTS.md#the-ladder).", "",
         "Reproduce: `python3 -m ngi_train.generator.ladder` (two lanes, one core each), then "
         "`python3 -m ngi_train.generator.ladder_eval` (commands in docs/RESULTS.md).", ""]
    recipe = zoo["protocol"]["recipe"]
    L.append(f"Recipe (every rung): {recipe['steps']} steps, batch 1, Adam {recipe['lr']} / beta1 {recipe['beta1']}, "
             f"BCE + {recipe['lambda_l1']}·L1 (thesis eq. 4.10), PatchGAN ({recipe['d_layers']} layers, ndf "
             f"{recipe['ndf']}) on the front crop, lr linear to 0 over the last {recipe['decay_steps']} steps, "
             f"dropout in training, off at inference.")
    L.append("")
    for r in zoo["rungs"]:
        if r["kind"] != "rung":
            continue
        h = (r["accuracy"] or {}).get("heldout") or {}
        t = r.get("training") or {}
        what = ("the global view (6 faces merged to 4N x 2N, 12 channels)" if r["layout"] == "surround"
                else "the front face only (10 channels)")
        L.append(f"## `{r['file']}`")
        L.append("")
        L.append(f"- **Sees** {what}; N = {r['n']}, input {r['input']}; ngf {r['ngf']}, {r['num_downs']} "
                 f"downsamplings; {fmt(r.get('gflop'), '.2f')} GFLOP per frame.")
        L.append(f"- **Output**: the GI lightmap (direct + indirect diffuse, no albedo) of the "
                 f"{'global view (front view = exact crop)' if r['layout'] == 'surround' else 'front view'}; "
                 f"batch norm at inference: {r['bn_mode']} (chosen at export by L1 on frames of the held-out test split itself, not on a validation split: a known flaw of this record; scores in the file's training.bn_mode_selection).")
        L.append(f"- **Training**: {t.get('steps')} steps = {fmt(t.get('epochs'), '.1f')} epochs over "
                 f"{t.get('frames')} frames, seed {t.get('seed')}, {fmt((t.get('wall_seconds') or 0) / 60, '.0f')} "
                 f"min on one core of the 2-core machine.")
        if h:
            L.append(f"- **Held-out** ({h['frames']} frames of 6 unseen scenes, converged references): final SSIM "
                     f"{h['final']['ssim']:.4f}, PSNR {h['final']['psnr']:.2f} dB; lightmap PSNR "
                     f"{h['lightmap']['psnr']:.2f} dB.")
        costs = "; ".join(f"{d}: generator {c['generator_ms']:.1f} ms, whole `ngi lightmap` {c['lightmap_ms']:.0f} ms"
                          for d, c in r["cost"].items())
        L.append(f"- **Cost**: {costs}.")
        L.append(f"- **Limits**: trained on 20 procedural scenes at N = {r['n']}; one seed; see the zoo for the "
                 f"temporal metrics and the other batch-norm mode.")
        L.append("")
    return "\n".join(L) + "\n"


def write(summary, temporal, out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "ladder_tables.md").write_text(tables(summary))
    for d in summary["speed_devices"]:
        plot_pareto(summary, d, out / f"ladder_pareto_{d}.png")
    names = [n for n in ("surround_n64_ngf32", "single_view_n64_ngf32", "surround_n64_ngf8", "single_view_n64_ngf8",
                         "surround_n32_ngf32", "direct_only") if n in (temporal or {})]
    if names:
        plot_temporal(summary, temporal, names, out / "ladder_temporal.png")

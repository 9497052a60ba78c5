"""Model only what a scene requires: pick the cheapest zoo rung that meets a budget on this scene and device.

    python3 -m ngi.plan --scene room:seed=7 --min-ssim 0.85 --out plan.json        # cheapest rung that is good enough
    python3 -m ngi.plan --scene street:seed=3 --max-ms 300 --out plan.json         # best rung that fits the time
    ngi lightmap --frame F --plan plan.json --out DIR                              # run what the plan chose

It renders --frames calibration frames of the scene's camera path with converged references (ngi.Renderer), runs
every rung of the zoo (models/zoo.json, written by ngi_train.generator.ladder_eval) on them and scores each with
ngi.scoring, exactly as the ladder's held-out evaluation does. The cost of a rung is the zoo's measured ms per
frame on this device (--cost lightmap: the whole `ngi lightmap` command; generator: the network alone); a device
the zoo has not measured gets the rung's in-process pipeline time measured here instead.

Noise: two candidates are compared on the same calibration frames, pairwise. For each metric (final-image PSNR and
SSIM) the margin of a over b is the mean over the frames of a's score minus b's on the same frame, and its noise is
the standard error of that mean (sample standard deviation of the per-frame differences / sqrt(frames)), never less
than a floor of 0.1 dB PSNR / 0.002 SSIM (NOISE_FLOORS; with one calibration frame there is no spread to measure
and the floor alone is the noise). a is better than b beyond noise in a metric when the margin exceeds the noise,
worse beyond noise when it is below minus the noise, and within noise otherwise.

Choice: a rung earns its cost over a cheaper candidate only by being better beyond noise in at least one metric
and worse beyond noise in neither; a rung that does not earn it over every cheaper candidate is dominated and never
chosen. So a rung is not chosen for a metric it wins when a cheaper one is better in the other (a worse image for
a metric), nor for margins within noise (the cheaper one is as good as the frames can tell). The cheapest
candidate is never dominated. Among the rungs that are not dominated and fit the budget: with a quality floor
(--min-ssim / --min-psnr, on the mean over the calibration frames) the cheapest that meets it (and --max-ms, if
given); with only --max-ms the most expensive that fits, which by the rule above is within noise of or better than
every cheaper candidate in both metrics at once: the most accurate in PSNR and SSIM together, with no ranking of
one metric over the other needed. Only rungs of equal cost are ordered by a metric: PSNR first, then SSIM (SSIM
saturates near 1 where PSNR still separates images: the user's report that prompted this rule was a 4.4 dB worse
image that SSIM rated 0.002 better). choose() is that decision, pure (no device). Surround-aware rungs with a
measured per-frame switch in the zoo are also tried with it (frames with little light outside the front view run
the single-view twin; docs/RESULTS.md).

Validation: --validate K renders K other frames of the path (disjoint from the calibration frames) and scores the
chosen rung and every cheaper candidate on them. The plan records the chosen rung's margin over each cheaper
candidate on both frame sets, whether a quality floor held, and whether the choice held: a chosen rung that is
worse beyond noise (same definition, over the validation frames) than a cheaper candidate there did not hold; the
plan names those candidates and the planner prints a warning.

Candidates: the direct-light rung and the rungs that compute indirect light for the pipeline to add to the frame's
direct light: the rungs whose network predicts it (zoo "output_mode": "indirect") and the physics rungs (zoo
"kind": "ssgi": no network, the pipeline gathers light over the frame's faces with the model file's settings),
each as exported. The thesis-mode rungs (the network predicts the whole lightmap; they lose to direct light alone on
the held-out split, docs/RESULTS.md) and the other batch-norm mode of each rung are measured comparisons, tried only
with --all-rungs. A zoo with no indirect-light rung offers all of its rungs. A rung with a measured per-frame guard
in the zoo (rung "guard": {"max_indirect_share": t}, ngi_train.generator.gi_eval) runs with it (a frame whose
indirect share exceeds t falls back to direct light: ngi.indirect_share, `ngi lightmap --guard`), and the plan
records it.

Adapted models (--adapted M, written by ngi_train.adapt: a network fitted to one scene, docs/ADAPT.md) join the
candidates, with their cost measured here, only for the scene they were fitted to: the model's "adapt" record
names the scene and, for a file, its content digest; another scene is refused (exit code 1, nothing written).

Nothing meets the budget (or only rungs that a cheaper candidate dominates do): exit code 1, the closest rung (or
the dominated rung and its margins) named, nothing written. The plan is JSON ("format": "ngi-plan", version 1;
docs/MODEL_FORMAT.md): the rung, its model file relative to the plan's folder, bn_mode, face size n, the optional
switch, and the calibration and validation evidence. read_plan() reads one back strictly (`ngi lightmap --plan` is
the C++ reader, samples/ngi/plan_file.cpp).
"""

import argparse
import errno
import json
import os
import stat
import sys
import time
from pathlib import Path

import numpy as np

from . import _constants, _ngi, model_file, scoring, zoo as zoo_mod

DEFAULT_ZOO = Path(os.environ.get("NGI_ZOO", "models/zoo.json"))  # the repository's, run from its root
PATH_FRAMES = 100
# The metrics a choice weighs (module doc, "Noise"): score key, margin key in the plan, noise floor. A floor is the
# least a margin must exceed to count even when the frames agree on it exactly (one frame, or the same difference
# on every frame): a rung is not worth its cost for less than 0.1 dB or 0.002 SSIM (the SSIM margin by which a rung
# 4.4 dB worse than direct light was once chosen). PSNR first: it orders rungs of equal cost.
METRICS = (("psnr", "psnr_db", 0.1), ("ssim", "ssim", 0.002))
NOISE_FLOORS = {key: floor for _, key, floor in METRICS}


class PlanError(Exception):
    """No rung meets the budget, or only dominated ones do (the message names the closest or dominated one)."""


class PlanFileError(ValueError):
    """A plan file that cannot be used: the message names the file and what is wrong."""


MAX_PLAN_BYTES = 64 << 20  # a plan is a few KB; the cap keeps a wrong file from filling the memory


def read_plan(path):
    """The plan at `path` (a dict), read strictly. The model paths are checked (relative to the plan's folder) and
    left as written.

    Refused with PlanFileError: a file that is not a regular file (model_file's rule), not JSON, a key twice in one
    object (Python's json, like most JSON readers, would silently keep the last one), not format "ngi-plan" version
    1, and a rung whose model file is missing or is not a regular file (saying which: a FIFO, a device, a folder)."""
    path = Path(path)
    try:
        text = model_file.read_input_file(path, MAX_PLAN_BYTES).decode("utf-8")
    except model_file.ConversionError as e:
        raise PlanFileError(str(e)) from None  # "cannot read PATH: it is a FIFO, ..."
    except UnicodeDecodeError as e:
        raise PlanFileError(f"plan {path}: not UTF-8 text: {e}") from None

    def unique_keys(pairs):
        seen = set()
        for key, _ in pairs:
            if key in seen:
                raise PlanFileError(f"plan {path}: the key {key!r} appears twice in one object")
            seen.add(key)
        return dict(pairs)

    try:
        p = json.loads(text, object_pairs_hook=unique_keys)
    except PlanFileError:
        raise
    except ValueError as e:
        raise PlanFileError(f"plan {path}: not valid JSON: {e}") from None
    if not isinstance(p, dict) or p.get("format") != "ngi-plan":
        raise PlanFileError(f"plan {path}: not a plan (\"format\": \"ngi-plan\")")
    if p.get("version") != 1:
        raise PlanFileError(f"plan {path}: version {p.get('version')!r}; this ngi reads version 1")
    for where, rung in (("the top level", p), ("switch", p.get("switch"))):
        if rung is None:
            continue
        if not isinstance(rung, dict) or "model" not in rung:
            raise PlanFileError(f"plan {path}: {where} has no 'model'")
        if rung["model"] is None:  # the direct-light rung: no network
            continue
        if not isinstance(rung["model"], str) or not rung["model"]:
            raise PlanFileError(f"plan {path}: {where}.model must be a non-empty string or null")
        model = path.parent / rung["model"]  # relative to the plan's folder (an absolute path stays itself)
        try:
            mode = os.stat(model).st_mode  # follows links: a link to /dev/zero is a device
            what = None if stat.S_ISREG(mode) else f"is {model_file.file_kind(mode)}"
        except OSError as e:
            what = "does not exist" if e.errno == errno.ENOENT else f"cannot be read: {e.strerror}"
        if what:
            raise PlanFileError(f"plan {path}: {where}.model: {model} {what} (rung {rung.get('rung', '?')})")
    return p


def progress(iterable, desc):
    try:
        import tqdm
        return tqdm.tqdm(iterable, desc=desc, unit="frame", file=sys.stderr, mininterval=1.0)
    except ImportError:  # tqdm is a Debian package (python3-tqdm); without it the plan still works, silently
        return iterable


def frame_indices(count, offset):
    """`count` path frames spread over the path, shifted by `offset` of the spacing (0.25 calibration, 0.75
    validation: disjoint sets)."""
    step = PATH_FRAMES / count
    return sorted({min(PATH_FRAMES - 1, int((k + offset) * step)) for k in range(count)})


def render(renderer, ns, idx, args):
    """Frame idx of the path at every face size in ns: {n: Frame}, the largest with a reference."""
    top = max(ns)
    out = {}
    for n in ns:
        out[n] = renderer.render(n=n, spp=args.spp, feature_spp=args.feature_spp, reference=(n == top),
                                 time=args.time, frame=idx, frames=PATH_FRAMES)
    return out


class Evaluator:
    def __init__(self, device, zoo):
        self.device, self.zoo = device, zoo
        self.models, self.pipes = {}, {}

    def pipe(self, n):
        if n not in self.pipes:
            self.pipes[n] = _ngi.Pipeline(self.device, n)
        return self.pipes[n]

    def model(self, rung):
        if rung["name"] not in self.models:
            # An ssgi rung has no batch norm (bn_mode null): its file's own settings.
            self.models[rung["name"]] = _ngi.Model(self.device, rung["path"], bn_mode=rung.get("bn_mode"))
        return self.models[rung["name"]]

    def lightmap(self, rung, frames):
        if rung["path"] is None:  # the direct-light rung
            return frames[rung["n"]].feature("direct")[0]
        return self.pipe(rung["n"]).run(self.model(rung), frames[rung["n"]], outputs=("lightmap",))["lightmap"]

    def time_ms(self, rung, frames, repeats=5):
        """In-process pipeline time of one frame (median after a warm-up), for devices the zoo has not measured."""
        if rung["path"] is None:
            return 0.0
        self.lightmap(rung, frames)
        ts = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            self.lightmap(rung, frames)
            ts.append((time.perf_counter() - t0) * 1e3)
        return float(np.median(ts))


def frame_scores(psnr, ssim, switched=0):
    """A candidate's final-image scores over a frame set: per frame, in the frame set's order (comparisons pair the
    frames), and the means a quality floor is about."""
    psnr, ssim = [float(x) for x in psnr], [float(x) for x in ssim]
    return {"ssim": float(np.mean(ssim)), "psnr": float(np.mean(psnr)), "switched": switched, "frames": len(ssim),
            "per_frame": {"psnr": psnr, "ssim": ssim}}


def score_all(ev, candidates, frame_sets):
    """frame_scores of every candidate over the frame sets, and the per-frame outside light shares."""
    top = max(max(fs) for fs in frame_sets)
    scores = {c["name"]: {"ssim": [], "psnr": [], "switched": 0} for c in candidates}
    shares = []
    for frames in frame_sets:
        ref = scoring.Reference(ev.device, ev.pipe(top), frames[top])
        share = _ngi.outside_light_share(frames[top])
        shares.append(share)
        cache = {}
        for c in candidates:
            rung = c["rung"]
            if c.get("switch") and share < c["switch"]["below_outside_light_share"]:
                rung = c["twin"]
                scores[c["name"]]["switched"] += 1
            if rung["name"] not in cache:
                lm = ev.lightmap(rung, frames)
                guard = (rung.get("guard") or {}).get("max_indirect_share")
                if guard is not None and _ngi.indirect_share(frames[rung["n"]], lm) > guard:
                    lm = frames[rung["n"]].feature("direct")[0]  # the guard's fallback: direct light alone
                cache[rung["name"]] = ref.score(lm)["final"]
            s = cache[rung["name"]]
            scores[c["name"]]["ssim"].append(s["ssim"])
            scores[c["name"]]["psnr"].append(s["psnr"])
    return {k: frame_scores(v["psnr"], v["ssim"], v["switched"]) for k, v in scores.items()}, shares


def meets(c, s, args):
    return ((args.max_ms is None or c["ms"] <= args.max_ms) and (args.min_ssim is None or s["ssim"] >= args.min_ssim)
            and (args.min_psnr is None or s["psnr"] >= args.min_psnr))


def shortfall(c, s, args):
    """Relative distance from the budget (0 = meets it)."""
    d = 0.0
    if args.max_ms is not None:
        d += max(0.0, c["ms"] / max(args.max_ms, 1e-9) - 1.0)
    if args.min_ssim is not None:
        d += max(0.0, (args.min_ssim - s["ssim"]) / max(args.min_ssim, 1e-9))
    if args.min_psnr is not None:
        d += max(0.0, (args.min_psnr - s["psnr"]) / max(args.min_psnr, 1e-9))
    return d


def margin(a, b):
    """a's margin over b (frame_scores of the same frames): per metric the mean paired difference and its noise
    (module doc, "Noise")."""
    if a["frames"] != b["frames"]:
        raise ValueError(f"margins pair frames: {a['frames']} frames against {b['frames']}")
    out = {}
    for m, key, floor in METRICS:
        d = np.subtract(a["per_frame"][m], b["per_frame"][m])
        se = np.std(d, ddof=1) / np.sqrt(d.size) if d.size > 1 else 0.0
        out[key], out[f"noise_{key}"] = float(d.mean()), float(max(se, floor))
    return out


def beyond_noise(mg, sign):
    """The metrics (margin keys) in which the margin `mg` is beyond its noise: above it (sign +1) or below minus it
    (sign -1)."""
    return [key for _, key, _ in METRICS if sign * mg[key] > mg[f"noise_{key}"]]


def margin_text(mg):
    return (f"PSNR {mg['psnr_db']:+.2f} dB (noise {mg['noise_psnr_db']:.2f}), "
            f"SSIM {mg['ssim']:+.4f} (noise {mg['noise_ssim']:.4f})")


def cheaper(cand, candidates):
    """The candidates that cost less than `cand`, cheapest first."""
    return sorted((c for c in candidates if c["ms"] < cand["ms"]), key=lambda c: c["ms"])


def margins_over(cand, others, scores):
    return {c["name"]: margin(scores[cand["name"]], scores[c["name"]]) for c in others}


def dominated_by(cand, candidates, scores):
    """(name, cand's margin over it) of the cheapest candidate that `cand` does not earn its cost over (module doc,
    "Choice"), or None: cand is not dominated."""
    for name, mg in margins_over(cand, cheaper(cand, candidates), scores).items():
        if beyond_noise(mg, -1) or not beyond_noise(mg, +1):
            return name, mg
    return None


def choose(candidates, scores, budget):
    """The choice (module doc, "Choice"), pure: candidates [{"name", "ms"}, ...], scores {name: frame_scores} on
    the calibration frames, budget with max_ms, min_ssim, min_psnr (and cost, for messages). Returns (the chosen
    candidate, why, its margins over each cheaper candidate); raises PlanError."""
    ok = [c for c in candidates if meets(c, scores[c["name"]], budget)]
    eligible = [c for c in ok if dominated_by(c, candidates, scores) is None]
    if not eligible and ok:
        c = min(ok, key=lambda c: c["ms"])
        name, mg = dominated_by(c, candidates, scores)
        raise PlanError(f"only rungs that a cheaper candidate matches or beats meet the budget ({budget_text(budget)}) "
                        f"on these calibration frames; the cheapest of them, {c['name']} ({c['ms']:.1f} ms), does "
                        f"not earn its cost over {name}: {margin_text(mg)}")
    if not eligible:
        closest = min(candidates, key=lambda c: shortfall(c, scores[c["name"]], budget))
        s = scores[closest["name"]]
        raise PlanError(f"no rung meets the budget ({budget_text(budget)}) on these calibration frames; the closest "
                        f"is {closest['name']}: {closest['ms']:.1f} ms, SSIM {s['ssim']:.4f}, PSNR {s['psnr']:.2f} dB")

    def accuracy(c):  # PSNR, then SSIM: orders rungs of equal cost only (module doc)
        return tuple(scores[c["name"]][m] for m, _, _ in METRICS)

    if budget.min_ssim is not None or budget.min_psnr is not None:
        least = min(c["ms"] for c in eligible)
        pick = max((c for c in eligible if c["ms"] == least), key=accuracy)
        why = (f"the cheapest of {len(eligible)} undominated candidates that meet {budget_text(budget)} on "
               f"{scores[pick['name']]['frames']} calibration frames")
    else:
        pick = max(eligible, key=lambda c: (c["ms"], accuracy(c)))
        why = (f"the most accurate of {len(eligible)} undominated candidates within {budget_text(budget)}: within "
               f"noise of or better than every cheaper candidate in PSNR and SSIM")
    return pick, why, margins_over(pick, cheaper(pick, candidates), scores)


def validate(pick, candidates, scores):
    """On the validation frames (scores: frame_scores of the pick and every cheaper candidate): the pick's margins
    over each cheaper candidate, and the names of those it is worse than beyond noise (the choice did not hold)."""
    margins = margins_over(pick, cheaper(pick, candidates), scores)
    return margins, [name for name, mg in margins.items() if beyond_noise(mg, -1)]


def budget_text(args):
    parts = []
    if args.max_ms is not None:
        parts.append(f"<= {args.max_ms:g} ms per frame ({args.cost})")
    if args.min_ssim is not None:
        parts.append(f"SSIM >= {args.min_ssim:g}")
    if args.min_psnr is not None:
        parts.append(f"PSNR >= {args.min_psnr:g} dB")
    return ", ".join(parts)


def computes_indirect(rung):
    """A rung whose output the pipeline adds to the frame's direct light: an indirect-light network, ssgi, or a
    network that corrects ssgi."""
    return rung.get("kind") == "ssgi" or (rung.get("kind") == "rung"
                                          and rung.get("output_mode") in ("indirect", "ssgi_residual"))


def default_rungs(zoo, all_rungs=False):
    """The rungs the planner offers (module doc, "Candidates")."""
    rungs = zoo["rungs"]
    if all_rungs or not any(computes_indirect(r) for r in rungs):
        return rungs
    return [r for r in rungs if r["file"] is None or computes_indirect(r)]


def adapted_rungs(paths, scene_spec, scene_name):
    """Rungs of models fitted to one scene by ngi_train.adapt (their "adapt" record): each is offered only for the
    scene it was adapted to (its name, and for a file its content digest); PlanError names the model otherwise."""
    rungs = []
    for path in paths:
        try:
            cfg = model_file.read_config(str(path))
        except (OSError, model_file.ConversionError) as e:
            raise PlanError(f"--adapted {path}: {e}") from None
        rec = cfg.get("adapt")
        if not isinstance(rec, dict) or "scene" not in rec:
            raise PlanError(f"--adapted {path}: not written by ngi_train.adapt (no adapt record)")
        spec = Path(scene_spec)
        digest = zoo_mod.sha256(spec)[:16] if spec.is_file() else None  # as ngi_train.adapt records it
        if rec["scene"] != scene_name or (digest is not None and rec.get("scene_digest") != digest):
            raise PlanError(f"--adapted {path}: adapted to {rec['scene']} (sha256 {rec.get('scene_digest')}), not to "
                            f"{scene_name}" + (f" (sha256 {digest})" if digest else "") +
                            ": an adapted model is offered only for the scene it was fitted to")
        rungs.append({"name": f"adapted:{Path(path).stem}", "kind": "rung", "file": str(path),
                      "path": str(Path(path).resolve()), "n": 64, "bn_mode": None,
                      "output_mode": cfg.get("output_mode"), "cost": {}})
    return rungs


def candidates_of(zoo, ev, key, args, frames, extra=()):
    cands = []
    for r in [*default_rungs(zoo, getattr(args, "all_rungs", False)), *extra]:
        if key is not None and key in r["cost"]:
            ms = r["cost"][key][f"{args.cost}_ms"]
            basis = f"zoo, {key}, {args.cost}"
        else:
            ms = ev.time_ms(r, frames)
            basis = "measured here (in-process pipeline)"
        cands.append({"name": r["name"], "rung": r, "ms": ms, "cost_basis": basis})
    offered = {c["name"] for c in cands}
    for sw in zoo.get("switches") or []:
        if sw["surround"] in offered and sw["single_view"] in offered and sw["below_outside_light_share"] > 0:
            base = next(c for c in cands if c["name"] == sw["surround"])
            twin = next(c for c in cands if c["name"] == sw["single_view"])
            cands.append({"name": f"{sw['surround']}+switch", "rung": base["rung"], "twin": twin["rung"],
                          "switch": sw, "ms_each": (base["ms"], twin["ms"]), "ms": base["ms"],
                          "cost_basis": base["cost_basis"]})
    return cands


def rung_json(rung, plan_dir, with_guard=True):
    """A plan's rung entry; the guard only at the top level (ngi lightmap --plan applies it to the frame)."""
    out = {"rung": rung["name"], "n": rung["n"],
           "model": os.path.relpath(rung["path"], plan_dir) if rung["path"] else None}
    if rung["path"]:
        if rung.get("bn_mode"):  # an ssgi rung has none
            out["bn_mode"] = rung["bn_mode"]
        if with_guard and (rung.get("guard") or {}).get("max_indirect_share") is not None:
            out["guard"] = {"max_indirect_share": rung["guard"]["max_indirect_share"]}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m ngi.plan", description=__doc__.split("\n\n")[0],
                                 epilog="See the module documentation (pydoc ngi.plan).")
    ap.add_argument("--scene", required=True, help="room|street|cave|backlit|bleed[:seed=S] or a .vox file")
    ap.add_argument("--out", required=True, type=Path, help="the plan to write (JSON)")
    ap.add_argument("--zoo", type=Path, default=DEFAULT_ZOO, help="the zoo manifest [default: $NGI_ZOO, else %(default)s]")
    ap.add_argument("--max-ms", type=float, help="time budget per frame on this device")
    ap.add_argument("--min-ssim", type=float, help="quality floor: mean final-image SSIM")
    ap.add_argument("--min-psnr", type=float, help="quality floor: mean final-image PSNR (dB)")
    ap.add_argument("--cost", choices=("lightmap", "generator"), default="lightmap",
                    help="which measured time the budget is about [default: %(default)s]")
    ap.add_argument("--frames", type=int, default=4, help="calibration frames [default: %(default)s]")
    ap.add_argument("--validate", type=int, default=4, help="validation frames (0: none) [default: %(default)s]")
    ap.add_argument("--spp", type=int, default=1024, help="reference samples per pixel [default: %(default)s]")
    ap.add_argument("--feature-spp", type=int, default=_constants.ENGINE_FEATURE_SPP,
                    help="direct-light feature spp; the default is converged, an engine's input [default: %(default)s]")
    ap.add_argument("--time", type=float, default=None, help="time of day (hours) [default: the scene's]")
    ap.add_argument("--device", default="", help="OpenCL device (ngi.Device spec) [default: ngi's choice]")
    ap.add_argument("--all-rungs", action="store_true",
                    help="also try the thesis-mode rungs and the other batch-norm modes (measured comparisons)")
    ap.add_argument("--adapted", action="append", default=[], type=Path, metavar="M.safetensors",
                    help="also a model fitted to this scene by ngi_train.adapt (repeatable; refused for another scene)")
    args = ap.parse_args(argv)
    if args.max_ms is None and args.min_ssim is None and args.min_psnr is None:
        ap.error("give a budget: --max-ms, --min-ssim and/or --min-psnr")
    for name in ("frames", "spp", "feature_spp"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')} must be at least 1")
    if args.validate < 0:
        ap.error("--validate must be 0 or more")
    try:
        model_file.check_output_file(args.out)  # a folder, /dev/null, a FIFO: the rename at the end would replace it
    except model_file.ConversionError as e:
        ap.error(str(e))

    try:
        zoo = zoo_mod.load(args.zoo)
    except zoo_mod.ZooError as e:
        print(f"ngi.plan: {e}", file=sys.stderr)
        return 1
    dev = _ngi.Device(args.device)
    info = dev.info
    key = zoo_mod.device_key(zoo, info)
    scene = _ngi.Scene(args.scene)
    try:
        adapted = adapted_rungs(args.adapted, args.scene, scene.name)
    except PlanError as e:
        print(f"ngi.plan: {e}; nothing written", file=sys.stderr)
        return 1
    renderer = _ngi.Renderer(dev, scene)
    ev = Evaluator(dev, zoo)
    ns = sorted({r["n"] for r in [*default_rungs(zoo, args.all_rungs), *adapted]})  # the face sizes offered
    cal_idx = frame_indices(args.frames, 0.25)
    cal = [render(renderer, ns, i, args) for i in progress(cal_idx, "calibration frames")]
    cands = candidates_of(zoo, ev, key, args, cal[0], adapted)
    scores, shares = score_all(ev, cands, cal)
    for c in cands:  # a switch's cost: the mean over the calibration frames of the rung it ran
        if c.get("switch"):
            k = scores[c["name"]]["switched"]
            c["ms"] = (c["ms_each"][0] * (len(cal) - k) + c["ms_each"][1] * k) / len(cal)

    dominated = {}  # name: {"rung": the cheaper candidate it does not earn its cost over, its margins} or None
    for c in cands:
        d = dominated_by(c, cands, scores)
        dominated[c["name"]] = {"rung": d[0], **d[1]} if d else None
    print(f"{'rung':40s} {'ms':>9s} {'SSIM':>7s} {'PSNR':>6s}  meets  dominated by", file=sys.stderr)
    for c in sorted(cands, key=lambda c: c["ms"]):
        s, d = scores[c["name"]], dominated[c["name"]]
        print(f"{c['name']:40s} {c['ms']:9.1f} {s['ssim']:7.4f} {s['psnr']:6.2f}  "
              f"{'yes' if meets(c, s, args) else 'no':5s}  {d['rung'] if d else '-'}", file=sys.stderr)
    try:
        pick, why, margins = choose(cands, scores, args)
    except PlanError as e:
        print(f"ngi.plan: {e}; nothing written", file=sys.stderr)
        return 1
    s = scores[pick["name"]]

    validation = None
    if args.validate:
        val_idx = [i for i in frame_indices(args.validate, 0.75) if i not in cal_idx]
        val = [render(renderer, ns, i, args) for i in progress(val_idx, "validation frames")]
        vs, _ = score_all(ev, [pick, *cheaper(pick, cands)], val)
        v = vs[pick["name"]]
        val_margins, beaten_by = validate(pick, cands, vs)
        # Only a quality floor is a promise about other frames (a time budget is kept by the zoo's measured ms).
        kept = None
        if args.min_ssim is not None or args.min_psnr is not None:
            kept = ((args.min_ssim is None or v["ssim"] >= args.min_ssim) and
                    (args.min_psnr is None or v["psnr"] >= args.min_psnr))
        validation = {"frames": val_idx, "ssim": v["ssim"], "psnr": v["psnr"], "switched": v["switched"],
                      "kept_quality_promise": kept, "margins": val_margins, "choice_held": not beaten_by,
                      "beaten_by": beaten_by}

    plan_dir = args.out.resolve().parent
    plan = {"format": "ngi-plan", "version": 1, **rung_json(pick["rung"], plan_dir)}
    if pick.get("switch"):
        plan["switch"] = {"below_outside_light_share": pick["switch"]["below_outside_light_share"],
                          **rung_json(pick["twin"], plan_dir, with_guard=False)}
    plan.update({
        "scene": scene.name, "device": {"name": info.get("name"), "platform": info.get("platform"), "zoo_key": key},
        "budget": {"max_ms": args.max_ms, "min_ssim": args.min_ssim, "min_psnr": args.min_psnr, "cost": args.cost},
        "why": f"{pick['name']}: {why}: {pick['ms']:.1f} ms ({pick['cost_basis']}), SSIM {s['ssim']:.4f}, "
               f"PSNR {s['psnr']:.2f} dB",
        "calibration": {"frames": cal_idx, "path_frames": PATH_FRAMES, "spp": args.spp, "feature_spp": args.feature_spp,
                        "outside_light_share": shares, "noise_floor": NOISE_FLOORS,
                        "rungs": [{"name": c["name"], "ms": c["ms"], **scores[c["name"]],
                                   "meets": meets(c, scores[c["name"]], args),
                                   "dominated_by": dominated[c["name"]]} for c in cands],
                        "margins": margins},
        "validation": validation, "zoo": os.path.relpath(args.zoo.resolve(), plan_dir)})
    if plan["model"] is None:
        plan["note"] = "direct light only: no network runs (ngi lightmap --plan uses the frame's direct light)"
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        model_file.write_file_atomic(args.out, lambda f: f.write((json.dumps(plan, indent=1) + "\n").encode()))
    except (OSError, model_file.ConversionError) as e:
        print(f"ngi.plan: {e}; nothing written", file=sys.stderr)
        return 1
    print(f"plan: {plan['why']}", file=sys.stderr)
    if validation:
        kept = validation["kept_quality_promise"]
        verdict = ("no quality floor asked" if kept is None else "quality promise kept" if kept
                   else "quality promise NOT kept")
        print(f"validation on {len(validation['frames'])} other frames: SSIM {validation['ssim']:.4f}, PSNR "
              f"{validation['psnr']:.2f} dB: {verdict}", file=sys.stderr)
        for name in validation["beaten_by"]:
            print(f"ngi.plan: warning: the choice did not hold on the validation frames: {pick['name']} is worse "
                  f"than the cheaper {name} beyond noise: {margin_text(validation['margins'][name])}", file=sys.stderr)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Export a training checkpoint as an ngi model file (.safetensors, docs/MODEL_FORMAT.md).

    PYTHONPATH=training:build/python /usr/bin/python3 -m ngi_train.generator.export --run runs/surround \\
        --out models/surround.safetensors

The generator's state_dict goes through ngi.convert.validate_state_dict (the tensor names are junyanz's, checked
with their shapes against the config; num_batches_tracked is dropped) into ngi.model_file.write_model. The
config says how ngi must run it:
  family pix2pix_unet, input_nc 12 (surround) or 10 (single view), output_nc 3, ngf, num_downs,
  input_layout   the C++ channel names (surround_input_channels / single_view_input_channels)
  input_range, output_range  [-1, 1]
  output_mode    the training config's: "lightmap" (the output is the whole lightmap) or "indirect" (indirect
                 light, which ngi adds to the frame's direct light)
  bn_mode        --bn-mode per_image | running | auto (default): auto scores both on held-out frames (the
                 eval split, dropout as exported) with the L1 of the training loss and keeps the better one
  dropout        --dropout off (default: nn.Dropout's expectation, deterministic) | seeded (pix2pix's
                 test-time dropout, ngi's hashed mask with --dropout-seed)
and, under "training" (ignored by the C++ loader, kept in ModelConfig::json): the training config, the
dataset folder and its dataset.json, frame count, steps, epochs, training wall time, the bn_mode scores, the
lumination transfer and global-view mode the targets were encoded with.

The written file is read back and checked against the checkpoint.
"""

import argparse
import datetime
import json
import sys
from pathlib import Path

import numpy as np
import torch

import ngi.convert as convert
import ngi.model_file as model_file

from ngi_train import checkpoint
from ngi_train.generator import data, evaluate


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", required=True, help="run folder of train.py")
    ap.add_argument("--checkpoint", help="checkpoint file (default RUN/checkpoints/latest.pt)")
    ap.add_argument("--out", required=True, help="output .safetensors")
    ap.add_argument("--bn-mode", default="auto", choices=("auto", "per_image", "running"))
    ap.add_argument("--dropout", default="off", choices=("off", "seeded"))
    ap.add_argument("--dropout-seed", type=int, default=0)
    ap.add_argument("--eval-split", help="held-out split for --bn-mode auto (default: the config's eval_split)")
    ap.add_argument("--eval-frames", type=int, default=100, help="held-out frames scored for auto (0 = all)")
    ap.add_argument("--dataset", help="dataset folder (default: the one the run was trained on)")
    ap.add_argument("--device", help="OpenCL device for merging held-out frames (ngi.Device spec)")
    ap.add_argument("--half", action="store_true", help="store F16 tensors")
    args = ap.parse_args(argv)

    run = Path(args.run)
    ckpt_path = Path(args.checkpoint) if args.checkpoint else run / "checkpoints" / "latest.pt"
    state = checkpoint.load(ckpt_path)
    cfg, n = state["config"], state["n"]
    run_info = json.loads((run / "run.json").read_text()) if (run / "run.json").is_file() else {}
    dataset_dir = Path(args.dataset or state["dataset"])
    g_state = state["model"]["G"]

    selection = None
    bn_mode = args.bn_mode
    if bn_mode == "auto":
        split = args.eval_split or cfg["eval_split"]
        cache_dir = Path(cfg["cache_dir"]) if cfg["cache_dir"] else data.default_cache_dir(dataset_dir, cfg["layout"])
        eval_set, _, _ = data.load_split(dataset_dir, split, cfg["layout"], cache_dir, device=args.device,
                                         max_frames=args.eval_frames)
        scores = {mode: evaluate.heldout_scores(g_state, cfg, eval_set, n, mode, args.dropout, args.dropout_seed)
                  for mode in ("per_image", "running")}
        bn_mode = min(scores, key=lambda m: scores[m]["l1"])
        selection = {"criterion": f"lower mean L1 (output encoding, front view) on {len(eval_set)} frames of "
                                  f"split '{split}'", "scores": scores, "chosen": bn_mode}
        for mode, s in scores.items():
            print(f"bn_mode {mode:9s}: L1 {s['l1']:.5f}  PSNR(enc) {s['psnr_enc']:.2f} dB  "
                  f"MSE(linear) {s['mse_linear']:.5g}  on {s['frames']} {split} frames"
                  + ("   <- chosen" if mode == bn_mode else ""), file=sys.stderr)

    config = model_file.make_config("pix2pix_unet", bn_mode=bn_mode, input_nc=data.input_nc(cfg["layout"]),
                                    output_nc=3, ngf=cfg["ngf"], num_downs=cfg["num_downs"], dropout=args.dropout,
                                    dropout_seed=args.dropout_seed, input_layout=data.channels(cfg["layout"]),
                                    output_mode=("ssgi_residual" if data.is_residual(cfg["layout"])
                                                 else cfg.get("output_mode", "lightmap")),
                                    source=f"ngi_train.generator.train, run {run.resolve().name}, step {state['step']}")
    if data.is_residual(cfg["layout"]):
        # The gather the network corrects travels with it: the settings its training inputs were made with (the
        # merge cache records them), not the rung file's settings of today.
        cache_dir = Path(cfg["cache_dir"]) if cfg["cache_dir"] else data.default_cache_dir(dataset_dir, cfg["layout"])
        info_path = cache_dir / "cache.json"
        if not info_path.is_file() or "ssgi" not in json.loads(info_path.read_text()):
            raise SystemExit(f"{info_path}: no record of the SSGI gather the training inputs were made with")
        config["ssgi"] = json.loads(info_path.read_text())["ssgi"]
        if config["ssgi"] != data.ssgi_gather(data.SSGI_BASES[cfg["layout"]]):
            print(f"warning: {data.SSGI_BASES[cfg['layout']]}'s settings changed since training; the model keeps "
                  f"the ones it was trained with: {config['ssgi']}", file=sys.stderr)
        config["required"] = sorted(set(config.get("required", [])) | {"ssgi"})
    steps = state["step"]
    samples = state.get("samples", steps)  # checkpoints from before the effective batch: one image per step
    config["training"] = {
        "layout": cfg["layout"],
        "steps": steps,
        "samples": samples,
        "effective_batch": state.get("effective_batch", 1),
        "epochs": samples / state["frames"],
        "frames": state["frames"],
        "frames_digest": state["frames_digest"],
        "wall_seconds": round(state["train_seconds"], 1),
        "dataset": str(dataset_dir),
        "dataset_config": run_info.get("dataset_config"),
        "config": cfg,
        "bn_mode_selection": selection,
        "lumination_transfer": "reinhard",
        "global_view_mode": "thesis",
        "target": "reference.exr encoded by SurroundPipeline::encode_lightmap (ngi merge target.npy)"
                  + ("; the output is indirect light, the loss sees direct + indirect encoded the same way"
                     if config["output_mode"] != "lightmap" else "")
                  + (f"; the output corrects {data.SSGI_BASES[cfg['layout']]}'s indirect light (added to its encoded input channels)"
                     if config["output_mode"] == "ssgi_residual" else ""),
        "checkpoint": str(ckpt_path),  # as given (relative to the working directory): no machine paths in shipped files
        "exported": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "torch": torch.__version__,
    }
    tensors = convert.validate_state_dict(g_state, config)  # name -> float32 array, upstream order
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    model_file.write_model(str(tmp), tensors, config, half=args.half)
    back, back_config = model_file.read_model(str(tmp))
    if back_config != config or list(back) != list(tensors):
        raise RuntimeError(f"{tmp}: read back a different config or tensor list")
    for name, t in tensors.items():
        want = t.astype(np.float16) if args.half else t
        if not np.array_equal(back[name], want):
            raise RuntimeError(f"{tmp}: tensor {name} differs after the round trip")
    tmp.replace(out)
    print(f"exported {out}: {cfg['layout']}, ngf {cfg['ngf']}, num_downs {cfg['num_downs']}, bn_mode {bn_mode}, "
          f"dropout {args.dropout}, step {steps} ({samples / state['frames']:.1f} epochs), "
          f"{len(tensors)} tensors", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

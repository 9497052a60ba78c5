#!/usr/bin/python3
"""What one evaluation of an OpenCL C built-in math function costs on a device, scalar and in vector lanes.

Why: on PoCL 3.1 a kernel's scalar sin, cos, log, pow or tanh runs one value at a time (its work-group vectorizer
does not widen those calls), 10-25x the cost per value of the same function on a float8, while exp, sqrt and plain
arithmetic vectorize either way. ngi's kernels avoid the slow forms where they are hot (activation.cl's tanh,
mlp.cl's encoding in vector lanes, gather_image.cl's sRGB table, jbu.cl's integer power; docs/PERFORMANCE.md,
"Small shapes"); this measures the trade on any device, so the next kernel and the next platform can be judged.

Each function is applied once per element of 2^21 floats (one kernel per function and width, local size 64), the
median of --repeats runs after a warm-up, reported as nanoseconds per value, with the worst error in ulp against
NumPy float64 on the same inputs. Prints one JSON object.

Usage: /usr/bin/python3 perf/builtin_cost.py [--platform Portable] [--widths 1 4 8] [--repeats 7] [--out F.json]
  (Mesa rusticl: RUSTICL_ENABLE=llvmpipe ... --platform rusticl). Needs python3-pyopencl.
"""
import argparse
import datetime
import json
import statistics
import time

import numpy as np
import pyopencl as cl

# name -> (OpenCL expression of v, NumPy float64 reference, input range)
FUNCTIONS = {
    "copy": ("v * 1.0001f", lambda x: x * 1.0001, (-3, 3)),
    "exp": ("exp(v)", np.exp, (-10, 10)),
    "exp2": ("exp2(v)", np.exp2, (-10, 10)),
    "log": ("log(v)", np.log, (1e-3, 100)),
    "log2": ("log2(v)", np.log2, (1e-3, 100)),
    "sin": ("sin(v)", np.sin, (-50, 50)),
    "cos": ("cos(v)", np.cos, (-50, 50)),
    "tanh": ("tanh(v)", np.tanh, (-6, 6)),
    "pow": ("pow(v, 2.4f)", lambda x: np.power(x, 2.4), (1e-3, 1)),
    "sqrt": ("sqrt(v)", np.sqrt, (0, 100)),
    "atan2": ("atan2(v, 1.5f)", lambda x: np.arctan2(x, 1.5), (-10, 10)),
}


def ulp_error(got, want):
    want32 = np.abs(want).astype(np.float32)
    ulp = np.spacing(want32).astype(np.float64)
    ok = np.isfinite(want) & (ulp > 0)
    return float(np.max(np.abs(got[ok].astype(np.float64) - want[ok]) / ulp[ok])) if ok.any() else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--platform", default="Portable", help="a substring of the OpenCL platform's name")
    ap.add_argument("--widths", type=int, nargs="+", default=[1, 4, 8], choices=[1, 2, 4, 8, 16])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--out")
    args = ap.parse_args()

    platforms = [p for p in cl.get_platforms() if args.platform.lower() in p.name.lower()]
    if not platforms:
        raise SystemExit(f"builtin_cost: no OpenCL platform matches '{args.platform}' "
                         f"({', '.join(p.name for p in cl.get_platforms())})")
    device = platforms[0].get_devices()[0]
    ctx = cl.Context([device])
    queue = cl.CommandQueue(ctx)
    n = 1 << 21
    rng = np.random.default_rng(1)
    result = {"platform": platforms[0].name, "device": device.name, "driver": device.driver_version,
              "values": n, "repeats": args.repeats, "local_size": 64,
              "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), "functions": {}}
    for width in args.widths:
        t = "float" if width == 1 else f"float{width}"
        load = "x[i]" if width == 1 else f"vload{width}(i, x)"
        store = "x[i] = r;" if width == 1 else f"vstore{width}(r, i, x);"
        src = "".join(f"__kernel void k_{name}(__global float* x) {{ const size_t i = get_global_id(0); "
                      f"const {t} v = {load}; const {t} r = {expr}; {store} }}\n"
                      for name, (expr, _, _) in FUNCTIONS.items())
        program = cl.Program(ctx, src).build()
        for name, (_, reference, (lo, hi)) in FUNCTIONS.items():
            x0 = rng.uniform(lo, hi, n).astype(np.float32)
            buf = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, x0.nbytes)
            kernel = getattr(program, f"k_{name}")
            times = []
            for r in range(args.repeats + 1):  # the first run is the warm-up
                cl.enqueue_copy(queue, buf, x0)
                queue.finish()
                start = time.perf_counter()
                kernel(queue, (n // width,), (64,), buf)
                queue.finish()
                if r:
                    times.append(time.perf_counter() - start)
            got = np.empty_like(x0)
            cl.enqueue_copy(queue, got, buf)
            queue.finish()
            row = result["functions"].setdefault(name, {})
            row[t] = {"ns_per_value": statistics.median(times) * 1e9 / n,
                      "max_ulp": ulp_error(got, reference(x0.astype(np.float64)))}
    for name, row in result["functions"].items():
        scalar, widest = row.get("float"), row.get(f"float{max(args.widths)}") if max(args.widths) > 1 else None
        if scalar and widest:
            row["scalar_over_widest"] = scalar["ns_per_value"] / widest["ns_per_value"]
    text = json.dumps(result, indent=1)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()

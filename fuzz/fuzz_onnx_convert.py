#!/usr/bin/env python3
"""A mutation fuzzer for ngi's ONNX converter (ngi.onnx_import.import_onnx, what `python3 -m ngi.convert` runs).

libFuzzer cannot drive Python and Atheris is not packaged in Debian, so this is the same loop written for the
converter: take a seed model (fuzz/corpus/onnx_convert/, fuzz/make_onnx_seeds.py) or an earlier interesting input,
mutate it -- mostly structure-aware (op types, attributes set to extreme values, tensor shapes and types, rewired and
dropped nodes, graph inputs and opsets, all on the parsed protobuf), sometimes as bytes (flips, truncation, splices)
-- write it to a file and convert it in this process. The converter's contract (bindings/python/ngi/onnx_import.py):

  * bad input raises ngi.model_file.ConversionError, one line naming the file, and writes nothing (no output, no
    temporary file beside it); any other exception is a finding;
  * one input converts in under --timeout seconds and the process stays under --rss-limit-mb;
  * what it writes, the C++ loader accepts: with --load-check K (needs the native module ngi._ngi and an OpenCL
    device) up to K converted models of distinct configs are loaded with ngi.Model; a refusal is a finding.

An input is kept in the corpus folder when it reaches a (node op, outcome) pair not seen before (the outcome is
"converted" or the error message with its numbers and names stripped): a cheap stand-in for coverage. Findings are
written to --artifacts as onnx_convert-<kind>-<hash>.onnx with the traceback beside it; the run goes on (a finding
is counted once per distinct place). At the end it prints libFuzzer's stat:: lines, which tools/fuzz.sh reads, and
exits 1 if anything was found.

    PYTHONPATH=build/python /usr/bin/python3 fuzz/fuzz_onnx_convert.py -runs=1000000 build-fuzz/corpus/onnx_convert \\
        fuzz/corpus/onnx_convert --load-check 200
"""
import argparse
import copy
import hashlib
import os
import random
import re
import resource
import signal
import sys
import tempfile
import time
import traceback
import warnings

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

from ngi import onnx_import
from ngi.model_file import ConversionError, read_config

INT_EDGES = [0, 1, -1, 2, 3, 7, 64, 65, 4096, 65536, 65537, 2**31 - 1, -2**31, 2**40, 2**63 - 1]
FLOAT_EDGES = [0.0, -0.0, 1.0, -1.0, 0.2, 1e-45, 1.2e-38, 65504.0, 1e30, 3.4e38, float("nan"), float("inf"),
               -float("inf"), 88.0, 89.0, -1e30]
OPS = list(onnx_import.SUPPORTED_OPS) + ["Resize", "Pad", "Reshape", "Flatten", "Elu", "LpPool", "Unknown"]
ATTR_NAMES = ["group", "dilations", "strides", "pads", "kernel_shape", "output_padding", "auto_pad", "axis", "alpha",
              "epsilon", "transA", "transB", "value", "min", "max", "mode", "ratio", "to", "beta", "momentum", "axes",
              "keepdims", "ceil_mode", "storage_order"]


class Timeout(BaseException):  # not an Exception: the converter's broad handlers must not turn it into a refusal
    pass


def _alarm(_signum, _frame):
    raise Timeout()


# --------------------------------------------------------------------------
# Mutations
# --------------------------------------------------------------------------

def mutate_attribute(r, node):
    if node.attribute and r.random() < 0.8:
        a = r.choice(node.attribute)
        if a.type == onnx.AttributeProto.INT:
            a.i = r.choice(INT_EDGES) if r.random() < 0.7 else a.i + r.randint(-3, 3)
        elif a.type == onnx.AttributeProto.INTS:
            if a.ints and r.random() < 0.7:
                a.ints[r.randrange(len(a.ints))] = r.choice(INT_EDGES)
            elif r.random() < 0.5 and a.ints:
                del a.ints[r.randrange(len(a.ints))]
            else:
                a.ints.append(r.choice(INT_EDGES))
        elif a.type == onnx.AttributeProto.FLOAT:
            a.f = r.choice(FLOAT_EDGES)
        elif a.type == onnx.AttributeProto.STRING:
            a.s = r.choice([b"", b"SAME_UPPER", b"VALID", b"NOTSET", b"x" * 600, b"\xff\xfe"])
        elif a.type == onnx.AttributeProto.TENSOR:
            mutate_tensor(r, a.t)
        else:
            node.attribute.remove(a)
        return
    name = r.choice(ATTR_NAMES)
    kind = r.randrange(4)
    if kind == 0:
        node.attribute.append(helper.make_attribute(name, r.choice(INT_EDGES)))
    elif kind == 1:
        node.attribute.append(helper.make_attribute(name, [r.choice(INT_EDGES) for _ in range(r.randrange(5))] or [1]))
    elif kind == 2:
        node.attribute.append(helper.make_attribute(name, r.choice(FLOAT_EDGES)))
    else:
        node.attribute.append(helper.make_attribute(name, numpy_helper.from_array(
            np.full([r.randrange(1, 4)], r.choice(FLOAT_EDGES), np.float32))))


def mutate_tensor(r, t):
    k = r.randrange(7)
    if k == 0 and t.dims:  # a dimension to an edge value (the data no longer matches, or matches a stranger shape)
        t.dims[r.randrange(len(t.dims))] = r.choice([0, 1, 2, 3, -1, 65537, 2**31 - 1, 2**40])
    elif k == 1:  # rank change
        if t.dims and r.random() < 0.5:
            del t.dims[r.randrange(len(t.dims))]
        else:
            t.dims.append(r.choice([1, 2]))
    elif k == 2:
        t.data_type = r.choice([0, 1, 2, 6, 7, 9, 10, 11, 16, 99])
    elif k == 3 and t.raw_data:
        t.raw_data = t.raw_data[:r.randrange(len(t.raw_data) + 1)]
    elif k == 4 and t.data_type == TensorProto.FLOAT and t.raw_data:  # extreme values, the shape kept
        a = np.frombuffer(t.raw_data[:len(t.raw_data) // 4 * 4], np.float32).copy()
        if a.size:
            a[r.randrange(a.size)] = r.choice(FLOAT_EDGES)
            if r.random() < 0.3:
                a[:] = r.choice(FLOAT_EDGES)
            t.raw_data = a.tobytes()
    elif k == 5:
        t.data_location = r.choice([0, 1])
    else:  # the same values moved from raw_data to the typed field, or dropped
        if t.raw_data and t.data_type == TensorProto.FLOAT:
            vals = np.frombuffer(t.raw_data[:len(t.raw_data) // 4 * 4], np.float32)
            t.ClearField("raw_data")
            t.float_data.extend(vals.tolist()[:r.randrange(vals.size + 2)])
        else:
            t.ClearField("raw_data")


def mutate_value_info(r, vi):
    tt = vi.type.tensor_type
    k = r.randrange(4)
    if k == 0 and tt.shape.dim:
        d = tt.shape.dim[r.randrange(len(tt.shape.dim))]
        if r.random() < 0.2:
            d.dim_param = "N"
        else:
            d.dim_value = r.choice([0, 1, 2, 3, 5, 7, 8, 17, 64, 4096, 65536, 2**31 - 1, -1])
    elif k == 1:
        if tt.shape.dim and r.random() < 0.5:
            del tt.shape.dim[r.randrange(len(tt.shape.dim))]
        else:
            tt.shape.dim.add().dim_value = r.choice([1, 3, 8])
    elif k == 2:
        tt.elem_type = r.choice([0, 1, 10, 11, 7])
    else:
        vi.name = r.choice(["", "y", "x", "w1", vi.name + "_"])


def mutate_graph(r, m, seeds):
    g = m.graph
    names = [o for n in g.node for o in n.output] + [t.name for t in g.initializer] + [i.name for i in g.input]
    k = r.randrange(14)
    if k <= 2 and g.node:
        mutate_attribute(r, r.choice(g.node))
    elif k == 3 and g.node:
        r.choice(g.node).op_type = r.choice(OPS)
    elif k == 4 and g.node:  # rewire an input (a cycle, a missing tensor, a weight read as data)
        n = r.choice(g.node)
        if n.input:
            n.input[r.randrange(len(n.input))] = r.choice(names + ["", "missing"])
        else:
            n.input.append(r.choice(names))
    elif k == 5 and g.node:
        del g.node[r.randrange(len(g.node))]
    elif k == 6 and g.node:  # a duplicate node (two producers of one tensor) or one with an output renamed
        n = copy.deepcopy(r.choice(g.node))
        if r.random() < 0.5 and n.output:
            n.output[0] = n.output[0] + "_dup"
        g.node.insert(r.randrange(len(g.node) + 1), n)
    elif k == 7 and g.node:
        n = r.choice(g.node)
        if r.random() < 0.5 and len(n.input) > 0:
            del n.input[-1]
        else:
            n.input.append(r.choice(names))
    elif k == 8 and g.initializer:
        mutate_tensor(r, r.choice(g.initializer))
    elif k == 9:
        mutate_value_info(r, r.choice(list(g.input) + list(g.output)))
    elif k == 10:
        if r.random() < 0.5:
            m.opset_import[0].version = r.choice([1, 7, 8, 9, 10, 11, 12, 13, 16, 17, 18, 100])
        else:
            m.opset_import.add(domain=r.choice(["com.microsoft", "ai.onnx.ml", ""]), version=1)
    elif k == 11 and len(g.node) > 1:  # order: ONNX promises none, the converter sorts
        i, j = r.randrange(len(g.node)), r.randrange(len(g.node))
        a, b = copy.deepcopy(g.node[i]), copy.deepcopy(g.node[j])
        g.node[i].CopyFrom(b)
        g.node[j].CopyFrom(a)
    elif k == 12:  # a node of another seed grafted in, reading one of this graph's tensors
        other = onnx.load_model_from_string(r.choice(seeds))
        if other.graph.node:
            n = copy.deepcopy(r.choice(other.graph.node))
            if n.input:
                n.input[0] = r.choice(names)
            g.node.insert(r.randrange(len(g.node) + 1), n)
            for t in other.graph.initializer:
                if t.name in n.input and t.name not in {x.name for x in g.initializer}:
                    g.initializer.append(t)
    elif g.node:  # names: long, empty, repeated
        n = r.choice(g.node)
        n.name = r.choice(["", "a" * 600, g.node[0].name, "n\x00x", n.name + "'"])
    return m


def mutate_bytes(r, data, seeds):
    b = bytearray(data)
    for _ in range(r.randint(1, 4)):
        k = r.randrange(5)
        if k == 0 and b:
            i = r.randrange(len(b))
            b[i] ^= 1 << r.randrange(8)
        elif k == 1 and b:
            i = r.randrange(len(b))
            b[i] = r.choice([0, 1, 0x7f, 0x80, 0xff])
        elif k == 2:
            del b[r.randrange(len(b) + 1):]
        elif k == 3:
            i = r.randrange(len(b) + 1)
            b[i:i] = bytes(r.randrange(256) for _ in range(r.randint(1, 8)))
        else:
            o = r.choice(seeds)
            i, j = r.randrange(len(b) + 1), r.randrange(len(o) + 1)
            b = b[:i] + o[j:j + r.randint(1, 64)] + b[i:]
    return bytes(b)


def mutate(r, data, seeds):
    if r.random() < 0.2:
        return mutate_bytes(r, data, seeds)
    try:
        m = onnx.load_model_from_string(data)
    except Exception:  # noqa: BLE001 (a byte-mutated corpus entry: keep mutating its bytes)
        return mutate_bytes(r, data, seeds)
    try:
        for _ in range(r.choice([1, 1, 1, 2, 3])):
            mutate_graph(r, m, seeds)
        return m.SerializeToString()
    except Exception:  # noqa: BLE001 (protobuf refusing a mutation, e.g. a value out of a field's range)
        return mutate_bytes(r, data, seeds)


# --------------------------------------------------------------------------
# The loop
# --------------------------------------------------------------------------

_VARYING = re.compile(r"b?'[^']*'|b?\"[^\"]*\"|\[[^\]]*\]|\([^)]*\)|[-+]?\d[\w.+-]*")


def signature(data, outcome):
    """What makes an input interesting, a cheap stand-in for coverage: for a converted model its set of node ops,
    for a refusal the shape of its message (names, numbers and lists dropped: one entry per kind of refusal)."""
    if outcome != "converted":
        return "refused", _VARYING.sub("#", outcome.split(": ", 1)[-1])[:100]
    try:
        return "converted", tuple(sorted({n.op_type for n in onnx.load_model_from_string(data).graph.node}))
    except Exception:  # noqa: BLE001
        return "converted", ("<unparsed>",)


def find_place(tb):
    """The innermost frame of ngi's code (or the innermost at all) of a traceback: a finding's identity."""
    frames = traceback.extract_tb(tb)
    ours = [f for f in frames if "/ngi/" in f.filename] or frames
    f = ours[-1]
    return f"{os.path.basename(f.filename)}:{f.lineno}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], prefix_chars="-")
    p.add_argument("dirs", nargs="+", help="corpus folder (written), then seed folders (read)")
    p.add_argument("-runs", type=int, default=0, help="executions (0 = no limit)")
    p.add_argument("-max_total_time", type=int, default=0, help="seconds (0 = no limit)")
    p.add_argument("-seed", type=int, default=0, help="random seed (0 = from the clock)")
    p.add_argument("-artifact_prefix", default="onnx_convert-", help="where findings go (a path prefix)")
    p.add_argument("--timeout", type=float, default=10.0, help="seconds one input may take")
    p.add_argument("--rss-limit-mb", type=int, default=2048)
    p.add_argument("--load-check", type=int, default=0, metavar="K",
                   help="load up to K converted models of distinct configs with ngi.Model (native module + device)")
    p.add_argument("--device", default=os.environ.get("NGI_DEVICE", "cpu"))
    args = p.parse_args(argv)
    warnings.simplefilter("ignore")  # protobuf's parse warnings on byte-mutated inputs: the outcome says enough
    seed = args.seed or int(time.time() * 1000) % 2**31
    r = random.Random(seed)

    corpus_dir = args.dirs[0]
    os.makedirs(corpus_dir, exist_ok=True)
    def read_dir(d):
        found = []
        for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
            path = os.path.join(d, f)
            if os.path.isfile(path) and os.path.getsize(path) <= 1 << 20:
                with open(path, "rb") as fh:
                    found.append(fh.read())
        return found
    seeds = [c for d in args.dirs[1:] for c in read_dir(d) if c]
    corpus = read_dir(corpus_dir) + seeds
    seeds = seeds or [c for c in corpus if c] or [b""]
    print(f"INFO: seed {seed}, {len(corpus)} inputs from {', '.join(args.dirs)}", flush=True)

    model_cls = device = None
    if args.load_check:
        import ngi  # noqa: PLC0415 (the native part: only for the load check)
        device = ngi.Device(args.device)
        model_cls = ngi.Model
        print(f"INFO: load check on {device.name if hasattr(device, 'name') else args.device}", flush=True)

    work = tempfile.mkdtemp(prefix="ngi-fuzz-onnx-", dir="/dev/shm" if os.path.isdir("/dev/shm") else None)
    src, out = os.path.join(work, "in.onnx"), os.path.join(work, "out", "model.safetensors")
    os.makedirs(os.path.dirname(out))
    signal.signal(signal.SIGALRM, _alarm)
    seen, findings, loaded_configs = set(), {}, set()
    counts = {"converted": 0, "refused": 0, "loaded": 0}
    start = last = time.time()
    runs = 0

    def finding(kind, place, data, detail):
        key = (kind, place)
        if key in findings:
            findings[key] += 1
            return
        findings[key] = 1
        h = hashlib.sha1(data).hexdigest()[:12]
        path = f"{args.artifact_prefix}{kind}-{h}.onnx"
        with open(path, "wb") as fh:
            fh.write(data)
        with open(path + ".txt", "w") as fh:
            fh.write(detail)
        print(f"==FINDING== {kind} at {place}: {detail.strip().splitlines()[-1][:300]} (input {path})", flush=True)

    while True:
        if args.runs and runs >= args.runs:
            break
        if args.max_total_time and time.time() - start >= args.max_total_time:
            break
        # Half of the inputs grow from a seed: most mutants are refused, and refusals breed refusals.
        data = mutate(r, r.choice(corpus) if r.random() < 0.5 else r.choice(seeds), seeds)
        with open(src, "wb") as fh:
            fh.write(data)
        outcome = None
        signal.setitimer(signal.ITIMER_REAL, args.timeout)
        t0 = time.time()
        try:
            onnx_import.import_onnx(src, out)
            outcome = "converted"
        except ConversionError as e:
            outcome = str(e)
        except Timeout:
            finding("timeout", "import_onnx", data, f"one input ran past {args.timeout} s\n")
        except Exception as e:  # noqa: BLE001 (the finding itself: anything but ConversionError)
            finding("crash", f"{type(e).__name__}@{find_place(e.__traceback__)}", data,
                    "".join(traceback.format_exception(e)))
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        runs += 1
        left = os.listdir(os.path.dirname(out))
        if outcome is not None and outcome != "converted":
            counts["refused"] += 1
            if left:
                finding("partial", "refused-but-wrote", data, f"{outcome}\nleft behind: {left}\n")
            elif "\n" in outcome.strip() or src not in outcome:
                finding("unclear", "message", data, f"the error is not one line naming the file: {outcome!r}\n")
        elif outcome == "converted":
            counts["converted"] += 1
            if left != ["model.safetensors"]:
                finding("partial", "converted-left", data, f"the output folder holds {left}\n")
            if model_cls is not None and len(loaded_configs) < args.load_check and r.random() < 0.1:
                cfg = repr(read_config(out))
                if cfg not in loaded_configs:
                    loaded_configs.add(cfg)
                    try:
                        model_cls(device, out)
                        counts["loaded"] += 1
                    except Exception as e:  # noqa: BLE001 (the loader refusing what the converter wrote)
                        finding("loader-refused", f"{type(e).__name__}", data, f"{e}\n")
        for f in left:
            os.remove(os.path.join(os.path.dirname(out), f))
        if outcome is not None:
            sig = signature(data, outcome)
            if sig not in seen:
                seen.add(sig)
                corpus.append(data)
                with open(os.path.join(corpus_dir, hashlib.sha1(data).hexdigest()), "wb") as fh:
                    fh.write(data)
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024
        if rss > args.rss_limit_mb:
            finding("oom", "rss", data, f"peak RSS {rss} MB after this input (limit {args.rss_limit_mb} MB)\n")
            break
        if time.time() - t0 > args.timeout:  # a slow input that the alarm did not interrupt (inside C code)
            finding("timeout", "slow", data, f"one input took {time.time() - t0:.1f} s\n")
        now = time.time()
        if now - last >= 30:
            last = now
            rate = runs / (now - start)
            eta = f", ETA {(args.runs - runs) / rate / 60:.1f} min" if args.runs else ""
            print(f"#{runs}\tcorp: {len(corpus)} exec/s: {rate:.0f} rss: {rss}Mb converted: {counts['converted']} "
                  f"loaded: {counts['loaded']} findings: {len(findings)}{eta}", flush=True)

    for f in os.listdir(os.path.dirname(out)):
        os.remove(os.path.join(os.path.dirname(out), f))
    os.rmdir(os.path.dirname(out))
    for f in os.listdir(work):
        os.remove(os.path.join(work, f))
    os.rmdir(work)
    elapsed = max(time.time() - start, 1e-9)
    print(f"Done {runs} runs in {elapsed:.0f} second(s): converted {counts['converted']}, refused "
          f"{counts['refused']}, loaded {counts['loaded']} of them; {len(findings)} distinct findings")
    print(f"stat::number_of_executed_units: {runs}")
    print(f"stat::average_exec_per_sec:     {int(runs / elapsed)}")
    print(f"stat::new_units_added:          {len(seen)}")
    print(f"stat::peak_rss_mb:              {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024}")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())

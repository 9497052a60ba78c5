"""ONNX import: an ONNX file (e.g. from torch.onnx.export) -> an ngi model file of family "graph".

    /usr/bin/python3 -m ngi.convert model.onnx out.safetensors

Needs Debian's python3-onnx (the `onnx` package, 1.12 on Debian 12). The ONNX graph is checked, sorted
topologically and mapped node by node onto ngi's graph ops (docs/MODEL_FORMAT.md, family "graph"):

  Conv, ConvTranspose            -> conv2d, conv_transpose2d (2-D, symmetric padding; output_padding as a crop of a
                                    layer padded less); grouped / depthwise and
                                    dilated kernels expanded to the dense kernel they equal (zeros outside the groups
                                    and between the taps: exact, at group x the multiply-adds)
  Pad (zeros, H and W) read only by Conv -> the convolutions' padding
  Pad (reflect, edge, a constant, or zeros read by other nodes) -> pad2d
  Resize (linear = bilinear, by constant scales, or to a size: F.interpolate(size=...)) -> resize_bilinear
  DepthToSpace (DCR, CRD: PixelShuffle), Resize (nearest, one integer factor), AveragePool (square kernel; padding
                                    only with count_include_pad) -> conv2d / conv_transpose2d whose kernel copies or
                                    averages each channel (exact up to float summation order)
  Gemm, MatMul (weights constant) -> dense (a 1 x 1 convolution over the items)
  BatchNormalization (inference) -> affine (a per-channel scale and shift)
  Add, Sub, Mul, Div by a constant that varies along channels only (or not at all) -> affine
  Add, Mul of two computed tensors of one shape -> add, mul; of a tensor and a [1, C, 1, 1] one (a global pool's
                                    result and what 1 x 1 convolutions and activations make of it: squeeze-excitation)
                                    -> add, mul with broadcast
  Relu, LeakyRelu, Tanh, Sigmoid, Exp, Softplus, Erf (GELU's), Clip(min=0) -> activation
  MaxPool (ceil_mode 0, dilation 1, each pad below its kernel side) -> max_pool2d
  GlobalAveragePool, ReduceMean over H and W -> global_avg_pool; Flatten, Reshape, Unsqueeze, Squeeze of its result
                                    -> the same tensor, Gemm / MatMul on it -> a 1 x 1 conv2d
  InstanceNormalization          -> instance_norm
  Reshape [0, G, -1] + InstanceNormalization + Reshape(Shape(x)) (GroupNorm as PyTorch exports it) -> group_norm
  Clip with other bounds (ReLU6)  -> x - relu(x - hi) + relu(lo - x) as affine, activation and add nodes
  PRelu with one slope            -> activation leaky_relu; with a slope per channel -> relu(x) - a relu(-x)
  SpaceToDepth                    -> conv2d routing each block pixel to its channel (exact)
  Clip(max=88) then Exp          -> activation exp (ngi's exp is exp(min(x, 88)))
  Concat (channel axis)          -> concat
  Dropout (inference), Identity  -> nothing (the tensor itself)
  Mul by constants + Sin + Cos + Concat as ngi.reference_models.encode_frequencies builds it -> frequency_encode
  torch.nan_to_num's IsNaN/IsInf/Where pattern (default limits) -> nan_to_num

The file describes the network as the ONNX graph does: affine and activation nodes stay nodes. ngi's loader fuses
them into the convolution or dense layer before them (or a ReLU into the convolutions that read it) where that is
exact (host/src/models/graph_fuse.hpp): every reader of the file gets the network, not one backend's rewriting of it.

Anything else is refused with the node's name and op (every such node of a model in one error). So are files that do not parse (truncated, corrupt), graphs
with a cycle, opsets outside 9..17 or other domains, symbolic, zero or negative input dimensions, initializers whose
data does not match their shape, more than one input or output, attributes that are not finite numbers and weights
that are not finite as stored (as F16 with half=True), which the loader would refuse. Only a regular file of at
most 2 GiB is read (a FIFO or /dev/zero is refused before it is opened). Nothing is written unless the whole graph
maps; the file appears at its path only when complete (written beside it, then renamed).
"""

import heapq
import math
import os

import numpy as np

from . import _constants
from .model_file import FORMAT_VERSION, ConversionError, check_output_file, read_input_file, write_model

MIN_OPSET, MAX_OPSET = 9, 17
# The kernels the converter builds (grouped layers' dense kernels, dilated ones, channel-copying ones) may hold at most
# this many values in all, per model: 2^26 values are 256 MiB as the file's float32 (512 MiB while converted, in
# float64), far above what a model ngi runs needs (a depthwise 3 x 3 layer of 1,024 channels expands to 9.4 M).
MAX_BUILT_WEIGHTS = 1 << 26
EXP_CLAMP = _constants.ACT_EXP_MAX  # ngi's exp activation: exp(min(x, ACT_EXP_MAX)), host/src/ops/op_types.hpp
FLT_MAX = float(np.finfo(np.float32).max)
FLT_MIN = float(np.finfo(np.float32).tiny)  # the least normal float32
# An ONNX file is one protobuf message, which cannot exceed 2 GiB (larger models keep their weights in external
# data, which the importer refuses): the most _load reads.
ONNX_MAX_BYTES = (2 << 30) - 1
_ACTIVATIONS = {"Relu": "relu", "LeakyRelu": "leaky_relu", "Tanh": "tanh", "Sigmoid": "sigmoid", "Exp": "exp",
                "Softplus": "softplus", "Erf": "erf"}
SUPPORTED_OPS = ("Conv", "ConvTranspose", "BatchNormalization", "Relu", "LeakyRelu", "Tanh", "Sigmoid", "Exp",
                 "Softplus", "Erf", "Clip", "Concat", "Gemm", "MatMul", "Add", "Sub", "Mul", "Div", "Dropout",
                 "Identity", "Constant", "Pad", "DepthToSpace", "SpaceToDepth", "Resize", "AveragePool", "MaxPool",
                 "GlobalAveragePool", "ReduceMean", "InstanceNormalization", "PRelu", "ConstantOfShape", "Reshape",
                 "Flatten",
                 "Slice", "Transpose", "Unsqueeze", "Squeeze",
                 "Sin", "Cos", "IsNaN", "IsInf", "Where", "Cast", "And", "Greater", "Less")


def _onnx():
    try:
        import onnx  # noqa: PLC0415 (optional dependency: only the ONNX path needs it)
        import onnx.numpy_helper  # noqa: F401,PLC0415
    except ImportError as error:
        raise ConversionError("ONNX import needs the onnx Python package (Debian: apt-get install python3-onnx): "
                              f"{error}") from None
    return onnx


# --------------------------------------------------------------------------
# Reading and checking the file
# --------------------------------------------------------------------------

_DTYPES = {1: np.float32, 10: np.float16, 11: np.float64, 7: np.int64, 6: np.int32, 9: np.bool_}


# Shape arithmetic exporters write between constants (F.pad's pads at opset 13: ConstantOfShape, Concat, Reshape,
# Slice, Transpose, Cast): folded into the constant it makes when every input is a constant. Bounded: at most
# _FOLD_MAX_VALUES values a result and _FOLD_MAX_DEPTH producers deep, else the node stays unfolded (and is refused
# where it is read).
_FOLDABLE = ("ConstantOfShape", "Concat", "Reshape", "Slice", "Transpose", "Cast", "Unsqueeze", "Squeeze")
_FOLD_MAX_VALUES = 1 << 16
# ONNX ops that act pixel by pixel (a [1, C, 1, 1] input gives a [1, C, 1, 1] output).
_PIXELWISE = ("Relu", "LeakyRelu", "PRelu", "Tanh", "Sigmoid", "Exp", "Softplus", "Erf", "Clip", "Concat", "Add",
              "Sub", "Mul", "Div", "BatchNormalization")
_FOLD_MAX_DEPTH = 64
_CAST_TYPES = {1: np.float32, 6: np.int32, 7: np.int64, 9: np.bool_, 10: np.float16, 11: np.float64}


def _fold(node, attrs, inputs, opset):
    """The constant `node` makes from the constant `inputs` (np arrays, None for an absent optional input), or None
    when it is not a shape computation this folds."""
    op = node.op_type
    ints = lambda v: [int(i) for i in np.asarray(v).reshape(-1)]  # noqa: E731
    if op == "ConstantOfShape":
        shape = ints(inputs[0])
        if any(d < 0 for d in shape) or np.prod(shape, dtype=np.float64) > _FOLD_MAX_VALUES:
            return None
        fill = attrs.get("value")
        if fill is not None and np.asarray(fill).size != 1:
            return None
        return np.zeros(shape, np.float32) if fill is None else np.full(shape, np.asarray(fill).reshape(-1)[0])
    if op == "Concat":
        return np.concatenate([np.asarray(v) for v in inputs], axis=int(attrs.get("axis", 0)))
    if op == "Reshape":
        shape, data = ints(inputs[1]), np.asarray(inputs[0])
        if attrs.get("allowzero", 0) == 0:
            shape = [data.shape[k] if d == 0 and k < data.ndim else d for k, d in enumerate(shape)]
        return data.reshape(shape)
    if op == "Transpose":
        perm = attrs.get("perm")
        return np.transpose(np.asarray(inputs[0]), None if perm is None else [int(p) for p in perm])
    if op == "Cast":
        to = _CAST_TYPES.get(int(attrs.get("to", 0)))
        return None if to is None else np.asarray(inputs[0]).astype(to)
    if op == "Slice":
        data = np.asarray(inputs[0])
        if opset < 10:
            starts, ends, axes, steps = attrs.get("starts"), attrs.get("ends"), attrs.get("axes"), None
        else:
            starts, ends = inputs[1], inputs[2]
            axes = inputs[3] if len(inputs) > 3 else None
            steps = inputs[4] if len(inputs) > 4 else None
        starts, ends = ints(starts), ints(ends)
        axes = list(range(len(starts))) if axes is None else ints(axes)
        steps = [1] * len(starts) if steps is None else ints(steps)
        if not len(starts) == len(ends) == len(axes) == len(steps) or 0 in steps:
            return None
        index = [slice(None)] * data.ndim
        for s, e, a, st in zip(starts, ends, axes, steps):
            clip = lambda v: max(min(v, 2**62), -2**62)  # noqa: E731 (INT64_MAX / MIN as "to the end")
            index[a] = slice(clip(s), clip(e), st)
        return data[tuple(index)]
    if op in ("Unsqueeze", "Squeeze"):
        data = np.asarray(inputs[0])
        axes = attrs.get("axes") if opset < 13 else (inputs[1] if len(inputs) > 1 else None)
        if axes is None:
            return np.squeeze(data) if op == "Squeeze" else None
        axes = ints(axes)
        if op == "Squeeze":
            return np.squeeze(data, axis=tuple(axes))
        rank = data.ndim + len(axes)
        if any(not -rank <= a < rank for a in axes) or len({a % rank for a in axes}) != len(axes):
            return None  # out of range or repeated: an invalid model, left to its reader's refusal
        return np.expand_dims(data, tuple(a % rank for a in axes))
    return None


def _tensor_array(onnx, t, what, path):
    """A TensorProto as an np.ndarray, its data checked against its dims first."""
    what = f"{path}: {what}"
    if t.data_location == 1:  # EXTERNAL
        raise ConversionError(f"{what} '{t.name}' keeps its data in an external file; save the model with its "
                              "data inside (onnx.save_model(..., save_as_external_data=False))")
    dims = list(t.dims)
    if any(d < 0 for d in dims):
        raise ConversionError(f"{what} '{t.name}' has a negative dimension {dims}")
    if t.data_type not in _DTYPES:
        known = {v: k for k, v in onnx.TensorProto.DataType.items()}
        raise ConversionError(f"{what} '{t.name}' has data type {t.data_type} "
                              f"({known.get(t.data_type, 'not an ONNX data type')}); float, double, float16, int "
                              "and bool tensors are supported")
    count = int(np.prod(dims, dtype=np.int64))
    itemsize = np.dtype(_DTYPES[t.data_type]).itemsize
    if t.HasField("raw_data"):
        if len(t.raw_data) != count * itemsize:
            raise ConversionError(f"{what} '{t.name}' has {len(t.raw_data)} bytes of data, its shape {dims} of "
                                  f"{np.dtype(_DTYPES[t.data_type]).name} needs {count * itemsize}")
    else:
        field = {1: t.float_data, 10: t.int32_data, 11: t.double_data, 7: t.int64_data, 6: t.int32_data,
                 9: t.int32_data}[t.data_type]
        if len(field) != count:
            raise ConversionError(f"{what} '{t.name}' has {len(field)} values, its shape {dims} needs {count}")
    try:
        return onnx.numpy_helper.to_array(t)
    except Exception as error:  # noqa: BLE001 (whatever the helper raises is one more malformed tensor)
        raise ConversionError(f"{what} '{t.name}': unreadable data: {error}") from None


def _load(onnx, path):
    data = read_input_file(path, ONNX_MAX_BYTES)  # regular files only: a FIFO would block, /dev/zero never end
    if not data:
        raise ConversionError(f"{path} is empty")
    try:
        model = onnx.load_model_from_string(data)
    except Exception as error:  # noqa: BLE001 (protobuf's DecodeError and friends)
        raise ConversionError(f"{path} is not a readable ONNX model (truncated or corrupt?): {error}") from None
    if not model.HasField("graph") or not model.graph.node:
        raise ConversionError(f"{path}: the ONNX model has no graph nodes (truncated or not an ONNX model?)")
    _check_names(model.graph, path)
    return model


def _printable(name):
    """A name ngi can put in a one-line message and a JSON model file: valid UTF-8 without control characters."""
    if isinstance(name, bytes):  # protobuf hands over a string field that is not valid UTF-8 as bytes
        return False
    return all(c.isprintable() or c == " " for c in name)


def _check_names(graph, path):
    """Every name and op type in the graph printable, before any message quotes one (a name holding a newline or
    invalid UTF-8 would break the one-line error, and protobuf refuses to store the latter again)."""
    def check(name, where):
        if not _printable(name):
            raise ConversionError(f"{path}: {where} is not printable UTF-8 text: {name!r}")
    for i, node in enumerate(graph.node):
        check(node.op_type, f"the op type of node {i}")
        check(node.name, f"the name of node {i} ({node.op_type})")
        for k, name in enumerate(list(node.input) + list(node.output)):
            check(name, f"tensor name {k} of node {i} ({node.op_type})")
    for kind, items in (("initializer", graph.initializer), ("graph input", graph.input),
                        ("graph output", graph.output)):
        for i, item in enumerate(items):
            check(item.name, f"the name of {kind} {i}")


def _check_opsets(model, path):
    opsets = {(o.domain or "ai.onnx"): o.version for o in model.opset_import}
    for domain, version in opsets.items():
        if domain != "ai.onnx":
            raise ConversionError(f"{path}: opset domain '{domain}' is not supported (only the default ai.onnx "
                                  "domain)")
    version = opsets.get("ai.onnx")
    if version is None:
        raise ConversionError(f"{path}: the model imports no ai.onnx opset")
    if not MIN_OPSET <= version <= MAX_OPSET:
        raise ConversionError(f"{path}: opset {version} is not supported (ai.onnx opsets {MIN_OPSET}..{MAX_OPSET}; "
                              f"export with torch.onnx.export(..., opset_version=13))")
    return version


def _topological(nodes, available, path):
    """The nodes in an order where every input is made before it is read; refuses a cycle, naming its nodes."""
    producer = {}
    for i, node in enumerate(nodes):
        for out in node.output:
            if out:
                if out in producer or out in available:
                    other = "an initializer or the input" if out in available else f"node '{nodes[producer[out]].name}'"
                    raise ConversionError(f"{path}: tensor '{out}' is made twice (node '{node.name}' and {other})")
                producer[out] = i
    deps = {i: set() for i in range(len(nodes))}
    for i, node in enumerate(nodes):
        for name in node.input:
            if not name or name in available:
                continue
            if name not in producer:
                raise ConversionError(f"{path}: node '{node.name}' ({node.op_type}) reads '{name}', which no node, "
                                      "initializer or input makes")
            deps[i].add(producer[name])
    users = {i: [] for i in range(len(nodes))}
    for i, d in deps.items():
        for p in d:
            users[p].append(i)
    # Kahn's algorithm, keeping the file's order among ready nodes (a heap: n log n for any graph's shape).
    waiting = {i: len(d) for i, d in deps.items()}
    ready = [i for i, n in waiting.items() if n == 0]
    heapq.heapify(ready)
    order = []
    while ready:
        i = heapq.heappop(ready)
        order.append(i)
        for u in users[i]:
            waiting[u] -= 1
            if waiting[u] == 0:
                heapq.heappush(ready, u)
    if len(order) != len(nodes):
        # Walk back from a node that never became ready along dependencies that did not either: it closes a loop.
        stuck = {i for i in range(len(nodes)) if waiting[i] > 0}
        seen, walk = {}, []
        i = min(stuck)
        while i not in seen:
            seen[i] = len(walk)
            walk.append(i)
            i = min(d for d in deps[i] if d in stuck)
        cycle = walk[seen[i]:][::-1]
        names = " -> ".join(f"'{nodes[k].name}' ({nodes[k].op_type})" for k in cycle + cycle[:1])
        raise ConversionError(f"{path}: the graph has a cycle: {names}")
    return [nodes[i] for i in order]


def _text(value):
    """A string attribute as text (bytes from protobuf; undecodable bytes replaced, so a message can quote them)."""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _attrs(onnx, node):
    return {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}


def _integers(value):
    """The values of a constant read as sizes or indices, as Python ints; None when one is not a finite whole number
    (a float tensor there holds NaN or 2.5 as easily as 2: such a pattern does not match, and the reader refuses it)."""
    flat = np.asarray(value).reshape(-1)
    if flat.dtype.kind in "iub":
        return [int(v) for v in flat]
    if flat.dtype.kind != "f" or not np.all(np.isfinite(flat)) or np.any(flat != np.round(flat)):
        return None
    return [int(v) for v in flat]


# --------------------------------------------------------------------------
# Mapping
# --------------------------------------------------------------------------

class _Importer:
    def __init__(self, onnx, model, path):
        self.onnx = onnx
        self.path = path
        graph = model.graph
        self.opset = _check_opsets(model, path)
        self.consts = {}
        for t in graph.initializer:
            self.consts[t.name] = _tensor_array(onnx, t, "initializer", path)
        inputs = [i for i in graph.input if i.name not in self.consts]
        if len(inputs) != 1:
            raise ConversionError(f"{path}: the graph has {len(inputs)} inputs "
                                  f"({', '.join(i.name for i in inputs)}); ngi models take exactly one")
        if len(graph.output) != 1:
            raise ConversionError(f"{path}: the graph has {len(graph.output)} outputs; ngi models give exactly one")
        self.input = inputs[0]
        self.output_name = graph.output[0].name
        self.layout, self.input_nc, self.input_hw = self._input_shape(self.input)
        # Node names, unique and non-empty (ONNX allows neither to hold).
        names = set()
        for i, node in enumerate(graph.node):
            name = node.name or f"{node.op_type}_{i}"
            while name in names:
                name += "_"
            names.add(name)
            node.name = name
        self.nodes = _topological(list(graph.node), set(self.consts) | {self.input.name}, path)
        self.readers = {}
        for node in self.nodes:
            for name in node.input:
                if name:
                    self.readers.setdefault(name, []).append(node)
        self.producer = {out: node for node in self.nodes for out in node.output if out}
        self.alias = {}      # ONNX tensor -> the ngi tensor it is (Identity, Dropout)
        self.zero_pads = {}  # a zero Pad's output -> (its input, [top, left, bottom, right]): folded into convolutions
        self.built_values = 0  # values of the kernels built so far (MAX_BUILT_WEIGHTS)
        self.channels = {self.input.name: self.input_nc}
        self.unit = set()    # ngi tensors of one value a channel ([1, C, 1, 1]): a global pool's and what follows
        self.ir = []         # ngi nodes: dicts
        self.weights = {}    # tensor name -> float64 array
        self.done = set()    # ONNX node names consumed by a pattern
        self.fold_depth = 0  # producers being folded (const()), bounded by _FOLD_MAX_DEPTH
        self.not_const = set()  # tensors const() found not to be constants
        # Every tensor name of the file: the converter's own intermediate tensors (Clip, PRelu) avoid them.
        self.taken = {t.name for t in graph.initializer} | {self.input.name} | {
            n for node in graph.node for n in [*node.input, *node.output] if n}
        self.node_names = {node.name for node in graph.node}

    def fresh(self, base, taken):
        """`base`, or base with underscores appended, not in `taken` (the file's tensor or node names); reserved."""
        name = base
        while name in taken:
            name += "_"
        taken.add(name)
        return name

    def fail(self, node, message):
        return ConversionError(f"{self.path}: node '{node.name}' ({node.op_type}): {message}")

    def _input_shape(self, value_info):
        t = value_info.type.tensor_type
        if not value_info.type.HasField("tensor_type") or t.elem_type != 1:
            raise ConversionError(f"{self.path}: input '{value_info.name}' must be a float32 tensor")
        dims = []
        for k, d in enumerate(t.shape.dim):
            if d.HasField("dim_param") or not d.HasField("dim_value"):
                raise ConversionError(
                    f"{self.path}: input '{value_info.name}' dimension {k} is symbolic "
                    f"('{d.dim_param or '?'}'); export with a fixed example shape (no dynamic_axes): ngi still runs "
                    "the model at any size its layers allow")
            if d.dim_value <= 0:
                raise ConversionError(f"{self.path}: input '{value_info.name}' dimension {k} is {d.dim_value}; "
                                      "dimensions must be positive")
            dims.append(d.dim_value)
        if len(dims) in (2, 4) and dims[1] > _constants.GRAPH_MAX_CHANNELS:
            raise ConversionError(f"{self.path}: input '{value_info.name}' has {dims[1]} channels; ngi loads at most "
                                  f"{_constants.GRAPH_MAX_CHANNELS}")
        if len(dims) == 4 and dims[0] == 1:
            return "nchw", dims[1], (dims[2], dims[3])
        if len(dims) == 2:
            return "nc", dims[1], None
        raise ConversionError(f"{self.path}: input '{value_info.name}' has shape {dims}; ngi takes [1, C, H, W] "
                              "images or [N, C] item lists")

    # -- tensors --------------------------------------------------------------------------------------------------

    def const(self, name):
        """The constant value of tensor `name` (initializer, Constant node, Identity of either, shape arithmetic
        between constants), or None. A tensor found not constant is remembered (a chain of nodes each reading its
        predecessor twice was asked again and again: exponential time), and the producers followed are bounded
        (_FOLD_MAX_DEPTH: a chain of 5,000 Identity nodes overflowed Python's stack)."""
        if name in self.consts:
            return self.consts[name]
        if name in self.not_const:
            return None
        node = self.producer.get(name)
        if node is None:
            return None
        if node.op_type in ("Identity", *_FOLDABLE) and self.fold_depth >= _FOLD_MAX_DEPTH:
            return None  # not remembered: a shorter path may reach it
        value = self._const_of(name, node)
        if value is None and node.op_type in ("Identity", *_FOLDABLE):
            self.not_const.add(name)
        return value

    def _const_of(self, name, node):
        if node.op_type == "Constant":
            attrs = _attrs(self.onnx, node)
            if "value" not in attrs:
                raise self.fail(node, f"only the 'value' form is supported, got {sorted(attrs)}")
            self.consts[name] = _tensor_array(self.onnx, attrs["value"], "constant", self.path)
            self.done.add(node.name)
            return self.consts[name]
        if node.op_type == "Identity":
            self.fold_depth += 1
            try:
                value = self.const(node.input[0])
            finally:
                self.fold_depth -= 1
            if value is not None:
                self.consts[name] = value
                self.done.add(node.name)
            return value
        if node.op_type in _FOLDABLE and len(node.output) == 1:
            self.fold_depth += 1
            try:
                inputs = [self.const(i) if i else None for i in node.input]
                if any(i and v is None for i, v in zip(node.input, inputs)) \
                        or sum(np.asarray(v).size for v in inputs if v is not None) > _FOLD_MAX_VALUES:
                    return None
                attrs = _attrs(self.onnx, node)
                if node.op_type == "ConstantOfShape" and "value" in attrs:  # a TensorProto
                    attrs["value"] = _tensor_array(self.onnx, attrs["value"], "ConstantOfShape value", self.path)
                try:
                    value = _fold(node, attrs, inputs, self.opset)
                except (ValueError, IndexError, TypeError, OverflowError, np.AxisError):
                    value = None  # not a computation these shapes allow: left to the reader, which refuses it
            finally:
                self.fold_depth -= 1
            if value is None or np.asarray(value).size > _FOLD_MAX_VALUES:
                return None
            self.consts[name] = np.asarray(value)
            self.done.add(node.name)
            return self.consts[name]
        return None

    def tensor(self, node, name):
        """The ngi tensor of a computed ONNX tensor; refuses constants where a computed tensor is needed."""
        name = self.alias.get(name, name)
        if name not in self.channels:
            raise self.fail(node, f"input '{name}' is a constant or not computed by a supported node; ngi's graph "
                                  "ops take computed tensors there")
        return name

    def emit(self, onnx_node, op, inputs, output, **fields):
        fields = {k: v for k, v in fields.items() if v is not None}
        entry = {"name": onnx_node.name, "op": op, "inputs": list(inputs), "output": output, **fields}
        self.ir.append(entry)
        return entry

    def put_weight(self, key, array):
        self.weights[key] = np.asarray(array, dtype=np.float64)
        return key

    def per_channel(self, node, value, channels, what):
        """A constant that broadcasts along the channel axis only (or not at all) -> [channels] float64."""
        v = np.asarray(value, dtype=np.float64)
        rank = 4 if self.layout == "nchw" else 2
        if v.ndim > rank:
            raise self.fail(node, f"{what} has rank {v.ndim}, the tensor {rank}")
        shape = (1,) * (rank - v.ndim) + v.shape
        if any(s != 1 for i, s in enumerate(shape) if i != 1) or shape[1] not in (1, channels):
            raise self.fail(node, f"{what} of shape {list(v.shape)} does not broadcast per channel "
                                  f"({channels} channels); only constants that vary along the channel axis (or not "
                                  "at all) are supported")
        return np.broadcast_to(v.reshape(shape[1]), (channels,)).copy()

    # -- the nodes ------------------------------------------------------------------------------------------------

    def run(self):
        # Patterns that span nodes the walk below would meet one by one: the frequency encoding (its Mul, Sin and
        # Cos come before the Concat that gathers them).
        self.freq_runs = {}
        for node in self.nodes:
            if node.op_type == "Concat":
                runs, i, inputs = [], 0, list(node.input)
                while i < len(inputs):
                    run = self._frequency_run(node, inputs, i)
                    if run is None:
                        i += 1
                        continue
                    runs.append((i, run))
                    i = run[-1]
                self.freq_runs[node.name] = runs
        # GroupNorm as PyTorch exports it at opsets <= 17: Reshape(x, [0, G, -1]) -> InstanceNormalization (G
        # constants) -> Reshape(., Shape(x)), then the affine as Mul and Add by constants (mapped as usual).
        self.group_norms = {}
        for node in self.nodes:
            if node.op_type == "InstanceNormalization":
                found = self._group_norm_pattern(node)
                if found is not None:
                    self.group_norms[node.name] = found
                    self.done.update(n.name for n in found[1:4])
        # A bilinear resize to a fixed size (F.interpolate(size=...)): sizes = Concat(Slice(Shape(x), 0, 2), [h, w]).
        self.resize_sizes = {}
        for node in self.nodes:
            found = self._resize_sizes(node)
            if found is not None:
                self.resize_sizes[node.name] = found[0]
                self.done.update(n.name for n in found[1])
        # Every node that cannot be mapped is reported in one pass (issue 48): a failed node's outputs are marked, and
        # the nodes reading them are skipped (they fail only because of it).
        failures, failed = [], set()
        for node in self.nodes:
            if node.name in self.done:
                continue
            if any(name in failed for name in node.input):
                failed.update(o for o in node.output if o)
                continue
            try:
                self.map_node(node)
            except ConversionError as error:
                failures.append(str(error).removeprefix(f"{self.path}: "))
                failed.update(o for o in node.output if o)
        if len(failures) == 1:
            raise ConversionError(f"{self.path}: {failures[0]}")
        if failures:
            unsupported = any("is not supported; supported:" in f for f in failures)
            listed = "; ".join(f.split("; supported:")[0] for f in failures)
            raise ConversionError(f"{self.path}: {len(failures)} nodes cannot be converted: {listed}"
                                  + (f" (supported ops: {', '.join(SUPPORTED_OPS)})" if unsupported else ""))
        out = self.alias.get(self.output_name, self.output_name)
        if out not in self.channels or out == self.input.name:
            raise ConversionError(f"{self.path}: the graph output '{self.output_name}' is not computed by the mapped "
                                  "nodes (a constant, or the input itself)")
        return out

    def map_node(self, node):
        op = node.op_type
        attrs = _attrs(self.onnx, node)
        for name, value in attrs.items():
            # A NaN would reach the config as a NaN literal, which is not JSON: the loader refuses the file.
            values = value if isinstance(value, list) else [value]
            if any(isinstance(v, float) and not math.isfinite(v) for v in values):
                raise self.fail(node, f"attribute '{name}' is {value}: not a finite number")
        if op == "Constant":
            self.const(node.output[0])
            return
        if op in _FOLDABLE and self.const(node.output[0]) is not None:
            return  # shape arithmetic between constants: folded
        if op == "Identity" or op == "Dropout":
            if op == "Dropout":
                if len(node.output) > 1 and node.output[1] and self.readers.get(node.output[1]):
                    raise self.fail(node, "its mask output is used; only inference dropout (the identity) maps")
                if len(node.input) > 2 and node.input[2]:
                    training = self.const(node.input[2])
                    if training is None or bool(np.asarray(training).reshape(-1)[0]):
                        raise self.fail(node, "training_mode is on (or not constant); export the model in eval mode")
            if self.const(node.input[0]) is not None:
                if op == "Dropout":
                    self.consts[node.output[0]] = self.const(node.input[0])
                return
            self.alias[node.output[0]] = self.tensor(node, node.input[0])
            return
        handler = getattr(self, "op_" + op, None)
        if handler is None:
            if op in ("Sin", "Cos"):
                raise self.fail(node, "Sin and Cos are supported only as part of a frequency encoding "
                                      "(Concat of [x,] Sin(s x), Cos(s x), ... with s = 2^k or 2^k pi doubling)")
            if op in ("IsNaN", "IsInf", "Where", "Cast", "And", "Greater", "Less"):
                raise self.fail(node, "supported only as part of torch.nan_to_num(x) with its default limits"
                                + (" or between constants" if op == "Cast" else ""))
            if op in _FOLDABLE:
                raise self.fail(node, f"{op} is supported only as shape arithmetic between constants, folded into a "
                                      f"constant of at most {_FOLD_MAX_VALUES} values")
            if op == "Shape":
                raise self.fail(node, "supported only as part of GroupNorm's export (Reshape [0, G, -1], "
                                      "InstanceNormalization, Reshape to Shape(x))")
            raise self.fail(node, f"op {op} is not supported; supported: {', '.join(SUPPORTED_OPS)}")
        handler(node, attrs)
        # One value a channel stays one value a channel through what acts pixel by pixel (ReLU6's several nodes,
        # a per-channel PReLU, a concat of such tensors, ...), so a later multiply broadcasts it.
        if op in _PIXELWISE and node.output and node.output[0] in self.channels:
            computed = [self.alias.get(i, i) for i in node.input if self.alias.get(i, i) in self.channels]
            if computed and all(i in self.unit for i in computed):
                self.unit.add(node.output[0])

    def out(self, node, channels):
        # Refused at once, not at the end with the loader's other limits: a per-channel constant of that many
        # channels is built in float64 (2^31 channels took 16 GiB; the fuzzer found it).
        if channels > _constants.GRAPH_MAX_CHANNELS:
            raise self.fail(node, f"makes {channels} channels; ngi loads at most {_constants.GRAPH_MAX_CHANNELS}")
        self.channels[node.output[0]] = channels
        return node.output[0]

    def _conv(self, node, attrs, transpose):
        if len(node.output) != 1:
            raise self.fail(node, "one output expected")
        src, extra = node.input[0], [0, 0, 0, 0]
        if src in self.zero_pads and not transpose:  # a zero Pad before it: the convolution pads instead
            src, extra = self.zero_pads[src]
        x = self.tensor(node, src)
        w = self.const(node.input[1]) if len(node.input) > 1 else None
        if w is None:
            raise self.fail(node, "the weight must be a constant (an initializer)")
        if w.ndim != 4:
            raise self.fail(node, f"weight of rank {w.ndim}: only 2-D convolutions (4-D weights) are supported")
        b = self.const(node.input[2]) if len(node.input) > 2 and node.input[2] else None
        if len(node.input) > 2 and node.input[2] and b is None:
            raise self.fail(node, "the bias must be a constant")
        cin = self.channels[x]
        w = self._ungroup(node, w, int(attrs.get("group", 1)), cin, transpose)
        w = self._undilate(node, w, list(attrs.get("dilations", [1, 1])))
        auto_pad = _text(attrs.get("auto_pad", b"NOTSET"))
        if auto_pad not in ("NOTSET", "VALID"):
            raise self.fail(node, f"auto_pad {auto_pad}: give explicit pads")
        kh, kw = int(w.shape[2]), int(w.shape[3])
        dil = list(attrs.get("dilations", [1, 1]))
        declared = [(k - 1) * d + 1 for k, d in zip(attrs.get("kernel_shape", []), dil)]
        if "kernel_shape" in attrs and declared != [kh, kw]:
            raise self.fail(node, f"kernel_shape {attrs['kernel_shape']} disagrees with the weight {list(w.shape)}")
        strides = list(attrs.get("strides", [1, 1]))
        pads = list(attrs.get("pads", [0, 0, 0, 0])) if auto_pad == "NOTSET" else [0, 0, 0, 0]
        pads = [p + e for p, e in zip(pads, extra)]
        if len(strides) != 2 or strides[0] != strides[1]:
            raise self.fail(node, f"strides {strides}: only equal strides along H and W are supported")
        if len(pads) != 4 or len(set(pads)) != 1:
            raise self.fail(node, f"pads {pads}: only the same padding on every side is supported")
        crop = 0  # output_padding o: the layer with padding p - o, then its first o rows and columns cropped
        if transpose:
            out_pad = [int(v) for v in attrs.get("output_padding", [0, 0])]
            if any(out_pad):
                if len(out_pad) != 2 or out_pad[0] != out_pad[1] or not 0 < out_pad[0] < strides[0] \
                        or out_pad[0] > pads[0]:
                    raise self.fail(node, f"output_padding {out_pad} with stride {strides[0]}, pads {pads}: the same "
                                          "output_padding along H and W, below the stride and at most the padding, "
                                          "is supported")
                crop = out_pad[0]
            if "output_shape" in attrs:
                raise self.fail(node, "output_shape is not supported; give pads")
            if w.shape[0] != cin:
                raise self.fail(node, f"weight {list(w.shape)} takes {w.shape[0]} channels, the input has {cin}")
            cout = int(w.shape[1])
        else:
            if w.shape[1] != cin:
                raise self.fail(node, f"weight {list(w.shape)} takes {w.shape[1]} channels, the input has {cin}")
            cout = int(w.shape[0])
        if b is not None and b.shape != (cout,):
            raise self.fail(node, f"bias of shape {list(b.shape)}, expected [{cout}]")
        if self.layout == "nc":
            raise self.fail(node, "a convolution on an [N, C] item list")
        key = node.name
        # output_padding o (ONNX: o more rows and columns at the bottom and right, rows p .. of the full transposed
        # convolution): the layer padded p - o gives rows p - o .., o more at each end; cropping the first o of them
        # (a pad2d of -o at the top and left) leaves exactly ONNX's rows. Exact.
        out = self.fresh(f"{node.output[0]}/uncropped", self.taken) if crop else self.out(node, cout)
        if crop:
            self.channels[out] = cout
        self.emit(node, "conv_transpose2d" if transpose else "conv2d", [x], out, **{
            "in": cin, "out": cout, "kernel": [kh, kw], "stride": strides[0], "pad": pads[0] - crop,
            "weight": self.put_weight(key + ".weight", w),
            "bias": self.put_weight(key + ".bias", b) if b is not None else None})
        if crop:
            self.ir.append({"name": self.fresh(f"{node.name}/output_padding", self.node_names), "op": "pad2d",
                            "inputs": [out], "output": self.out(node, cout), "pads": [-crop, -crop, 0, 0],
                            "mode": "constant"})
        if x in self.unit and not transpose and kh == kw == 1 and strides[0] == 1 and pads[0] == 0:
            self.unit.add(node.output[0])  # a 1 x 1 layer keeps one value a channel

    def _ungroup(self, node, w, group, cin, transpose):
        """A grouped (or depthwise) convolution's weight as the dense one it equals: zero outside each group's
        block. Exact; it costs group x the multiply-adds of the grouped layer."""
        if group == 1:
            return w
        if group < 1 or cin % group:
            raise self.fail(node, f"group {group} does not divide the input's {cin} channels")
        if (w.shape[0] != cin) if transpose else (w.shape[1] * group != cin):
            raise self.fail(node, f"weight {list(w.shape)} with group {group} does not fit {cin} input channels")
        self._check_built(node, w.size * group, f"group {group}")
        if transpose:  # [cin, cout / group, kh, kw]
            per_out = w.shape[1]
            dense = np.zeros((cin, per_out * group) + w.shape[2:], np.float32)
            per_in = cin // group
            for g in range(group):
                dense[g * per_in:(g + 1) * per_in, g * per_out:(g + 1) * per_out] = w[g * per_in:(g + 1) * per_in]
            return dense
        cout, per_in = w.shape[0], w.shape[1]
        if cout % group:
            raise self.fail(node, f"weight {list(w.shape)} with group {group}: {cout} outputs do not split in groups")
        per_out = cout // group
        dense = np.zeros((cout, cin) + w.shape[2:], np.float32)
        for g in range(group):
            dense[g * per_out:(g + 1) * per_out, g * per_in:(g + 1) * per_in] = w[g * per_out:(g + 1) * per_out]
        return dense

    def _undilate(self, node, w, dilations):
        """A dilated kernel as the ordinary one it equals: zeros between the taps. Exact."""
        if len(dilations) != 2 or any(d < 1 for d in dilations):
            raise self.fail(node, f"dilations {dilations}: two positive integers expected")
        if dilations == [1, 1]:
            return w
        dh, dw = dilations
        kh, kw = w.shape[2], w.shape[3]
        if max((kh - 1) * dh + 1, (kw - 1) * dw + 1) > _constants.GRAPH_MAX_KERNEL:
            raise self.fail(node, f"dilations {dilations} make a {kh} x {kw} kernel {(kh - 1) * dh + 1} x "
                                  f"{(kw - 1) * dw + 1}, beyond ngi's {_constants.GRAPH_MAX_KERNEL}")
        self._check_built(node, w.shape[0] * w.shape[1] * ((kh - 1) * dh + 1) * ((kw - 1) * dw + 1), "dilation")
        out = np.zeros(w.shape[:2] + ((kh - 1) * dh + 1, (kw - 1) * dw + 1), np.float32)
        out[:, :, ::dh, ::dw] = w
        return out

    def _check_built(self, node, values, what):
        self.built_values += values
        if self.built_values > MAX_BUILT_WEIGHTS:
            raise self.fail(node, f"{what} would make a kernel of {values} values, taking the kernels the converter "
                                  f"builds for this model to {self.built_values}, beyond {MAX_BUILT_WEIGHTS}")

    def _channel_copy(self, node, x, channels, kernel, routes, op, stride, pad):
        """A convolution whose weight moves channels around without mixing values: routes = (input channel, output
        channel, kernel [kh, kw]) triples, every other pair zero. What nearest upsampling, depth-to-space and average
        pooling are, exactly."""
        if self.layout == "nc":
            raise self.fail(node, "a spatial op on an [N, C] item list (no H and W axes)")
        cin = self.channels[x]
        for what, v in (("kernel", kernel), ("stride", stride)):
            if not 1 <= v <= _constants.GRAPH_MAX_KERNEL:
                raise self.fail(node, f"{what} {v} is outside ngi's 1..{_constants.GRAPH_MAX_KERNEL}")
        self._check_built(node, cin * channels * kernel * kernel, "it")
        w = np.zeros((cin, channels, kernel, kernel) if op == "conv_transpose2d" else (channels, cin, kernel, kernel),
                     np.float32)
        for ci, co, k in routes:
            if op == "conv_transpose2d":
                w[ci, co] = k
            else:
                w[co, ci] = k
        self.emit(node, op, [x], self.out(node, channels), **{
            "in": cin, "out": channels, "kernel": [kernel, kernel], "stride": stride, "pad": pad,
            "weight": self.put_weight(node.name + ".copy", w)})

    def op_Pad(self, node, attrs):
        # Zero padding of H and W read only by convolutions (or counting average pools): folded into their padding
        # (exact). Any other padding of H and W -- reflect, edge, a constant, zeros read by anything else -- is a
        # pad2d node.
        x = self.tensor(node, node.input[0])
        mode = _text(attrs.get("mode", b"constant"))
        pads = attrs.get("pads")
        if pads is None and len(node.input) > 1 and node.input[1]:
            pads = self.const(node.input[1])
        value = self.const(node.input[2]) if len(node.input) > 2 and node.input[2] else attrs.get("value", 0.0)
        if mode not in ("constant", "reflect", "edge"):
            raise self.fail(node, f"mode {mode}: constant, reflect and edge are supported")
        if pads is None or value is None:
            raise self.fail(node, "pads and the constant value must be constants (pads an exporter computes with "
                                  "shape nodes, as nn.ZeroPad2d at opset 13 writes them, are not supported)")
        value = np.asarray(value, np.float64).reshape(-1)
        if value.size != 1 or not np.isfinite(value[0]) or abs(value[0]) > FLT_MAX:
            raise self.fail(node, f"constant value {list(value)}: one finite float32 number expected")
        value = float(np.float32(value[0]))
        pads = np.asarray(pads).reshape(-1)
        if pads.dtype.kind not in "iu":  # ONNX says int64; a float tensor (NaN, 1.5) is no padding
            raise self.fail(node, f"pads of type {pads.dtype}: integers expected")
        pads = [int(p) for p in pads]
        if len(pads) != 8 or any(pads[i] for i in (0, 1, 4, 5)) or min(pads) < -_constants.GRAPH_MAX_PAD:
            raise self.fail(node, f"pads {pads}: only padding (or cropping: negative) of H and W is supported")
        if not any(pads):  # what torch.onnx writes before an AvgPool2d without padding
            self.alias[node.output[0]] = x
            return
        sides = [pads[2], pads[3], pads[6], pads[7]]  # top, left, bottom, right
        readers = self.readers.get(node.output[0], [])
        if mode == "constant" and value == 0 and min(sides) >= 0 and readers and node.output[0] != self.output_name \
                and all(r.op_type in ("Conv", "AveragePool") for r in readers):
            self.zero_pads[node.output[0]] = (x, sides)
            return
        if self.layout == "nc":
            raise self.fail(node, "a spatial op on an [N, C] item list (no H and W axes)")
        if max(sides) > _constants.GRAPH_MAX_PAD:
            raise self.fail(node, f"pads {pads}: beyond ngi's {_constants.GRAPH_MAX_PAD}")
        self.emit(node, "pad2d", [x], self.out(node, self.channels[x]), pads=sides, mode=mode,
                  value=value if mode == "constant" else None)

    def op_DepthToSpace(self, node, attrs):
        # PixelShuffle: a stride-b transposed convolution whose b x b kernel routes each input channel to one output
        # pixel of its block (exact).
        x = self.tensor(node, node.input[0])
        b = int(attrs.get("blocksize", 0))
        mode = _text(attrs.get("mode", b"DCR"))
        cin = self.channels[x]
        if not 1 <= b <= _constants.GRAPH_MAX_KERNEL or cin % (b * b) or mode not in ("DCR", "CRD"):
            raise self.fail(node, f"blocksize {b}, mode {mode} on {cin} channels: a blocksize in "
                                  f"1..{_constants.GRAPH_MAX_KERNEL} dividing the channels as b^2, mode DCR or CRD")
        c = cin // (b * b)

        def routes():
            for ci in range(cin):
                i, j, co = ((ci // c) // b, (ci // c) % b, ci % c) if mode == "DCR" else \
                           ((ci % (b * b)) // b, ci % b, ci // (b * b))
                k = np.zeros((b, b))
                k[i, j] = 1.0
                yield ci, co, k
        self._channel_copy(node, x, c, b, routes(), "conv_transpose2d", b, 0)

    def op_SpaceToDepth(self, node, attrs):
        # PixelUnshuffle: a stride-b convolution whose b x b kernel picks one pixel of each block into a channel (ONNX
        # order: output channel (i b + j) C + c takes input channel c at block offset (i, j); exact).
        x = self.tensor(node, node.input[0])
        b = int(attrs.get("blocksize", 0))
        if not 1 <= b <= _constants.GRAPH_MAX_KERNEL:
            raise self.fail(node, f"blocksize {b}: 1..{_constants.GRAPH_MAX_KERNEL} expected")
        c = self.channels[x]

        def routes():
            for co in range(c * b * b):
                k = np.zeros((b, b))
                k[(co // c) // b, (co // c) % b] = 1.0
                yield co % c, co, k
        self._channel_copy(node, x, c * b * b, b, routes(), "conv2d", b, 0)

    def op_PRelu(self, node, attrs):
        # One slope for every channel (nn.PReLU() as exported): a leaky ReLU. A slope per channel
        # (nn.PReLU(num_parameters=C)): relu(x) - a relu(-x) as activation, affine and add nodes -- exactly x where
        # x > 0 (x + -0) and a x where x < 0 (one rounding, as a x itself).
        slope = self.const(node.input[1]) if len(node.input) > 1 else None
        if slope is None:
            raise self.fail(node, "the slope must be a constant")
        if np.unique(np.asarray(slope, np.float64)).size == 1:
            self._leaky_relu(node, float(np.float32(np.asarray(slope).reshape(-1)[0])))
            return
        x = self.tensor(node, node.input[0])
        c = self.channels[x]
        a = self.per_channel(node, slope, c, "the slope")
        names = {tag: self.fresh(f"{node.output[0]}/{tag}", self.taken)
                 for tag in ("positive", "negated", "negative_part", "scaled")}
        for tag, op, inputs, fields in (
                ("positive", "activation", [x], {"activation": "relu"}),
                ("negated", "affine", [x], {"scale": -np.ones(c)}),
                ("negative_part", "activation", [names["negated"]], {"activation": "relu"}),
                ("scaled", "affine", [names["negative_part"]], {"scale": -a})):
            entry = {"name": self.fresh(f"{node.name}/{tag}", self.node_names), "op": op, "inputs": inputs,
                     "output": names[tag]}
            for k, v in fields.items():
                entry[k] = self.put_weight(f"{node.name}/{tag}.{k}", v) if k == "scale" else v
            self.ir.append(entry)
            self.channels[names[tag]] = c
        self.emit(node, "add", [names["positive"], names["scaled"]], self.out(node, c))

    def op_Resize(self, node, attrs):
        # Nearest upsampling by an integer factor (what F.interpolate(scale_factor=s) exports): each pixel copied to an
        # s x s block, a stride-s transposed convolution with a one-hot channel kernel of ones (exact).
        x = self.tensor(node, node.input[0])
        mode, ctm, nearest = (_text(attrs.get(k, d)) for k, d in (
            ("mode", "nearest"), ("coordinate_transformation_mode", "half_pixel"),
            ("nearest_mode", "round_prefer_floor")))
        at = 1 if self.opset < 11 else 2  # Resize-10: (X, scales); 11+: (X, roi, scales, sizes)
        scales = self.const(node.input[at]) if len(node.input) > at and node.input[at] else None
        if (scales is None or np.asarray(scales).size == 0) and node.name in self.resize_sizes:
            if mode != "linear":
                raise self.fail(node, f"mode {mode} by sizes: only a bilinear resize takes an output size")
            self._resize_linear(node, attrs, x, ctm, None, self.resize_sizes[node.name])
            return
        if scales is None or np.asarray(scales).size == 0:
            raise self.fail(node, "only Resize by constant scales is supported (export with scale_factor, not size)")
        sc = np.asarray(scales, np.float64).reshape(-1)
        if mode == "linear":
            if self.opset < 11:  # Resize-10 has no coordinate modes: its linear resize is asymmetric
                ctm = "asymmetric"
            self._resize_linear(node, attrs, x, ctm, sc)
            return
        floor_map = (ctm == "asymmetric" and nearest == "floor") or \
                    (ctm in ("half_pixel", "pytorch_half_pixel") and nearest.startswith("round_prefer"))
        if mode != "nearest" or not floor_map:
            raise self.fail(node, f"mode {mode} ({ctm}, {nearest}): only nearest upsampling that copies each pixel to "
                                  "a block is supported (bilinear is not)")
        if sc.size != 4 or sc[0] != 1 or sc[1] != 1 or sc[2] != sc[3] or not 1 <= sc[2] <= _constants.GRAPH_MAX_KERNEL \
                or sc[2] != int(sc[2]):
            raise self.fail(node, f"scales {list(sc)}: only one integer factor along H and W is supported (at most "
                                  f"{_constants.GRAPH_MAX_KERNEL})")
        f = int(sc[2])
        ones = np.ones((f, f))
        self._channel_copy(node, x, self.channels[x], f, ((c, c, ones) for c in range(self.channels[x])),
                           "conv_transpose2d", f, 0)

    def _resize_sizes(self, node):
        """[h, w] when `node` (a Resize) takes its output size as F.interpolate(size=(h, w)) writes it at opsets
        11..17: sizes = Concat(Slice(Shape(x), 0, 2), [h, w]) with x the Resize's own input (N and C kept); the
        constant form [1, C, h, w] too. Else None."""
        if node.op_type != "Resize" or self.opset < 11 or len(node.input) < 4 or not node.input[3]:
            return None
        if len(node.input) > 2 and node.input[2] and self.const(node.input[2]) is not None \
                and np.asarray(self.const(node.input[2])).size:
            return None  # scales given
        sizes = self.const(node.input[3])
        if sizes is not None:
            s = _integers(sizes)
            return (s[2:], []) if s is not None and len(s) == 4 and s[0] == 1 else None
        cat = self.producer.get(node.input[3])
        if cat is None or cat.op_type != "Concat" or len(cat.input) != 2 or self._only_reader(cat.output[0]) is not node:
            return None
        hw = self.const(cat.input[1])
        sl = self.producer.get(cat.input[0])
        hw = None if hw is None else _integers(hw)
        if hw is None or len(hw) != 2 or sl is None or sl.op_type != "Slice" \
                or self._only_reader(sl.output[0]) is not cat:
            return None
        # starts, ends, axes, steps: [0], [2] and, when given, [0] and [1] (a bound given but not constant, or not
        # a whole number, reads as [] and fails the match)
        consts = [self.const(i) if i else None for i in sl.input[1:]]
        bounds = [None if not i else [] if v is None else (_integers(v) or []) for i, v in zip(sl.input[1:], consts)]
        wanted = ([0], [2], [0], [1])
        if len(bounds) < 2 or any(b is not None and b[:1] != w for b, w in zip(bounds, wanted)) \
                or bounds[0] is None or bounds[1] is None:
            return None
        shape = self.producer.get(sl.input[0])
        if shape is None or shape.op_type != "Shape" or shape.input[0] != node.input[0] \
                or self._only_reader(shape.output[0]) is not sl:
            return None
        return hw, [shape, sl, cat]

    def _resize_linear(self, node, attrs, x, ctm, sc, sizes=None):
        # Bilinear resize by constant scales (F.interpolate(mode="bilinear", scale_factor=s)): resize_bilinear, the
        # output floor(in * scale) a side as ONNX derives it; or to a fixed output size (size=(h, w)).
        if ctm not in ("half_pixel", "pytorch_half_pixel", "align_corners", "asymmetric"):
            raise self.fail(node, f"coordinate_transformation_mode {ctm}: half_pixel, pytorch_half_pixel, "
                                  "align_corners and asymmetric are supported")
        if attrs.get("exclude_outside", 0) or attrs.get("antialias", 0):
            raise self.fail(node, "exclude_outside and antialias are not supported")
        if self.layout == "nc":
            raise self.fail(node, "a spatial op on an [N, C] item list (no H and W axes)")
        if sizes is not None:
            if not all(1 <= s <= 65536 for s in sizes):
                raise self.fail(node, f"sizes {sizes}: output sizes in 1..65536 are supported")
            self.emit(node, "resize_bilinear", [x], self.out(node, self.channels[x]), sizes=list(sizes),
                      coordinate=ctm)
            return
        if sc.size != 4 or sc[0] != 1 or sc[1] != 1 or not all(1 / 64 <= s <= 64 for s in sc[2:]):
            raise self.fail(node, f"scales {list(sc)}: scales of H and W in [1/64, 64] (N and C 1) are supported")
        self.emit(node, "resize_bilinear", [x], self.out(node, self.channels[x]),
                  scales=[float(np.float32(sc[2])), float(np.float32(sc[3]))], coordinate=ctm)

    def op_AveragePool(self, node, attrs):
        # A convolution with 1 / (kh kw) on the diagonal channel pairs (exact up to float summation order); padding
        # only where the padded zeros count (count_include_pad, or no padding).
        x = node.input[0]
        if _text(attrs.get("auto_pad", b"NOTSET")) not in ("NOTSET", "VALID"):
            raise self.fail(node, f"auto_pad {_text(attrs['auto_pad'])}: give explicit pads")
        pads = list(attrs.get("pads", [0, 0, 0, 0]))
        # Padded zeros count in the average with count_include_pad, or when the pool has no padding of its own (then
        # the only padding is a Pad node's, whose zeros are values the pool averages).
        counted = bool(attrs.get("count_include_pad", 0)) or not any(pads)
        if x in self.zero_pads:
            if not counted:
                raise self.fail(node, "a Pad before a pooling that pads without count_include_pad: the two paddings "
                                      "average differently")
            x, extra = self.zero_pads[x]
            pads = [p + e for p, e in zip(pads, extra)]
        x = self.tensor(node, x)
        k = list(attrs.get("kernel_shape", []))
        strides = list(attrs.get("strides", [1, 1]))
        if len(k) != 2 or k[0] != k[1] or len(set(strides)) != 1 or len(set(pads)) != 1 or attrs.get("ceil_mode", 0):
            raise self.fail(node, f"kernel {k}, strides {strides}, pads {pads}: square kernels, equal strides and "
                                  "padding, ceil_mode 0 are supported")
        if pads[0] and not counted:
            raise self.fail(node, "padding without count_include_pad divides by a varying count: not supported")
        if not 1 <= k[0] <= _constants.GRAPH_MAX_KERNEL or not 0 <= pads[0] <= _constants.GRAPH_MAX_PAD:
            raise self.fail(node, f"kernel {k}, pads {pads}: beyond ngi's limits ({_constants.GRAPH_MAX_KERNEL}, "
                                  f"{_constants.GRAPH_MAX_PAD})")
        avg = np.full((k[0], k[0]), 1.0 / (k[0] * k[0]))
        self._channel_copy(node, x, self.channels[x], k[0], ((c, c, avg) for c in range(self.channels[x])), "conv2d",
                           strides[0], pads[0])

    def op_Conv(self, node, attrs):
        self._conv(node, attrs, False)

    def op_ConvTranspose(self, node, attrs):
        self._conv(node, attrs, True)

    def _dense(self, node, x, weight, bias):
        """weight [out, in] float64, bias [out] or None."""
        cin = self.channels[x]
        if self.layout != "nc" and x in self.unit:
            # A fully connected layer on one value a channel (squeeze-excitation written with Linear layers, after a
            # Flatten or a mean over H and W): a 1 x 1 convolution of the C x 1 x 1 tensor.
            if weight.shape[1] != cin:
                raise self.fail(node, f"the weight takes {weight.shape[1]} inputs, the input has {cin} channels")
            cout = int(weight.shape[0])
            out = self.out(node, cout)
            self.emit(node, "conv2d", [x], out, **{
                "in": cin, "out": cout, "kernel": [1, 1], "stride": 1, "pad": 0,
                "weight": self.put_weight(node.name + ".weight", weight.reshape(cout, cin, 1, 1)),
                "bias": self.put_weight(node.name + ".bias", bias) if bias is not None else None})
            self.unit.add(out)
            return
        if self.layout != "nc":
            raise self.fail(node, "a matrix product on an image: ngi maps Gemm/MatMul on [N, C] item lists only "
                                  "(use a 1 x 1 Conv for a per-pixel layer)")
        if weight.shape[1] != cin:
            raise self.fail(node, f"the weight takes {weight.shape[1]} inputs, the input has {cin} channels")
        cout = int(weight.shape[0])
        self.emit(node, "dense", [x], self.out(node, cout), **{
            "in": cin, "out": cout, "weight": self.put_weight(node.name + ".weight", weight),
            "bias": self.put_weight(node.name + ".bias", bias) if bias is not None else None})

    def op_Gemm(self, node, attrs):
        x = self.tensor(node, node.input[0])
        b = self.const(node.input[1])
        if b is None or b.ndim != 2:
            raise self.fail(node, "B must be a constant matrix (the weights)")
        if attrs.get("transA", 0):
            raise self.fail(node, "transA = 1 is not supported (the items are the rows)")
        bm = np.asarray(b, np.float64)
        bm = bm.T if attrs.get("transB", 0) else bm           # [in, out]
        weight = attrs.get("alpha", 1.0) * bm.T                # [out, in]
        bias = None
        if len(node.input) > 2 and node.input[2]:
            c = self.const(node.input[2])
            if c is None:
                raise self.fail(node, "C must be a constant (the bias)")
            c = np.asarray(c, np.float64)
            if c.ndim > 2 or (c.ndim == 2 and c.shape[0] != 1) or c.size not in (1, weight.shape[0]):
                raise self.fail(node, f"C of shape {list(c.shape)} is not a bias row of {weight.shape[0]}")
            bias = attrs.get("beta", 1.0) * np.broadcast_to(c.reshape(-1), (weight.shape[0],))
        self._dense(node, x, weight, bias)

    def op_MatMul(self, node, attrs):
        x = self.tensor(node, node.input[0])
        b = self.const(node.input[1])
        if b is None or b.ndim != 2:
            raise self.fail(node, "the second operand must be a constant matrix (the weights)")
        self._dense(node, x, np.asarray(b, np.float64).T, None)

    def op_BatchNormalization(self, node, attrs):
        if attrs.get("training_mode", 0):
            raise self.fail(node, "training_mode = 1; export the model in eval mode")
        if any(o and self.readers.get(o) for o in node.output[1:]):
            raise self.fail(node, "its running-statistics outputs are used (training mode)")
        x = self.tensor(node, node.input[0])
        params = [self.const(n) for n in node.input[1:5]]
        if len(params) != 4 or any(p is None for p in params):
            raise self.fail(node, "scale, bias, mean and variance must be constants")
        c = self.channels[x]
        gamma, beta, mean, var = (np.asarray(p, np.float64).reshape(-1) for p in params)
        for name, p in zip(("scale", "bias", "mean", "var"), (gamma, beta, mean, var)):
            if p.shape != (c,):
                raise self.fail(node, f"{name} has {p.size} values, the input {c} channels")
        eps = float(attrs.get("epsilon", 1e-5))
        if np.any(var + eps <= 0):
            raise self.fail(node, "variance + epsilon is not positive")
        scale = gamma / np.sqrt(var + eps)
        self._affine(node, x, scale, beta - mean * scale)

    def _affine(self, node, x, scale, shift):
        key = node.name
        self.emit(node, "affine", [x], self.out(node, self.channels[x]),
                  scale=self.put_weight(key + ".scale", scale) if scale is not None else None,
                  shift=self.put_weight(key + ".shift", shift) if shift is not None else None)
        if x in self.unit:
            self.unit.add(node.output[0])

    def _binary(self, node, kind):
        a, b = node.input[0], node.input[1]
        ca, cb = self.const(a), self.const(b)
        if ca is None and cb is None:
            if kind not in ("Add", "Mul"):
                raise self.fail(node, f"{kind} of two computed tensors is not supported (only by a constant)")
            x, y = self.tensor(node, a), self.tensor(node, b)
            if self.channels[x] != self.channels[y]:
                raise self.fail(node, f"combines {self.channels[x]} and {self.channels[y]} channels (no "
                                      "broadcasting between computed tensors)")
            if x in self.unit and y not in self.unit:
                x, y = y, x  # add and mul commute: the [1, C, 1, 1] operand second
            broadcast = y in self.unit and x not in self.unit
            out = self.out(node, self.channels[x])
            self.emit(node, kind.lower(), [x, y], out, broadcast=True if broadcast else None)
            if x in self.unit and y in self.unit:
                self.unit.add(out)
            return
        if ca is not None and cb is not None:
            raise self.fail(node, "both operands are constants (constant folding was off at export?)")
        swapped = ca is not None
        x = self.tensor(node, b if swapped else a)
        c = self.per_channel(node, cb if not swapped else ca, self.channels[x], "the constant")
        if kind == "Add":
            self._affine(node, x, None, c)
        elif kind == "Mul":
            self._affine(node, x, c, None)
        elif kind == "Sub":
            self._affine(node, x, -np.ones_like(c) if swapped else None, c if swapped else -c)
        else:  # Div
            if swapped:
                raise self.fail(node, "a constant divided by a computed tensor is not supported")
            if np.any(c == 0):
                raise self.fail(node, "division by a constant that holds 0")
            self._affine(node, x, 1.0 / c, None)

    def op_Add(self, node, attrs):
        self._binary(node, "Add")

    def op_Sub(self, node, attrs):
        self._binary(node, "Sub")

    def op_Mul(self, node, attrs):
        self._binary(node, "Mul")

    def op_Div(self, node, attrs):
        self._binary(node, "Div")

    def _activation(self, node, kind, slope=None):
        x = self.tensor(node, node.input[0])
        self.emit(node, "activation", [x], self.out(node, self.channels[x]), activation=kind, slope=slope)
        if x in self.unit:
            self.unit.add(node.output[0])

    def op_Relu(self, node, attrs):
        self._activation(node, "relu")

    def op_LeakyRelu(self, node, attrs):
        self._leaky_relu(node, float(np.float32(attrs.get("alpha", 0.01))))

    def _leaky_relu(self, node, alpha):
        # The loader's rule for a slope (host/src/models/graph_config.cpp): in [-1, 1], and 0 or a normal float32.
        if not (abs(alpha) <= 1.0 and (alpha == 0.0 or abs(alpha) >= FLT_MIN)):
            raise self.fail(node, f"alpha {alpha!r}: ngi's leaky_relu slope must lie in [-1, 1] and be 0 or at "
                                  "least 1.2e-38 in magnitude")
        self._activation(node, "leaky_relu", alpha)

    def op_Tanh(self, node, attrs):
        self._activation(node, "tanh")

    def op_Sigmoid(self, node, attrs):
        self._activation(node, "sigmoid")

    def op_Softplus(self, node, attrs):
        # ngi's softplus is max(x, 0) + log1p(exp(-|x|)): log(1 + e^x) without overflow.
        self._activation(node, "softplus")

    def op_Erf(self, node, attrs):
        # GELU as PyTorch exports it (x / sqrt(2) -> Erf -> + 1 -> * x -> * 0.5) maps node by node.
        self._activation(node, "erf")

    def _spatial(self, node):
        """The computed image input of a spatial op (refused on an [N, C] item list)."""
        if self.layout == "nc":
            raise self.fail(node, "a spatial op on an [N, C] item list (no H and W axes)")
        return self.tensor(node, node.input[0])

    def op_MaxPool(self, node, attrs):
        if len(node.output) > 1 and node.output[1] and self.readers.get(node.output[1]):
            raise self.fail(node, "its indices output is used; only the pooled values map")
        x = self._spatial(node)
        k = [int(v) for v in attrs.get("kernel_shape", [])]
        strides = [int(v) for v in attrs.get("strides", [1, 1])]
        auto_pad = _text(attrs.get("auto_pad", b"NOTSET"))
        if auto_pad not in ("NOTSET", "VALID"):
            raise self.fail(node, f"auto_pad {auto_pad}: give explicit pads")
        pads = [int(v) for v in attrs.get("pads", [0, 0, 0, 0])] if auto_pad == "NOTSET" else [0, 0, 0, 0]
        if len(k) != 2 or len(strides) != 2 or len(pads) != 4:
            raise self.fail(node, f"kernel {k}, strides {strides}, pads {pads}: only 2-D pooling is supported")
        if attrs.get("ceil_mode", 0) or any(int(d) != 1 for d in attrs.get("dilations", [1, 1])) \
                or attrs.get("storage_order", 0):
            raise self.fail(node, "ceil_mode 0, dilations 1 and storage_order 0 are supported")
        if not all(1 <= v <= _constants.GRAPH_MAX_KERNEL for v in k) \
                or not all(1 <= v <= _constants.GRAPH_MAX_STRIDE for v in strides) \
                or not all(0 <= v <= _constants.GRAPH_MAX_PAD for v in pads):
            raise self.fail(node, f"kernel {k}, strides {strides}, pads {pads}: beyond ngi's limits "
                                  f"({_constants.GRAPH_MAX_KERNEL}, {_constants.GRAPH_MAX_STRIDE}, "
                                  f"{_constants.GRAPH_MAX_PAD})")
        if any(p >= k[s % 2] for s, p in enumerate(pads)):
            raise self.fail(node, f"pads {pads} with kernel {k}: each pad must be below its kernel side (a window of "
                                  "padding alone has no value)")
        self.emit(node, "max_pool2d", [x], self.out(node, self.channels[x]), kernel=k, stride=strides, pads=pads)

    def _global_mean(self, node):
        x = self._spatial(node)
        out = self.out(node, self.channels[x])
        self.emit(node, "global_avg_pool", [x], out)
        self.unit.add(out)

    def op_GlobalAveragePool(self, node, attrs):
        self._global_mean(node)

    def op_ReduceMean(self, node, attrs):
        # The mean over H and W with the axes kept (x.mean((2, 3), keepdim=True)): a global average pool.
        if len(node.input) > 1 and node.input[1]:
            raise self.fail(node, "axes as an input (opset 18) are not supported")
        given = [int(a) for a in attrs.get("axes", [])]
        axes = sorted(a % 4 for a in given if -4 <= a < 4)
        # keepdims 0 ([1, C], x.mean((2, 3))): the same C x 1 x 1 tensor, which Flatten, Reshape and Unsqueeze keep
        # and Gemm reads as a 1 x 1 convolution.
        if self.layout == "nc" or len(given) != 2 or axes != [2, 3]:
            raise self.fail(node, f"axes {list(attrs.get('axes', []))}, keepdims {attrs.get('keepdims', 1)}: only the "
                                  "mean over H and W of an image with the axes kept maps (a global average pool)")
        self._global_mean(node)

    def _only_reader(self, tensor):
        readers = self.readers.get(tensor, [])
        return readers[0] if len(readers) == 1 and tensor != self.output_name else None

    def _group_norm_pattern(self, inorm):
        """(source tensor, the first Reshape, the Shape node, the second Reshape, groups) when `inorm` is the middle of
        PyTorch's GroupNorm export; else None (then it maps, or is refused, as an InstanceNormalization)."""
        first = self.producer.get(inorm.input[0])
        if first is None or first.op_type != "Reshape" or self._only_reader(first.output[0]) is not inorm:
            return None
        shape = self.const(first.input[1]) if len(first.input) > 1 else None
        if shape is None:
            return None
        shape = _integers(shape)
        if shape is None or len(shape) != 3 or shape[0] not in (0, 1) or shape[1] < 1 or shape[2] != -1:
            return None
        second = self._only_reader(inorm.output[0])
        if second is None or second.op_type != "Reshape" or len(second.input) < 2:
            return None
        size = self.producer.get(second.input[1])
        if size is None or size.op_type != "Shape" or size.input[0] != first.input[0] \
                or self._only_reader(size.output[0]) is not second:
            return None
        return first.input[0], first, size, second, shape[1]

    def _group_norm(self, node, attrs, found):
        src, _, _, second, groups = found
        if self.layout == "nc":
            raise self.fail(node, "a group normalization of an [N, C] item list (no H and W axes)")
        x = self.tensor(node, src)
        c = self.channels[x]
        if c % groups:
            raise self.fail(node, f"{groups} groups do not divide {c} channels")
        params = [self.const(n) if n else None for n in node.input[1:3]]
        if len(params) != 2 or any(p is None for p in params):
            raise self.fail(node, "scale and bias must be constants")
        scale, bias = (np.asarray(p, np.float64).reshape(-1) for p in params)
        if scale.shape != (groups,) or bias.shape != (groups,):
            raise self.fail(node, f"scale and bias have {scale.size} and {bias.size} values for {groups} groups")
        eps = self._epsilon(node, attrs)
        self.channels[second.output[0]] = c
        self.emit(node, "group_norm", [x], second.output[0], groups=groups, eps=eps,
                  scale=self.put_weight(node.name + ".scale", scale), shift=self.put_weight(node.name + ".shift", bias),
                  source=f"{node.name} (GroupNorm: Reshape, InstanceNormalization, Shape, Reshape)")

    def _epsilon(self, node, attrs):
        eps = float(attrs.get("epsilon", 1e-5))
        if not (0 < eps <= 1.0) or np.float32(eps) == 0 or not np.isfinite(np.float32(eps)):
            raise self.fail(node, f"epsilon {eps}: ngi's normalization takes a positive float32 epsilon up to 1")
        return float(np.float32(eps))

    def _unit_view(self, node, what):
        """Flatten, Reshape, Unsqueeze, Squeeze of a tensor of one value a channel: the same tensor (C x 1 x 1)."""
        x = self.tensor(node, node.input[0])
        if x not in self.unit:
            raise self.fail(node, f"{what} of a computed tensor is supported only on one value a channel (a global "
                                  "pool's result, squeeze-excitation); ngi's tensors are C x H x W")
        if what == "Reshape":
            shape = self.const(node.input[1]) if len(node.input) > 1 else None
            dims = None if shape is None else [int(d) for d in np.asarray(shape).reshape(-1)]
            c = self.channels[x]
            if dims is None or not 2 <= len(dims) <= 4 or dims[0] not in (0, 1, -1) or dims[1] not in (0, c, -1) \
                    or any(d != 1 for d in dims[2:]) or dims.count(-1) > 1:
                raise self.fail(node, f"shape {dims}: a reshape of a [1, {c}, 1, 1] tensor to [1, {c}] or "
                                      f"[1, {c}, 1, 1] is supported")
        self.alias[node.output[0]] = x

    def op_Flatten(self, node, attrs):
        if int(attrs.get("axis", 1)) != 1:
            raise self.fail(node, f"axis {attrs.get('axis')}: a Flatten from axis 1 is supported")
        self._unit_view(node, "Flatten")

    def op_Reshape(self, node, attrs):
        self._unit_view(node, "Reshape")

    def op_Unsqueeze(self, node, attrs):
        self._unit_view(node, "Unsqueeze")

    def op_Squeeze(self, node, attrs):
        self._unit_view(node, "Squeeze")

    def op_InstanceNormalization(self, node, attrs):
        if node.name in self.group_norms:
            self._group_norm(node, attrs, self.group_norms[node.name])
            return
        x = self._spatial(node)
        c = self.channels[x]
        params = [self.const(n) if n else None for n in node.input[1:3]]
        if len(params) != 2 or any(p is None for p in params):
            raise self.fail(node, "scale and bias must be constants")
        scale, bias = (np.asarray(p, np.float64).reshape(-1) for p in params)
        if scale.shape != (c,) or bias.shape != (c,):
            raise self.fail(node, f"scale and bias have {scale.size} and {bias.size} values, the input {c} channels")
        eps = self._epsilon(node, attrs)
        self.emit(node, "instance_norm", [x], self.out(node, c), eps=eps,
                  scale=self.put_weight(node.name + ".scale", scale), shift=self.put_weight(node.name + ".shift", bias))

    def op_Exp(self, node, attrs):
        # ngi's exp is exp(min(x, 88)); a bare Exp differs only where x > 88 (float32 exp >= 1.6e38 there, inf
        # beyond 88.72). Clip(max=88) + Exp (ngi.neural_gi's decoding) maps exactly: see op_Clip.
        self._activation(node, "exp")

    def _clip_limits(self, node, attrs):
        if self.opset < 11:
            return attrs.get("min"), attrs.get("max")
        limits = []
        for k in (1, 2):
            if len(node.input) > k and node.input[k]:
                v = self.const(node.input[k])
                if v is None or np.asarray(v).size != 1:
                    raise self.fail(node, "min and max must be scalar constants")
                limits.append(float(np.asarray(v).reshape(-1)[0]))
            else:
                limits.append(None)
        return limits

    def op_Clip(self, node, attrs):
        lo, hi = self._clip_limits(node, attrs)
        readers = self.readers.get(node.output[0], [])
        if lo is None and hi == EXP_CLAMP and len(readers) == 1 and readers[0].op_type == "Exp" \
                and node.output[0] != self.output_name:
            x = self.tensor(node, node.input[0])
            exp = readers[0]
            self.done.add(exp.name)
            self.emit(exp, "activation", [x], self.out(exp, self.channels[x]), activation="exp",
                      source=f"{node.name} (Clip max 88) + {exp.name} (Exp)")
            if x in self.unit:
                self.unit.add(exp.output[0])
            return
        if lo == 0.0 and hi is None:
            self._activation(node, "relu")
            return
        for v in (lo, hi):
            if v is not None and not (math.isfinite(v) and abs(v) <= FLT_MAX):
                raise self.fail(node, f"Clip(min={lo}, max={hi}): limits must be finite float32 numbers")
        if lo is not None and hi is not None and not lo <= hi:
            raise self.fail(node, f"Clip(min={lo}, max={hi}): min above max")
        if lo is None and hi is None:  # a clip of nothing: the tensor itself
            self.alias[node.output[0]] = self.tensor(node, node.input[0])
            return
        # Any other bounds (ReLU6 = Clip(0, 6)) as ReLUs of shifted copies added to x:
        #   clip(x, lo, hi) = x - relu(x - hi) + relu(lo - x): exactly x inside [lo, hi] (both ReLUs are 0), the bound
        #   within an ulp of x outside it (x - (x - hi) rounds once).
        x = self.tensor(node, node.input[0])
        c = self.channels[x]

        def step(tag, op, inputs, output=None, **fields):
            out = output or self.fresh(f"{node.output[0]}/{tag}", self.taken)
            entry = {"name": self.fresh(f"{node.name}/{tag}", self.node_names), "op": op, "inputs": list(inputs),
                     "output": out}
            for k, v in fields.items():
                if k in ("scale", "shift"):
                    entry[k] = self.put_weight(f"{node.name}/{tag}.{k}", np.full(c, v, np.float64))
                else:
                    entry[k] = v
            self.ir.append(entry)
            self.channels[out] = c
            return out
        final = node.output[0]
        y = x
        if hi is not None:
            t = step("above_max", "affine", [x], shift=-hi)
            t = step("relu_max", "activation", [t], activation="relu")
            t = step("minus_excess", "affine", [t], scale=-1.0)
            y = step("out" if lo is None else "capped", "add", [y, t], final if lo is None else None)
        if lo is not None:
            t = step("below_min", "affine", [x], scale=-1.0, shift=lo)
            t = step("relu_min", "activation", [t], activation="relu")
            step("out", "add", [y, t], final)

    def op_Concat(self, node, attrs):
        axis = attrs.get("axis")
        rank = 4 if self.layout == "nchw" else 2
        if axis not in (1, 1 - rank):
            raise self.fail(node, f"axis {axis}: only the channel axis (1) is supported")
        inputs = list(node.input)
        runs = dict(self.freq_runs.get(node.name, []))
        parts = []
        i = 0
        while i < len(inputs):
            if i in runs:
                x, include, first_exponent, pi, bands, used, end = runs[i]
                x = self.tensor(node, x)
                name = f"{node.name}.encode{i}"
                out = name + ".out"
                self.channels[out] = self.channels[x] * ((1 if include else 0) + 2 * bands)
                self.ir.append({"name": name, "op": "frequency_encode", "inputs": [x], "output": out,
                                "encoding": {"bands": bands, "first_exponent": first_exponent, "pi": pi,
                                             "include_input": include, "order": "band"},
                                "source": ", ".join(used)})
                parts.append(out)
                i = end
                continue
            parts.append(self.tensor(node, inputs[i]))
            i += 1
        if len(parts) == 1 and parts[0] != self.input.name:
            self.alias[node.output[0]] = parts[0]  # a concat of one tensor is that tensor
            return
        total = sum(self.channels[p] for p in parts)
        self.emit(node, "concat", parts, self.out(node, total))

    def _frequency_run(self, concat, inputs, i):
        """A run inputs[i:end] = [x,] Sin(s0 x), Cos(s0 x), Sin(2 s0 x), Cos(2 s0 x), ... (encode_frequencies'
        band order) -> (x, include_input, first_exponent, pi, bands, node names, end), or None."""
        def sincos(name, op):
            node = self.producer.get(name)
            if node is None or node.op_type != op or self.readers.get(name, []) != [concat]:
                return None
            mul = self.producer.get(node.input[0])
            if mul is None or mul.op_type != "Mul":
                return None
            if any(r.op_type not in ("Sin", "Cos") for r in self.readers.get(mul.output[0], [])):
                return None
            a, b = mul.input
            ca, cb = self.const(a), self.const(b)
            if (ca is None) == (cb is None):
                return None
            c, x = (ca, b) if ca is not None else (cb, a)
            if np.asarray(c).size != 1:
                return None
            return x, float(np.asarray(c, np.float64).reshape(-1)[0]), node, mul
        x = None
        include = False
        first = sincos(inputs[i], "Sin")
        if first is None:
            if i + 1 >= len(inputs):
                return None
            nxt = sincos(inputs[i + 1], "Sin")
            if nxt is None or inputs[i] != nxt[0]:
                return None
            include = True
            i += 1
        scales, used = [], []
        while i + 1 < len(inputs):
            s = sincos(inputs[i], "Sin")
            c = sincos(inputs[i + 1], "Cos")
            if s is None or c is None or s[0] != c[0] or s[1] != c[1] or (x is not None and s[0] != x):
                break
            x = s[0]
            scales.append(s[1])
            used += [s[2].name, c[2].name, s[3].name, c[3].name]
            i += 2
        if not scales:
            return None
        s0 = scales[0]
        if not (math.isfinite(s0) and s0 > 0):  # the bands of encode_frequencies are positive powers of two
            return None
        pi = False
        exponent = None
        for with_pi in (True, False):
            e = math.log2(s0 / math.pi) if with_pi else math.log2(s0)
            if abs(e - round(e)) < 1e-5 and -32 <= round(e) <= 31:
                pi, exponent = with_pi, int(round(e))
                break
        if exponent is None or exponent + len(scales) > 32:
            return None
        for b, s in enumerate(scales):
            want = 2.0 ** (exponent + b) * (math.pi if pi else 1.0)
            if abs(s - want) > 1e-6 * want:
                return None
        self.done.update(used)
        return x, include, exponent, pi, len(scales), sorted(set(used)), i

    # torch.nan_to_num(x) with its defaults, as torch.onnx exports it:
    #   r1 = Where(IsNaN(x), 0, x); [Cast]; r2 = Where(And(IsInf(r1), Greater(r1, 0)), FLT_MAX, r1); [Cast];
    #   r3 = Where(And(IsInf(r2), Less(r2, 0)), -FLT_MAX, r2)
    def op_Where(self, node, attrs):
        cond = self.producer.get(node.input[0])
        if cond is None or cond.op_type != "IsNaN" or cond.input[0] != node.input[2]:
            raise self.fail(node, "supported only as part of torch.nan_to_num(x) with its default limits")
        if not self._is_const_value(node.input[1], 0.0):
            raise self.fail(node, "nan_to_num with nan other than 0 is not supported")
        x = self.tensor(node, node.input[2])
        used = [cond.name, node.name]
        current = node.output[0]
        for compare, limit in (("Greater", FLT_MAX), ("Less", -FLT_MAX)):
            current = self._skip_casts(current, used)
            step = self._inf_step(current, compare, limit, used)
            if step is None:
                raise self.fail(node, f"torch.nan_to_num pattern not recognised (the {compare} step; only the "
                                      "default posinf / neginf are supported)")
            current = step
        current = self._skip_casts(current, used)
        self.done.update(used)
        self.emit(node, "nan_to_num", [x], current, source=", ".join(used))
        self.channels[current] = self.channels[x]

    def _is_const_value(self, name, value):
        c = self.const(name)
        return c is not None and np.asarray(c).size == 1 and float(np.asarray(c, np.float64).reshape(-1)[0]) == value

    def _skip_casts(self, name, used):
        while True:
            readers = self.readers.get(name, [])
            if len(readers) == 1 and readers[0].op_type == "Cast" and _attrs(self.onnx, readers[0]).get("to") == 1:
                used.append(readers[0].name)
                name = readers[0].output[0]
            else:
                return name

    def _follow_casts(self, name, chain):
        while True:
            readers = self.readers.get(name, [])
            if len(readers) != 1 or readers[0].op_type != "Cast":
                return name
            chain.append(readers[0].name)
            name = readers[0].output[0]

    def _inf_step(self, r, compare, limit, used):
        """Where(And(IsInf(r), compare(r, 0)), limit, r) reading r (Casts allowed between) -> its output, or None."""
        readers = self.readers.get(r, [])
        by = {n.op_type: n for n in readers}
        if len(readers) != 3 or len(by) != 3 or compare not in by or "Where" not in by:
            return None
        chain = []
        isinf = by.get("IsInf") or by.get("Cast")
        while isinf is not None and isinf.op_type == "Cast":
            chain.append(isinf.name)
            nxt = self.readers.get(isinf.output[0], [])
            isinf = nxt[0] if len(nxt) == 1 else None
        if isinf is None or isinf.op_type != "IsInf":
            return None
        cmp, where = by[compare], by["Where"]
        if cmp.input[0] != r or not self._is_const_value(cmp.input[1], 0.0):
            return None
        a = self._follow_casts(isinf.output[0], chain)
        b = self._follow_casts(cmp.output[0], chain)
        ands = self.readers.get(a, [])
        if len(ands) != 1 or ands[0].op_type != "And" or set(ands[0].input) != {a, b}:
            return None
        if where.input[0] != ands[0].output[0] or where.input[2] != r:
            return None
        c = self.const(where.input[1])
        if c is None or np.asarray(c).size != 1 or np.float32(np.asarray(c).reshape(-1)[0]) != np.float32(limit):
            return None
        used += chain + [isinf.name, cmp.name, ands[0].name, where.name]
        return where.output[0]

    def op_IsNaN(self, node, attrs):
        readers = self.readers.get(node.output[0], [])
        if len(readers) == 1 and readers[0].op_type == "Where":
            return  # mapped with its Where (op_Where), which comes later in topological order
        raise self.fail(node, "supported only as part of torch.nan_to_num(x) with its default limits")


def _check_weights(ir, weights, path, half):
    """Refuse a node whose tensor is not finite as stored (NaN or Inf in the file, made by folding constants, or
    beyond F16's range with --half), naming the .onnx file and the node."""
    dtype, name = (np.float16, "F16") if half else (np.float32, "F32")
    for n in ir:
        for field in ("weight", "bias", "scale", "shift"):
            if field not in n:
                continue
            with np.errstate(over="ignore", invalid="ignore"):
                bad = int(np.count_nonzero(~np.isfinite(weights[n[field]].astype(dtype))))
            if bad:
                raise ConversionError(f"{path}: node '{n['name']}' ({n.get('source', n['op'])}): its {field} has "
                                      f"{bad} value(s) that are not finite {name} numbers (NaN, Inf, or beyond "
                                      f"{name}'s range)")


def _check_loader_limits(config, channels, path):
    """Refuse what ngi's graph loader (host/src/models/graph_config.cpp) would refuse on reading the file back: more
    nodes than it loads, names longer than it reads, channel counts, kernels, strides and paddings beyond its
    limits (ngi/_constants.py, printed from the C++ definitions), naming the .onnx file and the node."""
    c = _constants
    g = config["graph"]
    nodes = g["nodes"]
    if len(nodes) > c.GRAPH_MAX_NODES:
        raise ConversionError(f"{path}: {len(nodes)} nodes; ngi loads at most {c.GRAPH_MAX_NODES}")

    def name_ok(x):
        return isinstance(x, str) and 1 <= len(x.encode()) <= c.GRAPH_MAX_NAME_BYTES

    rule = f"names of 1..{c.GRAPH_MAX_NAME_BYTES} bytes"
    for key in ("input", "output"):
        if not name_ok(g[key]):
            raise ConversionError(f"{path}: the graph {key} '{str(g[key])[:120]}...' is not one of ngi's {rule}")
    for key in ("input_nc", "output_nc"):
        if not 1 <= config[key] <= c.GRAPH_MAX_CHANNELS:
            raise ConversionError(f"{path}: {key} {config[key]} is beyond ngi's {c.GRAPH_MAX_CHANNELS} channels")
    worst = max(channels.values(), default=0)
    if worst > c.GRAPH_MAX_CHANNELS:
        t = max(channels, key=channels.get)
        raise ConversionError(f"{path}: tensor '{t[:120]}' has {worst} channels; ngi loads at most "
                              f"{c.GRAPH_MAX_CHANNELS}")
    for n in nodes:
        where = f"{path}: node '{str(n.get('name'))[:120]}' ({n.get('source', n.get('op'))})"
        names = [n.get("name"), n.get("output"), *n.get("inputs", [])] + [n[k] for k in ("weight", "bias", "scale",
                                                                                          "shift") if k in n]
        bad = next((x for x in names if not name_ok(x)), None)
        if bad is not None:
            raise ConversionError(f"{where}: '{str(bad)[:120]}...' ({len(str(bad).encode())} bytes) is not one of "
                                  f"ngi's {rule}")
        if len(n.get("inputs", [])) > c.GRAPH_MAX_NODE_INPUTS:
            raise ConversionError(f"{where}: {len(n['inputs'])} inputs; ngi takes at most {c.GRAPH_MAX_NODE_INPUTS}")
        limits = {"in": (1, c.GRAPH_MAX_CHANNELS), "out": (1, c.GRAPH_MAX_CHANNELS),
                  "stride": (1, c.GRAPH_MAX_STRIDE), "pad": (0, c.GRAPH_MAX_PAD),
                  "pads": (-c.GRAPH_MAX_PAD, c.GRAPH_MAX_PAD)}  # pad2d crops with negative pads
        # stride and pads are lists on max_pool2d ([h, w], [top, left, bottom, right]), numbers elsewhere
        values = [(k, v) for k in limits if k in n and k != "pads" for v in (n[k] if isinstance(n[k], list) else [n[k]])]
        values += [("pads", v) for v in n.get("pads", [])] + [("kernel", k) for k in n.get("kernel", [])]
        for key, v in values:
            lo, hi = limits.get(key, (1, c.GRAPH_MAX_KERNEL))
            if not lo <= v <= hi:
                raise ConversionError(f"{where}: {key} {v} is outside ngi's {lo}..{hi}")
        if n.get("slope") is not None and not (math.isfinite(n["slope"]) and abs(n["slope"]) <= 1.0):
            raise ConversionError(f"{where}: a LeakyRelu slope of {n['slope']} (ngi takes finite slopes in [-1, 1])")


def import_onnx(onnx_path, out_path, *, half=False, source=None, input_range=None):
    """Convert the ONNX file `onnx_path` to the ngi model file `out_path` (family "graph"); returns the config.
    input_range: (lo, hi), the range the network's inputs were trained in (the surround pipeline scales its features
    into it; without one the model runs on tensors only).

    Raises ConversionError (naming the node and op where there is one); nothing is written then."""
    check_output_file(out_path)  # before the work; write_model checks it again
    onnx = _onnx()
    model = _load(onnx, onnx_path)
    imp = _Importer(onnx, model, onnx_path)
    try:
        onnx.checker.check_model(model)
    except Exception as error:  # noqa: BLE001 (onnx.checker.ValidationError and protobuf errors)
        first = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise ConversionError(f"{onnx_path}: the ONNX checker refuses the model: {first}") \
            from None
    output = imp.run()
    ir = imp.ir
    weights = imp.weights
    _check_weights(ir, weights, onnx_path, half)
    used = {n[k] for n in ir for k in ("weight", "bias", "scale", "shift") if k in n}
    tensors = {k: v.astype(np.float32) for k, v in weights.items() if k in used}
    config = {
        "format_version": FORMAT_VERSION, "family": "graph", "input_nc": imp.input_nc,
        "output_nc": imp.channels[output],
        "graph": {"layout": imp.layout, "input": imp.input.name, "output": output, "nodes": ir},
        "onnx": {"opset": imp.opset, "producer": f"{model.producer_name} {model.producer_version}".strip(),
                 "nodes": len(model.graph.node),
                 **({"input_hw": list(imp.input_hw)} if imp.input_hw else {})},
        "source": source if source is not None else f"{os.path.basename(onnx_path)}, imported by ngi.convert",
        **({"input_range": [float(input_range[0]), float(input_range[1])]} if input_range is not None else {}),
    }
    _check_loader_limits(config, imp.channels, onnx_path)
    write_model(out_path, tensors, config, half=half)  # beside out_path, then renamed into place
    return config

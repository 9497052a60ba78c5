"""ngi model files (.safetensors): the writer, the reader and the config every generator family needs.

The file is a Hugging Face safetensors file written by hand (the `safetensors`
package is not a dependency): an 8-byte little-endian header length, a JSON
header padded with spaces to a multiple of 8 bytes, then the raw little-endian
tensor data. The ngi configuration travels as a JSON string in
`__metadata__["ngi"]`. docs/MODEL_FORMAT.md is the specification.

NumPy and the standard library only: write_model also takes torch tensors, but
this module never imports torch. The PyTorch checkpoint converter built on it
is ngi.convert.
"""

import json
import math
import os
import secrets
import stat
import struct

import numpy as np

from .dropout import DROPOUT_P

FORMAT_VERSION = 1
FAMILIES = ("pix2pix_unet", "deepillumination")
BN_MODES = ("running", "per_image")
DROPOUT_MODES = ("off", "seeded")
# What a pix2pix_unet generator's decoded output is (docs/MODEL_FORMAT.md, "output_mode"): the front view's whole
# lightmap (the thesis's; the default) or indirect light only, which the pipeline adds to the frame's direct light.
OUTPUT_MODES = ("lightmap", "indirect", "ssgi_residual")
# The settings of an SSGI gather (family "ssgi", and the "ssgi" object of a network that corrects it): the fields
# host/src/models/ssgi_config.cpp reads (docs/MODEL_FORMAT.md "ssgi").
SSGI_GATHER_FIELDS = ("view", "cluster_level", "bounces", "near_factor", "min_distance", "visibility_steps",
                      "thickness")

# Hyper-parameters both upstream generators hard-code; they are written into
# the config anyway so the C++ side never has to assume them (DROPOUT_P, the
# p of their nn.Dropout(0.5), is ngi.dropout's).
BN_EPS = 1e-05       # nn.BatchNorm2d default, not overridden upstream
LEAKY_SLOPE = 0.2    # nn.LeakyReLU(0.2, True)
# Both families are trained on images scaled to [-1, 1] and end in a Tanh.
VALUE_RANGE = [-1, 1]

METADATA_KEY = "__metadata__"
_NUMPY_DTYPES = {"F32": np.dtype("<f4"), "F16": np.dtype("<f2")}


class ConversionError(ValueError):
    """A checkpoint, option or file that cannot become (or is not) a valid ngi model file, or a file that ngi's
    tools do not read or write (the file rule below)."""


# --------------------------------------------------------------------------
# The file rule of ngi's Python tools, the C++ side's (host/src/base/file_util.cpp): only regular files are read or
# written. A FIFO blocks open() until a writer comes, /dev/zero never ends, and renaming a finished file over
# /dev/null (as root) replaces the device node with a regular file.
# --------------------------------------------------------------------------

# The most an input is read of: the C++ model loader's own file limit (docs/MODEL_FORMAT.md, "Container limits");
# generous for checkpoints (a pix2pix ngf 64 generator's is ~220 MB).
MAX_INPUT_BYTES = 4 << 30


def file_kind(mode):
    """What a file that is not regular is, in the C++ side's words."""
    return ("a directory" if stat.S_ISDIR(mode) else
            "a device, not a regular file" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else
            "a FIFO, not a regular file" if stat.S_ISFIFO(mode) else
            "a socket, not a regular file" if stat.S_ISSOCK(mode) else "not a regular file")


def check_input_file(path, max_bytes=MAX_INPUT_BYTES):
    """Refuse (ConversionError naming `path`) anything but an existing regular file of at most `max_bytes`.

    Judged by os.stat, which follows symlinks (a link to /dev/zero is a device), before anything opens the file:
    an open() of a FIFO would block. Returns the stat result."""
    try:
        st = os.stat(path)
    except OSError as error:
        raise ConversionError(f"cannot read {path}: {error.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise ConversionError(f"cannot read {path}: it is {file_kind(st.st_mode)}")
    if st.st_size > max_bytes:
        raise ConversionError(f"cannot read {path}: it is larger ({st.st_size} bytes) than the limit of "
                              f"{max_bytes} bytes")
    return st


def read_input_file(path, max_bytes=MAX_INPUT_BYTES):
    """The bytes of `path`, by the file rule (check_input_file); ConversionError naming the file otherwise."""
    check_input_file(path, max_bytes)
    try:
        # O_NONBLOCK: should the path have become a FIFO since the check, open() returns instead of waiting (fstat
        # below then refuses it); it changes nothing for a regular file.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as error:
        raise ConversionError(f"cannot read {path}: {error.strerror}") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(fd)  # of the file opened, which the check above may not have seen
        if not stat.S_ISREG(st.st_mode):
            raise ConversionError(f"cannot read {path}: it is {file_kind(st.st_mode)}")
        if st.st_size > max_bytes:
            raise ConversionError(f"cannot read {path}: it is larger ({st.st_size} bytes) than the limit of "
                                  f"{max_bytes} bytes")
        try:
            data = f.read(st.st_size)
            grew = f.read(1)
        except OSError as error:
            raise ConversionError(f"cannot read {path}: {error.strerror}") from None
    if grew:
        raise ConversionError(f"cannot read {path}: it grew while it was read")
    return data


def check_output_file(path):
    """Refuse (ConversionError) an output path that exists and is not a regular file (a folder, /dev/null, a
    FIFO): the rename that puts a finished file into place would replace it."""
    try:
        st = os.stat(path)
    except OSError:
        return  # absent (or unreachable: the write says why)
    if not stat.S_ISREG(st.st_mode):
        raise ConversionError(f"cannot write {path}: it exists and is {file_kind(st.st_mode)}; refusing to replace it")


def write_file_atomic(path, write):
    """Call write(f) on a new file beside `path`, then rename it to `path`: the file appears complete or not at all.

    An existing `path` that is not a regular file is refused before anything is written (check_output_file). A
    failure (the folder missing or not writable, a full disk) removes the temporary file and raises ConversionError
    naming `path`."""
    path = os.fspath(path)
    check_output_file(path)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        while True:
            # A short name of our own (not tempfile.mkstemp: its files are 0600, and os.replace would keep that
            # mode; here the umask applies, as to any new file). Short, so that it fits where `path`'s name fits.
            tmp = os.path.join(folder, f".ngi-{secrets.token_hex(6)}.tmp")
            try:
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
                break
            except FileExistsError:
                continue
    except OSError as error:
        raise ConversionError(f"cannot write {path}: {error.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException as error:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(error, OSError):
            raise ConversionError(f"cannot write {path}: {error.strerror or error}") from None
        raise


# --------------------------------------------------------------------------
# safetensors I/O
# --------------------------------------------------------------------------

def write_model(path, tensors, config, half=False):
    """Write `tensors` (name -> np.ndarray | torch.Tensor) and `config` to `path`.

    Tensors are stored in the iteration order of `tensors`, contiguously, as
    F32 (or F16 with half=True). The config dict is stored as a JSON string in
    __metadata__["ngi"], because safetensors metadata values must be strings.
    The file is written beside `path` and renamed into place (write_file_atomic).
    """
    dtype_name = "F16" if half else "F32"
    dtype = _NUMPY_DTYPES[dtype_name]
    header = {}
    blobs = []
    offset = 0
    for name, value in tensors.items():
        if name == METADATA_KEY:
            raise ConversionError(f"'{METADATA_KEY}' is reserved and cannot be a tensor name")
        if hasattr(value, "detach"):  # a torch.Tensor (duck-typed: this module does not import torch)
            value = value.detach().cpu().numpy()
        # np.array (unlike ascontiguousarray) keeps 0-d tensors 0-d. Overflow
        # warnings are silenced because the isfinite check below reports it by name.
        with np.errstate(over="ignore"):
            array = np.array(value, dtype=dtype, order="C")
        # Checked after the cast: a finite float32 above 65504 becomes inf in F16.
        if not np.isfinite(array).all():
            raise ConversionError(
                f"tensor '{name}' has non-finite values as {dtype_name}"
                f" (max |value| before the cast: {np.max(np.abs(np.asarray(value, np.float64)))})")
        data = array.tobytes()
        header[name] = {"dtype": dtype_name,
                        "shape": list(array.shape),
                        "data_offsets": [offset, offset + len(data)]}
        blobs.append(data)
        offset += len(data)
    try:
        # allow_nan=False: Python would write NaN / Infinity, which is not JSON (the loader's "malformed JSON").
        header[METADATA_KEY] = {"ngi": json.dumps(config, allow_nan=False)}
    except ValueError:
        raise ConversionError(f"{path}: config field '{_non_finite_key(config)}' is not a finite number; "
                              "JSON cannot hold NaN or Infinity") from None

    header_bytes = json.dumps(header, separators=(",", ":")).encode("utf-8")
    # Padding keeps the data section 8-byte aligned for readers that mmap it.
    header_bytes += b" " * (-len(header_bytes) % 8)

    def write(f):
        f.write(struct.pack("<Q", len(header_bytes)))
        f.write(header_bytes)
        for data in blobs:
            f.write(data)
    write_file_atomic(path, write)


def _non_finite_key(value, key=""):
    """The dotted path of the first non-finite float in a JSON-like value (for write_model's message), or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return key
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, (list, tuple)) else ()
    for k, v in items:
        found = _non_finite_key(v, f"{key}[{k}]" if isinstance(k, int) else f"{key}.{k}" if key else str(k))
        if found:
            return found
    return None


def _read_header(path, f):
    """(tensor entries of the header, ngi config) of the open model file `f`, read from its start."""
    prefix = f.read(8)
    if len(prefix) < 8:
        raise ConversionError(f"{path}: too short to be a safetensors file")
    (header_len,) = struct.unpack("<Q", prefix)
    if 8 + header_len > os.fstat(f.fileno()).st_size:
        raise ConversionError(f"{path}: header length {header_len} exceeds the file size")
    header = json.loads(f.read(header_len).decode("utf-8"))
    metadata = header.pop(METADATA_KEY, {})
    if "ngi" not in metadata:
        raise ConversionError(f"{path}: no __metadata__.ngi config; not an ngi model file")
    return header, json.loads(metadata["ngi"])


def read_config(path):
    """The ngi config of a model file, read from the header only (the tensor data is not read)."""
    check_input_file(path)
    with open(path, "rb") as f:
        return _read_header(path, f)[1]


def read_model(path):
    """Read an ngi model file; returns (tensors: dict name -> np.ndarray, config: dict).

    Arrays keep their stored dtype (float32 or float16), in file order.
    """
    check_input_file(path)
    with open(path, "rb") as f:
        header, config = _read_header(path, f)
        data = memoryview(f.read())

    tensors = {}
    for name, entry in header.items():
        if entry["dtype"] not in _NUMPY_DTYPES:
            raise ConversionError(f"{path}: tensor '{name}' has unsupported dtype {entry['dtype']}")
        dtype = _NUMPY_DTYPES[entry["dtype"]]
        begin, end = entry["data_offsets"]
        count = int(np.prod(entry["shape"], dtype=np.int64))
        if not 0 <= begin <= end <= len(data) or end - begin != count * dtype.itemsize:
            raise ConversionError(f"{path}: tensor '{name}' has bad data_offsets {entry['data_offsets']}")
        tensors[name] = np.frombuffer(data[begin:end], dtype=dtype).reshape(entry["shape"]).copy()
    return tensors, config


# --------------------------------------------------------------------------
# Expected state_dict layout of each family
# --------------------------------------------------------------------------

def _batch_norm(shapes, prefix, channels):
    # num_batches_tracked is deliberately absent: it only matters for training.
    for suffix in ("weight", "bias", "running_mean", "running_var"):
        shapes[prefix + suffix] = (channels,)


def _pix2pix_shapes(input_nc, output_nc, ngf, num_downs):
    """Tensor name -> shape of junyanz's UnetGenerator with norm='batch', in state_dict order.

    Each UnetSkipConnectionBlock is an nn.Sequential called `model`, and a
    block's submodule sits at index 1 (outermost) or 3 (others) of it, hence
    names like model.model.1.model.3.model.1.weight.
    """
    # (outer_nc, inner_nc) of each block, outermost first.
    levels = [(output_nc, ngf), (ngf, ngf * 2), (ngf * 2, ngf * 4), (ngf * 4, ngf * 8)]
    levels += [(ngf * 8, ngf * 8)] * (num_downs - 4)
    innermost = num_downs - 1
    shapes = {}

    def block(level, prefix):
        outer, inner = levels[level]
        # ConvTranspose2d weights are (in, out, kh, kw); Conv2d are (out, in, kh, kw).
        if level == 0:
            # [downconv, submodule, uprelu, upconv, tanh]; the downconv has no
            # bias (use_bias is False for BatchNorm), the upconv keeps its default bias.
            shapes[prefix + "0.weight"] = (inner, input_nc, 4, 4)
            block(1, prefix + "1.model.")
            shapes[prefix + "3.weight"] = (inner * 2, outer, 4, 4)
            shapes[prefix + "3.bias"] = (outer,)
        elif level == innermost:
            # [downrelu, downconv, uprelu, upconv, upnorm]: no down-norm.
            shapes[prefix + "1.weight"] = (inner, outer, 4, 4)
            shapes[prefix + "3.weight"] = (inner, outer, 4, 4)
            _batch_norm(shapes, prefix + "4.", outer)
        else:
            # [downrelu, downconv, downnorm, submodule, uprelu, upconv, upnorm(, dropout)]
            shapes[prefix + "1.weight"] = (inner, outer, 4, 4)
            _batch_norm(shapes, prefix + "2.", inner)
            block(level + 1, prefix + "3.model.")
            shapes[prefix + "5.weight"] = (inner * 2, outer, 4, 4)
            _batch_norm(shapes, prefix + "6.", outer)

    block(0, "model.model.")
    return shapes


def _deepillumination_shapes(input_nc, output_nc, ngf):
    """Tensor name -> shape of DeepIllumination's G, in state_dict order."""
    encoder_nc = [input_nc, ngf, ngf * 2, ngf * 4] + [ngf * 8] * 5
    decoder_nc = [ngf * 8] * 4 + [ngf * 4, ngf * 2, ngf, output_nc]
    shapes = {}
    for k in range(1, 9):
        shapes[f"conv{k}.weight"] = (encoder_nc[k], encoder_nc[k - 1], 4, 4)
        shapes[f"conv{k}.bias"] = (encoder_nc[k],)
    for k in range(1, 9):
        # Decoder k > 1 reads cat(decoder k-1, its encoder skip): twice the channels.
        in_nc = ngf * 8 if k == 1 else 2 * decoder_nc[k - 2]
        shapes[f"deconv{k}.weight"] = (in_nc, decoder_nc[k - 1], 4, 4)
        shapes[f"deconv{k}.bias"] = (decoder_nc[k - 1],)
    for name, channels in (("batch_norm", ngf), ("batch_norm2", ngf * 2),
                           ("batch_norm4", ngf * 4), ("batch_norm8", ngf * 8)):
        _batch_norm(shapes, name + ".", channels)
    return shapes


def expected_shapes(config):
    """Tensor name -> shape that `config` requires, in upstream state_dict order."""
    if config["family"] == "pix2pix_unet":
        return _pix2pix_shapes(config["input_nc"], config["output_nc"], config["ngf"], config["num_downs"])
    return _deepillumination_shapes(config["input_nc"], config["output_nc"], config["ngf"])


# --------------------------------------------------------------------------
# Config
# --------------------------------------------------------------------------

def make_config(family, *, bn_mode, input_nc=12, output_nc=3, ngf=64, num_downs=8,
                dropout="off", dropout_seed=0, input_layout=(), source="", output_mode="lightmap"):
    """Validate the options and return the complete ngi config dict."""
    if family not in FAMILIES:
        raise ConversionError(f"family must be one of {FAMILIES}, got {family!r}")
    if output_mode not in OUTPUT_MODES:
        raise ConversionError(f"output_mode must be one of {OUTPUT_MODES}, got {output_mode!r}")
    if output_mode != "lightmap" and family != "pix2pix_unet":
        raise ConversionError(f"output_mode {output_mode!r} is supported by family pix2pix_unet only, "
                              f"not {family!r}")
    if bn_mode not in BN_MODES:
        raise ConversionError(f"bn_mode must be one of {BN_MODES}, got {bn_mode!r}")
    if dropout not in DROPOUT_MODES:
        raise ConversionError(f"dropout must be one of {DROPOUT_MODES}, got {dropout!r}")
    for name, value in (("input_nc", input_nc), ("output_nc", output_nc), ("ngf", ngf)):
        if not isinstance(value, int) or value < 1:
            raise ConversionError(f"{name} must be a positive integer, got {value!r}")
    if family == "deepillumination" and num_downs != 8:
        raise ConversionError(f"deepillumination has exactly 8 downsamplings, got num_downs={num_downs}")
    if family == "pix2pix_unet" and (not isinstance(num_downs, int) or num_downs < 5):
        # junyanz's UnetGenerator hard-wires four outer blocks plus an innermost one.
        raise ConversionError(f"pix2pix_unet needs num_downs >= 5, got {num_downs!r}")
    if not isinstance(dropout_seed, int) or not 0 <= dropout_seed < 2 ** 32:
        raise ConversionError(f"dropout_seed must be a uint32, got {dropout_seed!r}")
    input_layout = list(input_layout)
    if input_layout and len(input_layout) != input_nc:
        raise ConversionError(f"input_layout names {len(input_layout)} channels but input_nc is {input_nc}")
    config = {
        "format_version": FORMAT_VERSION,
        "family": family,
        "input_nc": input_nc,
        "output_nc": output_nc,
        "ngf": ngf,
        "num_downs": num_downs,
        "norm": "batch",
        "bn_mode": bn_mode,
        "bn_eps": BN_EPS,
        "dropout": dropout,
        "dropout_p": DROPOUT_P,
        "dropout_seed": dropout_seed,
        "leaky_slope": LEAKY_SLOPE,
        "input_layout": input_layout,
        "input_range": VALUE_RANGE,
        "output_range": VALUE_RANGE,
        "output_mode": output_mode,
        "source": source,
    }
    if output_mode != "lightmap":
        # A reader that does not know the key would decode indirect light as the whole lightmap, silently dark:
        # "required" makes older readers refuse the file instead.
        config["required"] = ["output_mode"]
    return config


# --------------------------------------------------------------------------
# Family voxel_sh (seed 004): per-voxel SH coefficients from raw voxel attributes
# --------------------------------------------------------------------------

VOXEL_SH_ARCHITECTURES = ("mlp", "set", "resnet")
VOXEL_SH_INPUTS = 10    # x, y, z, albedo rgb, emission rgb, voxel id
VOXEL_SH_OUTPUTS = 27   # SH bands 0-2 x RGB, [3][9]
VOXEL_SH_INPUT_LAYOUT = ("x", "y", "z", "albedo.r", "albedo.g", "albedo.b",
                         "emission.r", "emission.g", "emission.b", "id")
_VOXEL_SH_MAX_WIDTH = 4096


def voxel_sh_shapes(config):
    """Tensor name -> shape of a voxel_sh network (docs/MODEL_FORMAT.md "voxel_sh"), in file order."""
    arch = config["architecture"]
    shapes = {}

    def linear(prefix, fan_in, fan_out):
        shapes[prefix + ".weight"] = (fan_out, fan_in)
        shapes[prefix + ".bias"] = (fan_out,)

    if arch == "mlp":
        widths = [VOXEL_SH_INPUTS] + list(config["hidden"]) + [VOXEL_SH_OUTPUTS]
        for i in range(len(widths) - 1):
            linear(f"layers.{i}", widths[i], widths[i + 1])
    elif arch == "set":
        phi = [VOXEL_SH_INPUTS] + list(config["phi"])
        for i in range(len(phi) - 1):
            linear(f"phi.{i}", phi[i], phi[i + 1])
        rho = [3 * phi[-1]] + list(config["rho"]) + [VOXEL_SH_OUTPUTS]  # [h | max | mean]
        for i in range(len(rho) - 1):
            linear(f"rho.{i}", rho[i], rho[i + 1])
    elif arch == "resnet":
        linear("input", VOXEL_SH_INPUTS, config["width"])
        for i in range(config["blocks"]):
            linear(f"blocks.{i}", config["width"], config["width"])
        linear("output", config["width"], VOXEL_SH_OUTPUTS)
    else:
        raise ConversionError(f"voxel_sh architecture must be one of {VOXEL_SH_ARCHITECTURES}, got {arch!r}")
    return shapes


def make_voxel_sh_config(architecture, *, grid, input_lo, input_hi, output_mean, output_std, hidden=None,
                         phi=None, rho=None, width=None, blocks=None, source="", training=None):
    """Validate and return the config of a voxel_sh model file. Widths: `hidden` (mlp), `phi` and `rho` (set),
    `width` and `blocks` (resnet); the other architectures' must stay None."""
    if architecture not in VOXEL_SH_ARCHITECTURES:
        raise ConversionError(f"architecture must be one of {VOXEL_SH_ARCHITECTURES}, got {architecture!r}")

    def width_list(name, value, lo_len, hi_len):
        value = [int(v) for v in value] if value is not None else None
        if value is None or not lo_len <= len(value) <= hi_len or not all(1 <= v <= _VOXEL_SH_MAX_WIDTH for v in value):
            raise ConversionError(f"{name} must be {lo_len}..{hi_len} widths in 1..{_VOXEL_SH_MAX_WIDTH}, got {value!r}")
        return value

    def floats(name, value, n, nonnegative=False):
        v = np.asarray(value, dtype=np.float64).reshape(-1)
        if v.shape != (n,) or not np.isfinite(v).all() or (np.abs(v) > 1e30).any() or (nonnegative and (v < 0).any()):
            raise ConversionError(f"{name} must be {n} finite numbers{' >= 0' if nonnegative else ''}, got {value!r}")
        return [float(x) for x in v]

    grid = [int(g) for g in grid]
    if len(grid) != 3 or not all(1 <= g <= 65536 for g in grid) or grid[0] * grid[1] * grid[2] > 2 ** 24:
        raise ConversionError(f"grid must be [X, Y, Z] in 1..65536 with X Y Z <= 2^24, got {grid!r}")
    lo, hi = floats("input_lo", input_lo, VOXEL_SH_INPUTS), floats("input_hi", input_hi, VOXEL_SH_INPUTS)
    for k, (a, b) in enumerate(zip(lo, hi)):
        if b < a or (b > a and 2.0 / (b - a) > 1e30):
            raise ConversionError(f"input channel {k}: lo {a}, hi {b}; needs lo == hi or 2e-30 <= hi - lo")
    config = {"format_version": FORMAT_VERSION, "family": "voxel_sh", "architecture": architecture,
              "input_nc": VOXEL_SH_INPUTS, "output_nc": VOXEL_SH_OUTPUTS, "grid": grid,
              "input_layout": list(VOXEL_SH_INPUT_LAYOUT), "input_lo": lo, "input_hi": hi,
              "output_mean": floats("output_mean", output_mean, VOXEL_SH_OUTPUTS),
              "output_std": floats("output_std", output_std, VOXEL_SH_OUTPUTS, nonnegative=True)}
    given = {"hidden": hidden, "phi": phi, "rho": rho, "width": width, "blocks": blocks}
    own = {"mlp": ("hidden",), "set": ("phi", "rho"), "resnet": ("width", "blocks")}[architecture]
    stray = [k for k, v in given.items() if v is not None and k not in own]
    if stray:
        raise ConversionError(f"{stray} do not apply to architecture {architecture!r}")
    if architecture == "mlp":
        config["hidden"] = width_list("hidden", hidden, 1, 64)
    elif architecture == "set":
        config["phi"] = width_list("phi", phi, 1, 16)
        config["rho"] = width_list("rho", rho, 1, 16)
    else:
        config["width"] = width_list("width", None if width is None else [width], 1, 1)[0]
        if blocks is None or not 0 <= int(blocks) <= 256:
            raise ConversionError(f"blocks must be in 0..256, got {blocks!r}")
        config["blocks"] = int(blocks)
    config["source"] = source
    if training is not None:
        config["training"] = training
    return config


def write_voxel_sh_model(path, tensors, config, half=False):
    """write_model for a voxel_sh config: the tensors must be exactly voxel_sh_shapes(config) (names and shapes);
    they are written in that order."""
    shapes = voxel_sh_shapes(config)
    missing = [k for k in shapes if k not in tensors]
    extra = [k for k in tensors if k not in shapes]
    if missing or extra:
        raise ConversionError(f"voxel_sh {config['architecture']}: missing tensors {missing}, unexpected {extra}")
    for name, shape in shapes.items():
        got = tuple(np.shape(tensors[name].detach().cpu().numpy() if hasattr(tensors[name], "detach") else tensors[name]))
        if got != shape:
            raise ConversionError(f"tensor '{name}' is {list(got)}, expected {list(shape)}")
    write_model(path, {name: tensors[name] for name in shapes}, config, half=half)

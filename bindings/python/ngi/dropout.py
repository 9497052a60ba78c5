"""ngi's seeded dropout: the counter-based hash whose keep mask the OpenCL kernel computes bit for bit.

docs/MODEL_FORMAT.md specifies it. NumPy only: the PyTorch module built on it (SeededDropout) is in
ngi.reference_models.
"""

import numpy as np

# Both upstream generators use nn.Dropout(0.5); the model-file config carries it as "dropout_p".
DROPOUT_P = 0.5


def mix32(x):
    """The 32-bit integer hash of ngi's dropout; x is a np.uint32 array, wrapping arithmetic."""
    x = x ^ (x >> np.uint32(16))
    x = x * np.uint32(0x7FEB352D)
    x = x ^ (x >> np.uint32(15))
    x = x * np.uint32(0x846CA68B)
    return x ^ (x >> np.uint32(16))


def dropout_keep_mask(seed, site, numel, p):
    """Boolean keep mask for the flat NCHW indices 0..numel-1 of dropout site `site`."""
    site_key = mix32(np.array([(seed + 0x9E3779B9 * (site + 1)) & 0xFFFFFFFF], dtype=np.uint32))
    u = mix32(site_key ^ np.arange(numel, dtype=np.uint32))
    # The top 24 bits as a float in [0, 1): exact in float32, and compared in
    # float32 like the OpenCL kernel does, so no element can round differently.
    uniform = (u >> np.uint32(8)).astype(np.float32) * np.float32(2.0 ** -24)
    return uniform >= np.float32(p)

"""Scoring a lightmap against a path-traced reference exactly as `ngi lightmap` does, for any rung of the zoo.

`ngi lightmap` scores the model's front-view lightmap at the frame's own face size: *final* = tone-mapped final
images (lightmap x albedo + emission + env, ACES, sRGB; data range 1), *lightmap* = linear HDR lightmaps (data
range = the reference's maximum). The ladder has rungs that run at a smaller face size than the reference; their
lightmap is upsampled bilinearly (pixel centres at +0.5, edges clamped: the library's resize_bilinear, PyTorch's
align_corners=False) to the reference's size and composed there with the full-resolution albedo, emission and
env, which is what a renderer that has its own full-resolution G-buffer does with a low-resolution lightmap.
At equal sizes the composition equals the pipeline's 'final' output (checked by ngi_train.generator.ladder_eval).

Needs the native module (ngi._ngi) for tone mapping and metrics.
"""

import numpy as np

from . import _constants, _ngi

LIGHT_MAX = _constants.LIGHT_MAX  # the largest lightmap value the library's decoding produces (kernels/compose.cl)
LUMA = np.array(_constants.REC709_LUMA, np.float32)  # Rec. 709, as outside_light_share


def upsample(image, size):
    """Bilinear resize of a [C, h, w] image to [C, size, size]: pixel centres at +0.5, edges clamped (the library's
    resize_bilinear kernel). The identity when the size already matches."""
    image = np.asarray(image, np.float32)
    c, h, w = image.shape
    if h == size and w == size:
        return image

    def axis(src, dst):
        f = np.clip((np.arange(dst, dtype=np.float64) + 0.5) * (src / dst) - 0.5, 0.0, src - 1)
        i0 = np.floor(f).astype(np.int64)
        i1 = np.minimum(i0 + 1, src - 1)
        return i0, i1, (f - i0).astype(np.float32)

    y0, y1, ay = axis(h, size)
    x0, x1, ax = axis(w, size)
    top = image[:, y0][:, :, x0] * (1 - ax) + image[:, y0][:, :, x1] * ax
    bottom = image[:, y1][:, :, x0] * (1 - ax) + image[:, y1][:, :, x1] * ax
    return (top * (1 - ay)[:, None] + bottom * ay[:, None]).astype(np.float32)


def _clean_light(v):
    v = np.nan_to_num(np.asarray(v, np.float32), nan=0.0, posinf=np.finfo(np.float32).max, neginf=0.0)
    return np.maximum(v, 0.0)


def compose(frame, lighting):
    """lighting x albedo + emission + env of the frame's front face (kernels/compose.cl compose_final: albedo NaN -> 0
    and clamped to [0, 1], light terms NaN / negative -> 0)."""
    front = lambda name: frame.feature(name)[0] if frame.feature(name) is not None else 0.0  # face 0 = front
    albedo = np.clip(np.nan_to_num(front("albedo"), nan=0.0), 0.0, 1.0)
    out = _clean_light(lighting) * albedo + _clean_light(front("emission")) + _clean_light(front("env"))
    return np.minimum(out, np.finfo(np.float32).max).astype(np.float32)


def display(pipeline, frame, lighting):
    """The tone-mapped final image (ACES, sRGB, [0, 1]) of `lighting` on `frame`'s front face."""
    return pipeline.tonemap(compose(frame, lighting))


class Reference:
    """A frame with a reference, prepared once for scoring many lightmaps against it."""

    def __init__(self, device, pipeline, frame):
        if frame.reference is None:
            raise _ngi.InputError("scoring: the frame has no reference.exr")
        self.device, self.pipeline, self.frame = device, pipeline, frame
        self.n = frame.n
        self.final = display(pipeline, frame, frame.reference)
        self.peak = max(float(np.max(frame.reference)), 1e-12)

    def score(self, lightmap):
        """{'final': {mse, psnr, ssim}, 'lightmap': {...}, 'display': the tone-mapped final image} of a [3, n, n]
        lightmap (n <= the reference's size; upsampled first). NaN and negative values count as 0."""
        # Sanitized as compose_final sanitizes light terms, and capped like the library's decoding (65504, or the
        # reference's own peak if that is higher) so that the linear metric stays defined.
        lm = np.minimum(upsample(_clean_light(lightmap), self.n), max(LIGHT_MAX, self.peak))
        shown = display(self.pipeline, self.frame, lm)
        final = _ngi.compare_images(self.device, shown, self.final, 1.0)
        light = _ngi.compare_images(self.device, lm, self.frame.reference, self.peak)
        pick = lambda m: {k: m[k] for k in ("mse", "psnr", "ssim")}
        return {"final": pick(final), "lightmap": pick(light), "display": shown}


def luminance(image):
    """Rec. 709 luminance of a [3, H, W] image."""
    return np.tensordot(LUMA, np.asarray(image, np.float32), axes=1)

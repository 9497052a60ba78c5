// 2D padding of planar C x H x W float32 (ONNX Pad over H and W, PyTorch F.pad with 4 pads) to
// C x (H + top + bottom) x (W + left + right). A batch is folded into C: every plane pads on its own.
//
// Output (c, oy, ox) reads the input at (iy, ix) = (oy - top, ox - left) when that lies in the plane; outside it:
//   constant: the value `value` (any float, NaN included, stored as given);
//   reflect:  the mirror image about the edge pixel, which is not repeated (ONNX 'reflect', PyTorch 'reflect'):
//             -k reads k, n - 1 + k reads n - 1 - k. The host keeps every pad below its axis' size, so one
//             reflection always lands inside the plane;
//   edge:     the nearest edge pixel (ONNX 'edge', PyTorch 'replicate').
// Copies only: every output is one of the inputs or the constant, exact.
//
// Build options, the host's (host/src/ops/pad2d.hpp, pad2d_defines()): PAD2D_LOCAL, the work-group size, and the
// mode codes PAD2D_CONSTANT, PAD2D_REFLECT and PAD2D_EDGE (PadMode).
#if !defined(PAD2D_LOCAL) || !defined(PAD2D_CONSTANT) || !defined(PAD2D_REFLECT) || !defined(PAD2D_EDGE)
#error "pad2d.cl needs PAD2D_LOCAL and the mode codes PAD2D_CONSTANT, PAD2D_REFLECT, PAD2D_EDGE: build it through Pad2d (pad2d_defines(), host/src/ops/pad2d.hpp)"
#endif

// The input index that index i (possibly outside [0, n)) reads along an axis of n pixels, for the reflect and edge
// modes. Reflect: pads < n keep i in (-n, 2n - 1), where one mirror step suffices.
static inline int pad2d_source(const int i, const int n, const int mode) {
    if (mode == PAD2D_REFLECT) {
        const int r = i < 0 ? -i : i;
        return r >= n ? 2 * (n - 1) - r : r;
    }
    return clamp(i, 0, n - 1);
}

// Launch: 1-D over C * OH * OW outputs (rounded up to PAD2D_LOCAL; the host keeps the count below 2^31),
// work-item i = (c * OH + oy) * OW + ox. x_off, y_off: the tensors' offsets in floats. top, left: the pads before
// the plane (bottom and right only shape OH and OW). mode: PAD2D_CONSTANT, PAD2D_REFLECT or PAD2D_EDGE.
__kernel __attribute__((reqd_work_group_size(PAD2D_LOCAL, 1, 1)))
void pad2d(__global const float* restrict x, const int x_off, const int C, const int H, const int W,
           __global float* restrict y, const int y_off, const int OH, const int OW, const int top, const int left,
           const int mode, const float value) {
    const int i = get_global_id(0);
    if (i >= C * OH * OW) return;
    const int ox = i % OW, t = i / OW;
    const int oy = t % OH, c = t / OH;
    int iy = oy - top, ix = ox - left;
    const bool inside = iy >= 0 && iy < H && ix >= 0 && ix < W;
    if (!inside) {
        if (mode == PAD2D_CONSTANT) {
            y[y_off + i] = value;
            return;
        }
        iy = pad2d_source(iy, H, mode);
        ix = pad2d_source(ix, W, mode);
    }
    y[y_off + i] = x[x_off + ((size_t)c * H + iy) * W + ix];
}

#!/usr/bin/python3
"""Write a MagicaVoxel .vox object for seed 001's AO experiment: a trefoil knot tube (self-occluding crossings,
a hole through every lobe, concave grooves where the tube passes itself) standing on a small plinth.

    /usr/bin/python3 tools/make_vox_object.py --out scenes/trefoil.vox

Deterministic. MagicaVoxel's axes are z-up; ngi maps (x, y, z)_vox -> (x, z, -y) (ngi/scene.hpp).
The file: VOX 150, MAIN with SIZE, XYZI and RGBA chunks (one model, palette index 1 = light grey).
"""

import argparse
import struct

import numpy as np


def trefoil_voxels(size=72, tube=4.2, scale=9.5):
    t = np.linspace(0.0, 2.0 * np.pi, 4000, endpoint=False)
    # The classic trefoil: (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t), scaled.
    curve = np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t) * 1.3], 1)
    curve = curve * scale + size / 2.0
    g = np.arange(size) + 0.5
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    solid = np.zeros(len(pts), bool)
    for c in np.array_split(curve, 40):  # distance to the polyline's points, in chunks (memory)
        lo, hi = c.min(0) - tube - 1, c.max(0) + tube + 1
        near = np.all((pts >= lo) & (pts <= hi), 1)
        idx = np.nonzero(near)[0]
        d2 = ((pts[idx, None, :] - c[None, :, :]) ** 2).sum(-1).min(1)
        solid[idx[d2 <= tube * tube]] = True
    vox = solid.reshape(size, size, size)
    # A plinth under the knot (z is up in MagicaVoxel): a 20 x 20 x 3 slab below the lowest point.
    zs = np.nonzero(vox.any((0, 1)))[0]
    z0 = max(int(zs.min()) - 3, 0)
    c = size // 2
    vox[c - 10:c + 10, c - 10:c + 10, z0:z0 + 3] = True
    # and a post from the plinth up to the knot's bottom so it stands
    col = vox[c - 2:c + 2, c - 2:c + 2, z0 + 3:]
    first = np.argmax(col.any((0, 1))) if col.any() else 0
    vox[c - 2:c + 2, c - 2:c + 2, z0 + 3:z0 + 3 + first + 1] = True
    return vox


def chunk(tag, content, children=b""):
    return tag + struct.pack("<ii", len(content), len(children)) + content + children


def write_vox(path, vox):
    sx, sy, sz = vox.shape
    xyz = np.argwhere(vox)
    xyzi = struct.pack("<i", len(xyz)) + b"".join(struct.pack("<BBBB", int(a), int(b), int(c), 1) for a, b, c in xyz)
    palette = bytearray()
    for i in range(256):
        palette += bytes([200, 200, 200, 255])
    children = chunk(b"SIZE", struct.pack("<iii", sx, sy, sz)) + chunk(b"XYZI", xyzi) + chunk(b"RGBA", bytes(palette))
    data = b"VOX " + struct.pack("<i", 150) + chunk(b"MAIN", b"", children)
    with open(path, "wb") as f:
        f.write(data)
    return len(xyz)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    n = write_vox(a.out, trefoil_voxels())
    print(f"{a.out}: {n} voxels")


if __name__ == "__main__":
    main()

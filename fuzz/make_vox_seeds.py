#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_vox (fuzz/corpus/vox/*.vox): small valid MagicaVoxel files covering every chunk
the loader reads (SIZE, XYZI, RGBA, MATL, nTRN with _t/_r, nGRP, nSHP) and some it skips. Run from the repo root:
/usr/bin/python3 fuzz/make_vox_seeds.py"""
import os
import struct


def i32(v):
    return struct.pack("<i", v)


def chunk(cid, content=b"", children=b""):
    return cid.encode() + i32(len(content)) + i32(len(children)) + content + children


def s(x):
    x = x.encode()
    return i32(len(x)) + x


def dct(kv):
    return i32(len(kv)) + b"".join(s(k) + s(v) for k, v in kv)


def size(x, y, z):
    return chunk("SIZE", i32(x) + i32(y) + i32(z))


def xyzi(vs):
    return chunk("XYZI", i32(len(vs)) + b"".join(bytes(v) for v in vs))


def ntrn(nid, child, frames=({},), attrs=()):
    return chunk("nTRN", i32(nid) + dct(list(attrs)) + i32(child) + i32(-1) + i32(0) + i32(len(frames)) +
                 b"".join(dct(list(f.items())) for f in frames))


def ngrp(nid, kids):
    return chunk("nGRP", i32(nid) + dct([]) + i32(len(kids)) + b"".join(i32(k) for k in kids))


def nshp(nid, models):
    return chunk("nSHP", i32(nid) + dct([]) + i32(len(models)) + b"".join(i32(m) + dct([]) for m in models))


def vox(children, version=150):
    return b"VOX " + i32(version) + chunk("MAIN", b"", children)


def seeds():
    box = [(x, y, z, 1 + (x + y + z) % 7) for x in range(3) for y in range(2) for z in range(4) if (x + y + z) % 2 == 0]
    rgba = chunk("RGBA", b"".join(bytes((i, 255 - i, i // 2, 255)) for i in range(256)))
    yield "single.vox", vox(size(3, 2, 4) + xyzi(box))
    yield "palette_emit.vox", vox(size(2, 2, 2) + xyzi([(0, 0, 0, 5), (1, 1, 1, 9), (1, 0, 1, 5)]) + rgba +
                                  chunk("MATL", i32(5) + dct([("_type", "_emit"), ("_emit", "0.5"), ("_flux", "1")])) +
                                  chunk("MATL", i32(9) + dct([("_type", "_diffuse")])))
    yield "graph.vox", vox(size(2, 1, 1) + xyzi([(0, 0, 0, 1), (1, 0, 0, 1)]) + size(1, 1, 1) + xyzi([(0, 0, 0, 2)]) +
                           ntrn(0, 1) + ngrp(1, [2, 4]) + ntrn(2, 3, ({"_r": "1", "_t": "0 0 0"},)) + nshp(3, [0]) +
                           ntrn(4, 5, ({"_t": "5 0 2"},)) + nshp(5, [1]))
    yield "shared_skipped.vox", vox(
        chunk("PACK", i32(1)) + size(1, 2, 1) + xyzi([(0, 0, 0, 3), (0, 1, 0, 4)]) + ntrn(0, 1) + ngrp(1, [2, 4, 6]) +
        ntrn(2, 3, ({"_t": "-3 1 0"},), [("_name", "a")]) + nshp(3, [0]) + ntrn(4, 3, ({"_t": "2 0 -1", "_r": "40"},)) +
        ntrn(6, 7) + ngrp(7, [8]) + ntrn(8, 3, ({"_r": "98"},)) + chunk("LAYR", i32(0) + dct([("_name", "l")]) + i32(-1)) +
        chunk("rOBJ", dct([("_type", "_bg")])) + chunk("NOTE", i32(0)) + chunk("ZZZZ", b"x", chunk("YYYY", b"nested")))
    yield "v200_frames.vox", vox(size(4, 4, 1) + xyzi([(x, x, 0, 10 + x) for x in range(4)]) +
                                 ntrn(0, 1, ({"_t": "1 2 3"}, {"_t": "9 9 9", "_f": "1"}), [("_hidden", "0")]) +
                                 nshp(1, [0]), version=200)
    # Hostile shapes (refused by the loader, kept as seeds so mutations explore around the limits): a scene graph
    # 70 nodes deep, and 26 groups each listing their child twice (2^26 paths in a 2 KB file).
    cube = size(1, 1, 1) + xyzi([(0, 0, 0, 1)])
    yield "hostile_deep.vox", vox(cube + b"".join(ntrn(i, i + 1, ({"_t": "1 0 0"},)) if i % 2 == 0 else ngrp(i, [i + 1])
                                                  for i in range(69)) + nshp(69, [0]))
    yield "hostile_doubling.vox", vox(cube + b"".join(ntrn(2 * l, 2 * l + 1) + ngrp(2 * l + 1, [2 * l + 2] * 2)
                                                      for l in range(26)) + ntrn(52, 53) + nshp(53, [0]))


if __name__ == "__main__":
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "vox")
    os.makedirs(out, exist_ok=True)
    for name, data in seeds():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)
        print(name, len(data))

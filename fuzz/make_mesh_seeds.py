#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_mesh (fuzz/corpus/mesh/*): small valid OBJ, PLY (ASCII, binary little and big
endian) and glTF / GLB files covering what the loader reads (polygons, vertex colours, normals, materials, node
transforms, index types), each behind fuzz_mesh's first byte (0 OBJ, 1 PLY, 2 glTF, 3 GLB). Run from the repo root:
/usr/bin/python3 fuzz/make_mesh_seeds.py"""
import base64
import json
import os
import struct

OUT = os.path.join("fuzz", "corpus", "mesh")


def put(name, fmt, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(bytes([fmt]) + data)


CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_F = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (4, 8, 7, 3), (1, 5, 8, 4), (2, 3, 7, 6)]


def obj_seeds():
    v = "".join("v %g %g %g\n" % p for p in CUBE_V)
    put("cube_quads.obj", 0, "# cube\nmtllib cube.mtl\n" + v + "usemtl red\n" +
        "".join("f %d %d %d %d\n" % f for f in CUBE_F[:3]) + "usemtl glow\n" +
        "".join("f %d %d %d %d\n" % f for f in CUBE_F[3:]))
    put("normals_uv.obj", 0, v + "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 -1\nvn 0 0 1\n"
        "f 1/1/1 4/2/1 3/3/1\nf -8//2 -7//2 -6//2\ng side\no thing\ns 1\nf 1/1 2/2 6/3 5/1\n")
    put("colours.obj", 0, "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0 1 1 1\nf 1 2 3\nf 2 4 3\nl 1 4\np 2\n")


def ply_header(fmt, nv, nf, extra=""):
    return ("ply\nformat %s 1.0\ncomment seed\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\n%selement face %d\nproperty list uchar int vertex_indices\nend_header\n"
            % (fmt, nv, extra, nf))


def ply_seeds():
    cols = "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    body = "".join("%g %g %g %d %d %d\n" % (p + (30 * i, 255 - 30 * i, 128)) for i, p in enumerate(CUBE_V))
    body += "".join("4 %d %d %d %d\n" % tuple(i - 1 for i in f) for f in CUBE_F)
    put("cube_colours.ply", 1, ply_header("ascii", 8, 6, cols) + body)
    for order, fmt in (("<", "binary_little_endian"), (">", "binary_big_endian")):
        b = ply_header(fmt, 8, 6, "property float nx\nproperty float ny\nproperty float nz\n").encode()
        for p in CUBE_V:
            n = tuple(2 * c - 1 for c in p)
            b += struct.pack(order + "6f", *(p + n))
        for f in CUBE_F:
            b += struct.pack(order + "B4i", 4, *(i - 1 for i in f))
        put("cube_%s.ply" % fmt, 1, b)
    # a tristrips element, uint list counts, short indices
    b = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
         "property double z\nelement tristrips 1\nproperty list uint short vertex_indices\nend_header\n").encode()
    for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]:
        b += struct.pack("<3d", *p)
    b += struct.pack("<I4h", 4, 0, 1, 2, 3)
    put("strip.ply", 1, b)


def gltf_doc(glb, index_type=5123):
    pos = b"".join(struct.pack("<3f", *p) for p in CUBE_V)
    col = b"".join(struct.pack("<4B", 30 * i, 255 - 30 * i, 128, 255) for i in range(8))
    tris = [t for f in CUBE_F for t in ((f[0], f[1], f[2]), (f[0], f[2], f[3]))]
    fmt = {5121: "B", 5123: "H", 5125: "I"}[index_type]
    idx = b"".join(struct.pack("<" + fmt, i - 1) for t in tris for i in t)
    while len(idx) % 4:
        idx += b"\0"
    binary = pos + col + idx
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1, 2], "rotation": [0, 0.7071068, 0, 0.7071068]},
                  {"mesh": 0, "translation": [2, 0, 0]},
                  {"mesh": 0, "matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.4, 0.2, 1]},
                       "emissiveFactor": [0.5, 0.5, 0],
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}}],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 128, "byteLength": len(idx)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5121, "normalized": True, "count": 8, "type": "VEC4"},
                      {"bufferView": 2, "componentType": index_type, "count": 36, "type": "SCALAR"}],
    }
    if not glb:
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
    return doc, binary


def glb(doc, binary):
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def gltf_seeds():
    for t in (5121, 5123, 5125):
        doc, binary = gltf_doc(False, t)
        put("cube_%d.gltf" % t, 2, json.dumps(doc))
    put("cube.glb", 3, glb(*gltf_doc(True)))
    # no indices, a primitive without material, strips
    doc, binary = gltf_doc(False)
    doc["meshes"][0]["primitives"] = [{"attributes": {"POSITION": 0}, "mode": 5}]
    put("strip.gltf", 2, json.dumps(doc))


def reader_seeds():
    """Issue 49: what the three readers read beyond the cube seeds -- polygons of 5+ corners (ear clipping), groups,
    points and lines, homogeneous vertices; a PLY with texture coordinates, an element it skips and double positions;
    a glTF with a sparse accessor, TEXCOORD_0, a fan, two primitives and nested nodes."""
    put("polygons_groups.obj", 0, "o a\ng g1\nv 0 0 0\nv 4 0 0\nv 4 3 0\nv 2 1 0 1\nv 0 3 0\nv -1 1.5 0\n"
        "vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1 5/1/1 6/1/1\ng g2\ns off\nf -6 -5 -4 -3 -2\nl 1 2 3\np 4\nf 2 3\n")
    b = ("ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
         "property float u\nproperty float v\nproperty ushort red\nproperty ushort green\nproperty ushort blue\n"
         "element face 2\nproperty list uchar uint vertex_index\nproperty uchar flags\nelement edge 1\n"
         "property int vertex1\nproperty int vertex2\nend_header\n")
    for i, p in enumerate([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1)]):
        b += "%g %g %g %g %g %d %d %d\n" % (p + (p[0], p[1], 9000 * i, 65535 - 9000 * i, 30000))
    b += "4 0 1 2 3 7\n3 0 1 4 0\n0 1\n"
    put("uv_edges.ply", 1, b)
    pos = b"".join(struct.pack("<3f", *p) for p in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1)])
    uv = b"".join(struct.pack("<2f", p[0], p[1]) for p in [(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.5)])
    sidx = struct.pack("<2H", 1, 4)
    sval = struct.pack("<6f", 2, 0, 0, 0.5, 0.5, 2)
    binary = pos + uv + sidx + sval
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [1, 2, 3], "scale": [2, 2, 2]},
                  {"mesh": 0, "rotation": [0, 0, 0.3826834, 0.9238795]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "mode": 6, "material": 0},
                                   {"attributes": {"POSITION": 2}, "mode": 5}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.6, 0.9, 1]}}],
        "buffers": [{"byteLength": len(binary),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(binary).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 60}, {"buffer": 0, "byteOffset": 60, "byteLength": 40},
                        {"buffer": 0, "byteOffset": 100, "byteLength": 4}, {"buffer": 0, "byteOffset": 104, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC2"},
                      {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3",
                       "sparse": {"count": 2, "indices": {"bufferView": 2, "componentType": 5123},
                                  "values": {"bufferView": 3}}}],
    }
    put("fan_sparse_nodes.gltf", 2, json.dumps(doc))


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    obj_seeds()
    ply_seeds()
    gltf_seeds()
    reader_seeds()

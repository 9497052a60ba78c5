#!/usr/bin/python3
"""Writes an uncompressed float32 OpenEXR file filled with one value (for the CLI tests' hostile frames).

Standard library only: the sanitizer builds have no native ngi module to write EXRs with.
Usage: write_exr.py OUT WIDTH HEIGHT CHANNELS VALUE [FIRST]
  CHANNELS  comma-separated names, e.g. R,G,B or Y;  VALUE: a float ("nan", "inf" allowed);
  FIRST     a different value for the first pixel of every channel (e.g. one negative depth).
"""
import struct
import sys


def attribute(name, kind, data):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data


def main():
    out, width, height, channels, value = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], float(sys.argv[5])
    first = float(sys.argv[6]) if len(sys.argv) > 6 else value
    names = sorted(channels.split(","))  # EXR stores channels in alphabetical order
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for n in names) + b"\0"  # 2 = FLOAT
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (attribute("channels", "chlist", chlist) + attribute("compression", "compression", b"\0") +
              attribute("dataWindow", "box2i", box) + attribute("displayWindow", "box2i", box) +
              attribute("lineOrder", "lineOrder", b"\0") + attribute("pixelAspectRatio", "float", struct.pack("<f", 1)) +
              attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0)) +
              attribute("screenWindowWidth", "float", struct.pack("<f", 1)) + b"\0")
    start = 8 + len(header) + 8 * height
    line_bytes = 4 * width * len(names)
    blocks, offsets = b"", b""
    for y in range(height):
        offsets += struct.pack("<Q", start + len(blocks))
        row = b""
        for _ in names:
            row += struct.pack("<f", first if y == 0 else value) + struct.pack("<f", value) * (width - 1)
        blocks += struct.pack("<ii", y, line_bytes) + row
    with open(out, "wb") as f:
        f.write(struct.pack("<ii", 20000630, 2) + header + offsets + blocks)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes scenes/sky.exr, the sample scene's environment map (scenes/sky.toml): a 64 x 32
equirectangular map (chambre's convention, docs/lights.md: row 0 is the +y pole, u = 0 is +x,
u grows towards -z) of a blue sky brightening towards the horizon, a brown ground below it, and
a bright sun-like spot of 2 x 2 texels 35 degrees above the horizon. An uncompressed scanline
OpenEXR file of 32-bit float R, G, B, written with the standard library alone.

    python3 tools/make_sky_map.py scenes/sky.exr
"""

import math
import struct
import sys

WIDTH, HEIGHT = 64, 32


def radiance(column, row):
    """Linear RGB radiance of texel (column, row)."""
    if row in (9, 10) and column in (9, 10):
        return (320.0, 300.0, 260.0)
    theta = math.pi * (row + 0.5) / HEIGHT
    elevation = math.pi / 2 - theta
    if elevation < 0:
        return (0.12, 0.09, 0.06)
    # Brighter and whiter towards the horizon.
    haze = math.exp(-4.0 * elevation)
    return (0.25 + 0.6 * haze, 0.45 + 0.5 * haze, 0.9 + 0.2 * haze)


def attribute(name, kind, data):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data


def exr(width, height, pixel):
    channels = b"".join(
        name.encode() + b"\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1) for name in "BGR"
    ) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = b"".join([
        attribute("channels", "chlist", channels),
        attribute("compression", "compression", b"\0"),
        attribute("dataWindow", "box2i", box),
        attribute("displayWindow", "box2i", box),
        attribute("lineOrder", "lineOrder", b"\0"),
        attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
        attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
    ]) + b"\0"
    start = 8 + len(header) + 8 * height
    line_bytes = 3 * 4 * width
    offsets = b"".join(struct.pack("<Q", start + y * (8 + line_bytes)) for y in range(height))
    lines = b""
    for y in range(height):
        texels = [pixel(x, y) for x in range(width)]
        data = b"".join(struct.pack("<f", t[c]) for c in (2, 1, 0) for t in texels)
        lines += struct.pack("<ii", y, len(data)) + data
    return struct.pack("<ii", 20000630, 2) + header + offsets + lines


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/sky.exr"
    with open(out, "wb") as f:
        f.write(exr(WIDTH, HEIGHT, radiance))

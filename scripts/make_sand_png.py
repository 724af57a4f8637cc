#!/usr/bin/env python3
"""Writes scenes/assets/sand_height.png, the sand floor of scenes/sand.json (Mercier 2013, Fig. 7,
"buried in sand"): a slope rising towards +y plus small wind ripples, as a 16-bit greyscale PNG
(value 0..1; the scene scales it by `amplitude`). Run with /usr/bin/python3 (needs numpy only; the PNG
is encoded with zlib so that no imaging module is required). Deterministic.

Image row 0 is the +y edge of the height field (north up, as harness/scene/heightfield/heightfield_image.cpp reads it).
"""
import os
import struct
import sys
import zlib

try:
    import numpy as np
except ImportError:
    sys.exit("make_sand_png.py needs numpy (Debian: python3-numpy; run with /usr/bin/python3)")

SIZE = 512


def height_map(size=SIZE):
    # Normalised coordinates over the field's rectangle: u = x in [0, 1], v = y in [0, 1] (v = 1 at row 0).
    u = np.linspace(0.0, 1.0, size)[None, :]
    v = np.linspace(1.0, 0.0, size)[:, None]
    slope = 0.05 + 0.85 * v                       # rises towards +y: shallow sand at the top of the slope
    slope = slope + 0.04 * np.sin(np.pi * u) * v  # a gentle shoulder across the slope
    # Ripples: two crossing trains, a few millimetres once scaled by the scene's amplitude (0.6 m).
    ripples = 0.006 * np.sin(2 * np.pi * (9.0 * u + 2.0 * v)) + 0.004 * np.sin(2 * np.pi * (4.0 * u - 11.0 * v) + 1.3)
    h = slope + ripples
    return np.clip(h, 0.0, 1.0)


def write_png16(path, img):
    data = np.round(img * 65535.0).astype(">u2")
    raw = b"".join(b"\x00" + row.tobytes() for row in data)
    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)
    header = struct.pack(">IIBBBBB", img.shape[1], img.shape[0], 16, 0, 0, 0, 0)  # 16-bit greyscale
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "scenes", "assets", "sand_height.png")
    write_png16(out, height_map())
    print("wrote", out)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Makes rust.mat's textures, deterministically (no randomness, no
dependencies): `rust_mask.png`, a grey 8-bit mask of rust patches (1: rust),
and `rust_normal.png`, an RGB 8-bit tangent-space normal map of the pits
the patches leave (the mask as a height field). Run from anywhere:
`python3 scenes/materials/textures/make.py`."""

import math
import os
import struct
import zlib

SIZE = 256
HERE = os.path.dirname(os.path.abspath(__file__))


def lattice(x, y, period):
    """A value in [0, 1) per lattice point, tiling with `period`."""
    h = ((x % period) * 374761393 + (y % period) * 668265263) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    return (h ^ (h >> 16)) / 2**32


def noise(u, v, period):
    """Smooth value noise at (u, v) in lattice units, tiling."""
    x0, y0 = math.floor(u), math.floor(v)
    fx, fy = u - x0, v - y0
    sx, sy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    a = lattice(x0, y0, period) + (lattice(x0 + 1, y0, period) - lattice(x0, y0, period)) * sx
    b = lattice(x0, y0 + 1, period) + (lattice(x0 + 1, y0 + 1, period) - lattice(x0, y0 + 1, period)) * sx
    return a + (b - a) * sy


def height(x, y):
    """Rust in [0, 1]: three octaves, sharpened into patches."""
    h = 0.0
    for octave, weight in ((4, 0.55), (8, 0.3), (16, 0.15)):
        h += weight * noise(x * octave / SIZE, y * octave / SIZE, octave)
    return min(max((h - 0.42) * 4.0, 0.0), 1.0)


def png(path, width, height_, channels, rows):
    kind = {1: 0, 3: 2}[channels]
    raw = b"".join(b"\0" + bytes(row) for row in rows)
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    ihdr = struct.pack(">IIBBBBB", width, height_, 8, kind, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    h = [[height(x, y) for x in range(SIZE)] for y in range(SIZE)]
    png(os.path.join(HERE, "rust_mask.png"), SIZE, SIZE, 1, [[round(v * 255) for v in row] for row in h])
    rows = []
    depth = 2.0  # pits' slope, in texels of height per unit of the mask
    for y in range(SIZE):
        row = []
        for x in range(SIZE):
            # Rust is pitted: height falls where the mask rises.
            dx = -(h[y][(x + 1) % SIZE] - h[y][(x - 1) % SIZE]) * depth
            dy = -(h[(y + 1) % SIZE][x] - h[(y - 1) % SIZE][x]) * depth
            n = (-dx, -dy, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            row.extend(round((c / length * 0.5 + 0.5) * 255) for c in n)
        rows.append(row)
    png(os.path.join(HERE, "rust_normal.png"), SIZE, SIZE, 3, rows)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Makes `crate.gltf`, a textured glTF asset with materials of its own,
deterministically (no randomness, no dependencies): a unit box whose four
sides are varnished wood (a base colour texture of planks, a tangent-space
normal map of their grooves, KHR_materials_clearcoat) and whose top and
bottom are felt (KHR_materials_sheen, and KHR_materials_anisotropy, read
as the felt's specular anisotropy). Writes
`crate.gltf`, `crate.bin`, `crate_wood.png` and `crate_wood_normal.png`
beside this script: `python3 scenes/meshes/crate/make_crate.py`."""

import json
import math
import os
import struct
import zlib

SIZE = 256
PLANKS = 4
HERE = os.path.dirname(os.path.abspath(__file__))


def png(path, rows):
    raw = b"".join(b"\0" + bytes(row) for row in rows)
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    ihdr = struct.pack(">IIBBBBB", SIZE, SIZE, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def groove(y):
    """Depth in [0, 1] of the groove between planks at row y (1: deepest)."""
    d = abs((y * PLANKS / SIZE) % 1.0 - 0.5) * 2.0  # 1 at a plank's edge
    return max(0.0, (d - 0.9) / 0.1)


def wood(x, y):
    """sRGB bytes: grain along x, each plank its own shade, dark grooves."""
    plank = int(y * PLANKS / SIZE)
    grain = 0.5 + 0.5 * math.sin(x * 0.15 + 6.0 * math.sin(y * 0.05 + plank) + plank * 1.7)
    shade = (0.85 + 0.15 * grain) * (1.0 - 0.12 * (plank % 2)) * (1.0 - 0.6 * groove(y))
    return [int(round(255 * min(1.0, c * shade))) for c in (0.78, 0.55, 0.32)]


def normal(y):
    """The groove's slope as a tangent-space normal (+y up the image)."""
    slope = (groove(y + 1) - groove(y - 1)) * 2.0
    n = (0.0, slope, 1.0)
    length = math.sqrt(sum(c * c for c in n))
    return [int(round(255 * (c / length * 0.5 + 0.5))) for c in n]


def box():
    """Per face: 4 vertices (position, normal, uv) and 2 triangles; sides
    first (primitive 0), then top and bottom (primitive 1)."""
    faces = [  # normal, u axis, v axis (v down the image)
        ((0, 0, 1), (1, 0, 0), (0, -1, 0)),
        ((1, 0, 0), (0, 0, -1), (0, -1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, -1)),
    ]
    vertices, primitives = [], [[], []]
    for f, (n, u, v) in enumerate(faces):
        base = len(vertices)
        for su, sv in ((0, 0), (1, 0), (1, 1), (0, 1)):
            p = [0.5 * n[k] + (su - 0.5) * u[k] + (sv - 0.5) * v[k] for k in range(3)]
            vertices.append((p, n, (su, sv)))
        primitives[0 if f < 4 else 1] += [base, base + 2, base + 1, base, base + 3, base + 2]
    return vertices, primitives


def main():
    png(os.path.join(HERE, "crate_wood.png"), [sum((wood(x, y) for x in range(SIZE)), []) for y in range(SIZE)])
    png(os.path.join(HERE, "crate_wood_normal.png"), [normal(y) * SIZE for y in range(SIZE)])
    vertices, primitives = box()
    blob = b"".join(struct.pack("<3f", *p) for p, _, _ in vertices)
    blob += b"".join(struct.pack("<3f", *n) for _, n, _ in vertices)
    blob += b"".join(struct.pack("<2f", *uv) for _, _, uv in vertices)
    index_offsets = []
    for prim in primitives:
        index_offsets.append(len(blob))
        blob += struct.pack(f"<{len(prim)}H", *prim)
    n = len(vertices)
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 12 * n},
        {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12 * n},
        {"buffer": 0, "byteOffset": 24 * n, "byteLength": 8 * n},
    ] + [{"buffer": 0, "byteOffset": o, "byteLength": 2 * len(p)} for o, p in zip(index_offsets, primitives)]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3", "min": [-0.5] * 3, "max": [0.5] * 3},
        {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": n, "type": "VEC2"},
    ] + [{"bufferView": 3 + i, "componentType": 5123, "count": len(p), "type": "SCALAR"} for i, p in enumerate(primitives)]
    attributes = {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}
    doc = {
        "asset": {"version": "2.0", "generator": "loupe scenes/meshes/crate/make_crate.py"},
        "extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_sheen", "KHR_materials_anisotropy"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "crate"}],
        "meshes": [{"name": "crate", "primitives": [
            {"attributes": attributes, "indices": 3, "material": 0},
            {"attributes": attributes, "indices": 4, "material": 1},
        ]}],
        "materials": [
            {
                "name": "wood",
                "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 0.6},
                "normalTexture": {"index": 1, "scale": 1.0},
                "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.05}},
            },
            {
                "name": "felt",
                "pbrMetallicRoughness": {"baseColorFactor": [0.08, 0.2, 0.12, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9},
                "extensions": {
                    "KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.8, 0.6], "sheenRoughnessFactor": 0.4},
                    "KHR_materials_anisotropy": {"anisotropyStrength": 0.5},
                },
            },
        ],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": "crate_wood.png"}, {"uri": "crate_wood_normal.png"}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "crate.bin", "byteLength": len(blob)}],
    }
    with open(os.path.join(HERE, "crate.bin"), "wb") as f:
        f.write(blob)
    with open(os.path.join(HERE, "crate.gltf"), "w") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")


main()

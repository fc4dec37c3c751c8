#!/usr/bin/env python3
"""Writes the project's own test scenes as glTF 2.0 files into scenes/test/.

Scenes nobody tuned the renderer for, with what breaks many-lights methods: closed rooms
joined by openings, thin occluders (a wall with a doorway, columns, a slab near the floor),
many small objects. Units are metres, +y up; every surface is a flat-shaded Lambertian
cuboid face, so that walls have two sides and a thickness as in real buildings. Cameras and
lights are in the matching scene files (scenes/test/*.toml).

    python3 scripts/make_test_scenes.py
"""

import base64
import json
import os
import random
import struct

OUT = os.path.join(os.path.dirname(__file__), "..", "scenes", "test")


class Builder:
    """Collects flat-shaded triangles per material."""

    def __init__(self):
        self.materials = []  # (name, rgb)
        self.tris = {}  # material index -> list of (positions, normal)

    def material(self, name, rgb):
        self.materials.append((name, rgb))
        self.tris[len(self.materials) - 1] = []
        return len(self.materials) - 1

    def quad(self, m, a, b, c, d):
        """A quad a b c d, counter-clockwise seen from its front."""
        n = normal(a, b, c)
        self.tris[m].append(((a, b, c), n))
        self.tris[m].append(((a, c, d), n))

    def box(self, m, lo, hi):
        """An axis-aligned cuboid with outward faces."""
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        p = lambda x, y, z: (x, y, z)
        self.quad(m, p(x0, y0, z0), p(x1, y0, z0), p(x1, y0, z1), p(x0, y0, z1))  # -y
        self.quad(m, p(x0, y1, z0), p(x0, y1, z1), p(x1, y1, z1), p(x1, y1, z0))  # +y
        self.quad(m, p(x0, y0, z0), p(x0, y0, z1), p(x0, y1, z1), p(x0, y1, z0))  # -x
        self.quad(m, p(x1, y0, z0), p(x1, y1, z0), p(x1, y1, z1), p(x1, y0, z1))  # +x
        self.quad(m, p(x0, y0, z0), p(x0, y1, z0), p(x1, y1, z0), p(x1, y0, z0))  # -z
        self.quad(m, p(x0, y0, z1), p(x1, y0, z1), p(x1, y1, z1), p(x0, y1, z1))  # +z

    def write(self, path):
        blob = bytearray()
        views, accessors, primitives = [], [], []
        for m, tris in self.tris.items():
            if not tris:
                continue
            pos, nor = [], []
            for (a, b, c), n in tris:
                for v in (a, b, c):
                    pos.append(v)
                    nor.append(n)
            for data, kind in ((pos, "POSITION"), (nor, "NORMAL")):
                start = len(blob)
                for v in data:
                    blob += struct.pack("<3f", *v)
                views.append({"buffer": 0, "byteOffset": start, "byteLength": len(blob) - start})
                acc = {
                    "bufferView": len(views) - 1,
                    "componentType": 5126,
                    "count": len(data),
                    "type": "VEC3",
                }
                if kind == "POSITION":
                    acc["min"] = [min(v[i] for v in data) for i in range(3)]
                    acc["max"] = [max(v[i] for v in data) for i in range(3)]
                accessors.append(acc)
            primitives.append(
                {
                    "attributes": {"POSITION": len(accessors) - 2, "NORMAL": len(accessors) - 1},
                    "material": m,
                }
            )
        gltf = {
            "asset": {"version": "2.0", "generator": "lgh scripts/make_test_scenes.py"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "name": "scene"}],
            "meshes": [{"primitives": primitives}],
            "materials": [
                {
                    "name": name,
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [*rgb, 1.0],
                        "metallicFactor": 0.0,
                        "roughnessFactor": 1.0,
                    },
                }
                for name, rgb in self.materials
            ],
            "buffers": [
                {
                    "byteLength": len(blob),
                    "uri": "data:application/octet-stream;base64,"
                    + base64.b64encode(bytes(blob)).decode(),
                }
            ],
            "bufferViews": views,
            "accessors": accessors,
        }
        with open(path, "w") as f:
            json.dump(gltf, f, indent=1)
            f.write("\n")


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = sum(x * x for x in n) ** 0.5
    return tuple(x / length for x in n)


def shell(b, m, lo, hi, t):
    """Floor, ceiling and four walls of thickness t around the inside box lo..hi."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    b.box(m, (x0 - t, y0 - t, z0 - t), (x1 + t, y0, z1 + t))  # floor
    b.box(m, (x0 - t, y1, z0 - t), (x1 + t, y1 + t, z1 + t))  # ceiling
    b.box(m, (x0 - t, y0, z0 - t), (x0, y1, z1 + t))  # -x wall
    b.box(m, (x1, y0, z0 - t), (x1 + t, y1, z1 + t))  # +x wall
    b.box(m, (x0, y0, z0 - t), (x1, y1, z0))  # -z wall
    b.box(m, (x0, y0, z1), (x1, y1, z1 + t))  # +z wall


def two_rooms():
    """Two 4 x 3 x 4 m rooms side by side along x, joined by a 1 x 2.1 m doorway in a 0.1 m
    dividing wall; boxes in both rooms. Room A (x < 0) holds the light; the camera is in
    room B, which only the doorway lights."""
    b = Builder()
    plaster = b.material("plaster", (0.75, 0.73, 0.7))
    wall = b.material("dividing wall", (0.7, 0.7, 0.72))
    red = b.material("red", (0.7, 0.15, 0.12))
    blue = b.material("blue", (0.15, 0.25, 0.65))
    shell(b, plaster, (-4.0, 0.0, -2.0), (4.0, 3.0, 2.0), 0.2)
    # The dividing wall at x in [-0.05, 0.05] with a doorway at z in [-0.5, 0.5], y < 2.1.
    b.box(wall, (-0.05, 0.0, -2.0), (0.05, 3.0, -0.5))
    b.box(wall, (-0.05, 0.0, 0.5), (0.05, 3.0, 2.0))
    b.box(wall, (-0.05, 2.1, -0.5), (0.05, 3.0, 0.5))
    b.box(red, (-3.0, 0.0, -1.5), (-2.2, 0.8, -0.7))
    b.box(blue, (1.2, 0.0, 0.6), (2.0, 0.6, 1.4))
    b.box(red, (2.6, 0.0, -1.6), (3.4, 1.4, -0.8))
    b.write(os.path.join(OUT, "two-rooms.gltf"))


def colonnade():
    """A 12 x 4 x 6 m hall with a row of eight 0.3 m columns, a 0.05 m slab 0.15 m above
    the floor (a low table), and an opening in the roof that a sun shines through."""
    b = Builder()
    stone = b.material("stone", (0.7, 0.66, 0.6))
    column = b.material("column", (0.8, 0.78, 0.74))
    slab = b.material("slab", (0.55, 0.35, 0.2))
    green = b.material("green", (0.2, 0.5, 0.25))
    x0, x1, z0, z1, h, t = -6.0, 6.0, -3.0, 3.0, 4.0, 0.25
    b.box(stone, (x0 - t, -t, z0 - t), (x1 + t, 0.0, z1 + t))  # floor
    for lo, hi in [((x0, 0, z0 - t), (x1, h, z0)), ((x0, 0, z1), (x1, h, z1 + t)),
                   ((x0 - t, 0, z0 - t), (x0, h, z1 + t)), ((x1, 0, z0 - t), (x1 + t, h, z1 + t))]:
        b.box(stone, lo, hi)
    # Roof with an opening at x in [-4, 4], z in [1, 2.2].
    b.box(stone, (x0 - t, h, z0 - t), (x1 + t, h + t, 1.0))
    b.box(stone, (x0 - t, h, 2.2), (x1 + t, h + t, z1 + t))
    b.box(stone, (x0 - t, h, 1.0), (-4.0, h + t, 2.2))
    b.box(stone, (4.0, h, 1.0), (x1 + t, h + t, 2.2))
    for k in range(8):
        cx = -5.25 + 1.5 * k
        b.box(column, (cx - 0.15, 0.0, 0.45), (cx + 0.15, h, 0.75))
    b.box(slab, (-2.0, 0.15, -2.0), (1.0, 0.2, -0.8))
    b.box(green, (3.0, 0.0, -2.4), (3.6, 1.2, -1.8))
    b.write(os.path.join(OUT, "colonnade.gltf"))


def clutter():
    """A closed 6 x 3 x 6 m room with 60 small boxes (0.1-0.5 m) on the floor and on two
    shelves, lit by two point lights under the ceiling: many small occluders and contacts."""
    b = Builder()
    plaster = b.material("plaster", (0.72, 0.72, 0.72))
    colours = [b.material(f"box {i}", c) for i, c in enumerate(
        [(0.7, 0.2, 0.2), (0.2, 0.6, 0.2), (0.2, 0.3, 0.7), (0.7, 0.6, 0.2), (0.6, 0.6, 0.6)])]
    shelf = b.material("shelf", (0.5, 0.35, 0.25))
    shell(b, plaster, (-3.0, 0.0, -3.0), (3.0, 3.0, 3.0), 0.2)
    b.box(shelf, (-3.0, 1.0, -3.0), (-2.4, 1.04, 1.0))
    b.box(shelf, (-3.0, 1.8, -3.0), (-2.4, 1.84, 1.0))
    rng = random.Random(7)
    for i in range(60):
        s = rng.uniform(0.1, 0.5)
        hgt = rng.uniform(0.1, 0.6)
        if i < 16:  # on the shelves
            y = 1.04 if i % 2 == 0 else 1.84
            s = min(s, 0.35)
            x = rng.uniform(-2.95, -2.45 - s)
            z = rng.uniform(-2.9, 0.9 - s)
            hgt = min(hgt, 0.5)
        else:
            y = 0.0
            x = rng.uniform(-2.2, 2.8 - s)
            z = rng.uniform(-2.8, 2.8 - s)
        b.box(colours[i % len(colours)], (x, y, z), (x + s, y + hgt, z + s))
    b.write(os.path.join(OUT, "clutter.gltf"))


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    two_rooms()
    colonnade()
    clutter()

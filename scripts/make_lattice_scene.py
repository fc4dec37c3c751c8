#!/usr/bin/env python3
"""Writes scenes/test/lattice.{obj,mtl,png} (and lattice.toml points at them): a test of
alpha cut-outs in the Wavefront format as exporters write them.

A room of floor, back wall and left wall (metres, +y up) with a lattice screen held level
at 1.2 m between a point light and the floor: one quad whose `map_d` (an RGBA PNG, the same
file as its `map_Kd`) cuts square holes, so that the light falls through the holes onto
the floor in a pattern of squares, and bounces. A standing screen with a second pattern
(`-s 2 2` on its map_d alone) stands beside it. The holes exist only in the texture: a
renderer that ignores map_d shows solid grey slabs and a dark floor. The back wall's
vertex colours (`v x y z r g b`, sRGB; white elsewhere) shade it from warm at the floor to
cool at the top.

    python3 scripts/make_lattice_scene.py
"""

import os
import struct
import zlib

OUT = os.path.join(os.path.dirname(__file__), "..", "scenes", "test")


def png(path, width, height, rgba):
    """Writes 8-bit RGBA pixels (rows top first) as a PNG file."""

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    raw = b"".join(
        b"\x00" + bytes(rgba[y * width * 4 : (y + 1) * width * 4]) for y in range(height)
    )
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def lattice(n=16, bar=4):
    """An n x n tile: opaque wooden bars `bar` texels wide along two edges, holes
    elsewhere (alpha 0), so that tiles repeat into a grid of square holes."""
    px = []
    for y in range(n):
        for x in range(n):
            solid = x < bar or y < bar
            px += [150, 110, 70, 255 if solid else 0]
    return px


def main():
    png(os.path.join(OUT, "lattice.png"), 16, 16, lattice())
    v, vt, faces = [], [], []
    white = (1, 1, 1)

    def quad(material, corners, uvs, colors=(white,) * 4):
        base = len(v)
        v.extend(c + col for c, col in zip(corners, colors))
        vt.extend(uvs)
        ids = [base + k + 1 for k in range(4)]
        faces.append((material, [(ids[0], ids[1], ids[2]), (ids[0], ids[2], ids[3])]))

    flat = [(0, 0), (1, 0), (1, 1), (0, 1)]
    # Floor (facing up), back wall (facing +z), left wall (facing +x).
    quad("floor", [(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)], flat)
    warm, cool = (1, 0.55, 0.45), (0.5, 0.7, 1)
    back = [(-3, 0, -3), (3, 0, -3), (3, 3, -3), (-3, 3, -3)]
    quad("wall", back, flat, (warm, warm, cool, cool))
    quad("wall", [(-3, 0, -3), (-3, 3, -3), (-3, 3, 3), (-3, 0, 3)], flat)
    # The level screen at y = 1.2, both sides (two quads back to back), texture repeated
    # 4 x 4 times across its 2 m.
    level = [(-1.5, 1.2, -1), (0.5, 1.2, -1), (0.5, 1.2, 1), (-1.5, 1.2, 1)]
    tiled = [(0, 0), (4, 0), (4, 4), (0, 4)]
    quad("screen", level[::-1], tiled[::-1])
    quad("screen", level, tiled)
    # The standing screen at x = 1.5, facing -x, 1.6 m square.
    standing = [(1.5, 0, 1.2), (1.5, 1.6, 1.2), (1.5, 1.6, -0.4), (1.5, 0, -0.4)]
    quad("standing", standing, tiled)
    with open(os.path.join(OUT, "lattice.mtl"), "w") as f:
        f.write("# Written by scripts/make_lattice_scene.py.\n")
        f.write("newmtl floor\nKd 0.7 0.7 0.7\n\nnewmtl wall\nKd 0.6 0.62 0.7\n\n")
        f.write("newmtl screen\nKd 1 1 1\nmap_Kd lattice.png\nmap_d lattice.png\n\n")
        f.write("newmtl standing\nKd 1 1 1\nmap_Kd lattice.png\nmap_d -s 2 2 lattice.png\n")
    with open(os.path.join(OUT, "lattice.obj"), "w") as f:
        f.write("# Written by scripts/make_lattice_scene.py.\nmtllib lattice.mtl\n")
        for p in v:
            f.write("v %g %g %g %g %g %g\n" % p)
        for t in vt:
            f.write("vt %g %g\n" % t)
        for material, tris in faces:
            f.write("usemtl %s\n" % material)
            for tri in tris:
                f.write("f %s\n" % " ".join("%d/%d" % (i, i) for i in tri))


if __name__ == "__main__":
    main()

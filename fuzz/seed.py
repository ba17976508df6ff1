#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets into fuzz/corpus/<target>/ (gitignored).

Seeds: every hostile file of tests/data/bad/ (by extension; files without a known extension
go to every reader) and a few small valid meshes (tetrahedron, octahedron with a quad,
3×3 grid) in every variant each reader knows: OBJ (plain, v/vt/vn, negative indices),
ASCII and binary PLY (both endians), OFF, ASCII and binary STL. The pipeline target gets
every seed prefixed with its format byte (0 OBJ, 1 PLY, 2 OFF, 3 STL; +4 = triangulate).

Run from anywhere: `python3 fuzz/seed.py`. Output is deterministic.
"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
BAD = os.path.join(HERE, "..", "tests", "data", "bad")
CORPUS = os.path.join(HERE, "corpus")
FORMATS = ["obj", "ply", "off", "stl"]

TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
# Octahedron with its top four triangles and the bottom as a quad-free pair plus one quad
# (0 1 2 3 is the equator): polygons exercise triangulation.
OCT_V = [(1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCT_F = [(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4), (1, 0, 5), (2, 1, 5), (3, 2, 5), (0, 3, 5)]
PYR_F = [(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4), (3, 2, 1, 0)]
GRID_V = [(x * 0.5, y * 0.5, 0.1 * x * y) for y in range(3) for x in range(3)]
GRID_F = []
for y in range(2):
    for x in range(2):
        a = y * 3 + x
        GRID_F += [(a, a + 1, a + 4), (a, a + 4, a + 3)]
MESHES = {"tet": (TET_V, TET_F), "oct": (OCT_V, OCT_F), "pyr": (OCT_V[:5], PYR_F), "grid": (GRID_V, GRID_F)}


def obj(v, f, style=""):
    s = "# seed\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    if style == "vtvn":
        s += "vt 0 0\nvn 0 0 1\n"
        return s + "".join("f " + " ".join(f"{i + 1}/1/1" for i in face) + "\n" for face in f)
    if style == "neg":
        n = len(v)
        return s + "".join("f " + " ".join(str(i - n) for i in face) + "\n" for face in f)
    return s + "".join("f " + " ".join(str(i + 1) for i in face) + "\n" for face in f)


def off(v, f):
    s = f"OFF\n{len(v)} {len(f)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in v)
    return s + "".join(f"{len(face)} " + " ".join(str(i) for i in face) + "\n" for face in f)


def ply_header(fmt, v, f):
    return (f"ply\nformat {fmt} 1.0\ncomment seed\n"
            f"element vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")


def ply_ascii(v, f):
    s = ply_header("ascii", v, f) + "".join(f"{x} {y} {z}\n" for x, y, z in v)
    return s + "".join(f"{len(face)} " + " ".join(str(i) for i in face) + "\n" for face in f)


def ply_binary(v, f, endian):
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    b = ply_header(fmt, v, f).encode()
    b += b"".join(struct.pack(endian + "3f", *p) for p in v)
    b += b"".join(struct.pack("B", len(face)) + struct.pack(f"{endian}{len(face)}i", *face) for face in f)
    return b


def triangles(v, f):
    out = []
    for face in f:
        for k in range(1, len(face) - 1):
            out.append([v[face[0]], v[face[k]], v[face[k + 1]]])
    return out


def stl_ascii(v, f):
    s = "solid seed\n"
    for t in triangles(v, f):
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join(f"   vertex {x} {y} {z}\n" for x, y, z in t)
        s += "  endloop\n endfacet\n"
    return s + "endsolid seed\n"


def stl_binary(v, f):
    tris = triangles(v, f)
    b = b"seed".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0"
    return b


def put(target, name, data):
    if isinstance(data, str):
        data = data.encode()
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as fh:
        fh.write(data)


seeds = {fmt: [] for fmt in FORMATS}
for name in sorted(os.listdir(BAD)):
    if name.endswith(".py"):
        continue
    with open(os.path.join(BAD, name), "rb") as fh:
        data = fh.read()
    ext = name.rsplit(".", 1)[-1].lower() if "." in name else ""
    for fmt in [ext] if ext in FORMATS else FORMATS:
        seeds[fmt].append((f"bad_{name}", data))
for mname, (v, f) in MESHES.items():
    seeds["obj"] += [(f"{mname}.obj", obj(v, f)), (f"{mname}_vtvn.obj", obj(v, f, "vtvn")),
                     (f"{mname}_neg.obj", obj(v, f, "neg"))]
    seeds["off"].append((f"{mname}.off", off(v, f)))
    seeds["ply"] += [(f"{mname}_ascii.ply", ply_ascii(v, f)), (f"{mname}_le.ply", ply_binary(v, f, "<")),
                     (f"{mname}_be.ply", ply_binary(v, f, ">"))]
    seeds["stl"] += [(f"{mname}_ascii.stl", stl_ascii(v, f)), (f"{mname}_binary.stl", stl_binary(v, f))]
for k, fmt in enumerate(FORMATS):
    for name, data in seeds[fmt]:
        put(fmt, name, data)
        raw = data.encode() if isinstance(data, str) else data
        put("pipeline", f"{fmt}_{name}", bytes([k]) + raw)
        put("pipeline", f"{fmt}_tri_{name}", bytes([k + 4]) + raw)
print({fmt: len(s) for fmt, s in seeds.items()})

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

# The volume readers (issue #39): a cube of six tetrahedra in every dialect the readers take,
# and the first 4 KB of the small shared volume files when ../../shared/data/volumes exists.
CUBE_V = [(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]
CUBE_T = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]


def medit(version):
    lines = [f"MeshVersionFormatted {version}", "Dimension 3", "Vertices", str(len(CUBE_V))]
    lines += [f"{x} {y} {z} 0" for x, y, z in CUBE_V]
    lines += ["Triangles", "1", "1 2 4 0", "Tetrahedra", str(len(CUBE_T))]
    lines += [" ".join(str(i + 1) for i in t) + " 1" for t in CUBE_T]
    return "\n".join(lines + ["End", ""])


def gmsh22(binary=False):
    head = f"$MeshFormat\n2.2 {1 if binary else 0} 8\n"
    if binary:
        head += struct.pack("<i", 1).decode("latin-1") + "\n"
    head += "$EndMeshFormat\n$Nodes\n" + str(len(CUBE_V)) + "\n"
    if binary:
        body = b"".join(struct.pack("<i3d", i + 1, *p) for i, p in enumerate(CUBE_V))
        elems = struct.pack("<3i", 4, len(CUBE_T), 2) + b"".join(
            struct.pack("<7i", k + 1, 1, 1, *(i + 1 for i in t)) for k, t in enumerate(CUBE_T))
        return (head.encode("latin-1") + body + b"\n$EndNodes\n$Elements\n" + str(len(CUBE_T)).encode()
                + b"\n" + elems + b"\n$EndElements\n")
    nodes = "".join(f"{i + 1} {x} {y} {z}\n" for i, (x, y, z) in enumerate(CUBE_V))
    elems = "".join(f"{k + 1} 4 2 1 1 " + " ".join(str(i + 1) for i in t) + "\n" for k, t in enumerate(CUBE_T))
    return head + nodes + f"$EndNodes\n$Elements\n{len(CUBE_T) + 1}\n7 2 2 1 1 1 2 4\n" + elems + "$EndElements\n"


def gmsh41():
    n, m = len(CUBE_V), len(CUBE_T)
    nodes = f"$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n" + "".join(f"{i + 1}\n" for i in range(n))
    nodes += "".join(f"{x} {y} {z}\n" for x, y, z in CUBE_V) + "$EndNodes\n"
    elems = f"$Elements\n1 {m} 1 {m}\n3 1 4 {m}\n"
    elems += "".join(f"{k + 1} " + " ".join(str(i + 1) for i in t) + "\n" for k, t in enumerate(CUBE_T))
    return "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" + nodes + elems + "$EndElements\n"


def vtk(polydata=False):
    pts = "".join(f"{x} {y} {z}\n" for x, y, z in CUBE_V)
    head = f"# vtk DataFile Version 2.0\ncube\nASCII\nDATASET {'POLYDATA' if polydata else 'UNSTRUCTURED_GRID'}\n"
    head += f"POINTS {len(CUBE_V)} float\n" + pts
    cells = "".join("4 " + " ".join(map(str, t)) + "\n" for t in CUBE_T)
    if polydata:
        return head + f"POLYGONS {len(CUBE_T)} {5 * len(CUBE_T)}\n" + cells
    return head + f"CELLS {len(CUBE_T)} {5 * len(CUBE_T)}\n" + cells + f"CELL_TYPES {len(CUBE_T)}\n" + "10\n" * len(CUBE_T)


import struct  # noqa: E402

put("volume_medit", "cube_v1.mesh", medit(1))
put("volume_medit", "cube_v2.mesh", medit(2))
put("volume_gmsh", "cube22.msh", gmsh22())
put("volume_gmsh", "cube22_binary.msh", gmsh22(binary=True))
put("volume_gmsh", "cube41.msh", gmsh41())
put("volume_vtk", "cube_grid.vtk", vtk())
put("volume_vtk", "cube_polydata.vtk", vtk(polydata=True))
SHARED = os.path.join(HERE, "..", "..", "shared", "data", "volumes")
for target, rel in [("volume_medit", "libigl-tutorial-data/octopus-low.mesh"),
                    ("volume_gmsh", "scikit-fem/cuubat.msh"), ("volume_gmsh", "scikit-fem/box.msh"),
                    ("volume_gmsh", "libigl-tutorial-data/hand.msh"), ("volume_vtk", "lapy/cubeTetra.vtk")]:
    path = os.path.join(SHARED, rel)
    if os.path.isfile(path):
        with open(path, "rb") as fh:
            put(target, "shared_" + rel.replace("/", "_"), fh.read(4096))

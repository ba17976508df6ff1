#!/usr/bin/env python3
"""Writes the malformed / hostile mesh corpus used by tests/bad_input.rs.

Run from anywhere: `python3 tests/data/bad/make.py`. Output is deterministic.
"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def w(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


# A tetrahedron: a closed, valid mesh used as the base of many cases.
TV = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TF = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def obj(v, f):
    s = "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    return s + "".join("f " + " ".join(str(i) for i in face) + "\n" for face in f)


def off(v, f, counts=None):
    nv, nf = counts if counts else (len(v), len(f))
    s = f"OFF\n{nv} {nf} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in v)
    return s + "".join(f"{len(face)} " + " ".join(str(i) for i in face) + "\n" for face in f)


def ply_ascii(v, f, nv=None, nf=None):
    nv = len(v) if nv is None else nv
    nf = len(f) if nf is None else nf
    s = ("ply\nformat ascii 1.0\n"
         f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
         f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
    s += "".join(f"{x} {y} {z}\n" for x, y, z in v)
    return s + "".join(f"{len(face)} " + " ".join(str(i) for i in face) + "\n" for face in f)


def ply_binary(v, f, nv=None, nf=None):
    nv = len(v) if nv is None else nv
    nf = len(f) if nf is None else nf
    h = ("ply\nformat binary_little_endian 1.0\n"
         f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
         f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    b = b"".join(struct.pack("<3f", *p) for p in v)
    b += b"".join(struct.pack("<B", len(face)) + struct.pack(f"<{len(face)}i", *face) for face in f)
    return h + b


def stl_ascii(tris):
    s = "solid t\n"
    for t in tris:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join(f"   vertex {x} {y} {z}\n" for x, y, z in t)
        s += "  endloop\n endfacet\n"
    return s + "endsolid t\n"


def stl_binary(tris, count=None):
    count = len(tris) if count is None else count
    b = b"binary stl written by make.py".ljust(80, b" ") + struct.pack("<I", count)
    for t in tris:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0"
    return b


TET_TRIS = [[TV[i] for i in face] for face in TF]
GARBAGE = bytes((i * 97 + 13) % 256 for i in range(512))
OBJ_TET = [tuple(i + 1 for i in f) for f in TF]

# ---- empty files, every format
for ext in ["obj", "off", "ply", "stl"]:
    w(f"empty.{ext}", b"")

# ---- garbage
for ext in ["obj", "off", "ply", "stl"]:
    w(f"garbage.{ext}", GARBAGE)

# ---- OBJ
w("obj_truncated.obj", obj(TV, OBJ_TET)[:-3])  # last line cut to "f 2 3"
w("obj_vertices_only.obj", obj(TV, []))
w("obj_nan.obj", obj(TV[:2] + [("nan", 1, 0)] + TV[3:], OBJ_TET))
w("obj_inf.obj", obj(TV[:3] + [(0, 0, "inf")], OBJ_TET))
w("obj_index_out_of_range.obj", obj(TV, OBJ_TET[:3] + [(2, 3, 5)]))
w("obj_zero_index.obj", obj(TV, [(0, 2, 3)] + OBJ_TET[1:]))
w("obj_negative_before_first.obj", obj(TV, OBJ_TET[:2] + [(-1, -2, -9)] + OBJ_TET[3:]))
w("obj_negative_relative_ok.obj", obj(TV, [(-4, -2, -3), (-4, -3, -1), (-4, -1, -2), (-3, -2, -1)]))
w("obj_repeated_vertex.obj", obj(TV, OBJ_TET[:3] + [(2, 2, 4)]))
# tetrahedron + one collinear (zero-area) face using an extra vertex on edge 1-2
w("obj_zero_area_face.obj", obj(TV + [(0.5, 0, 0)], OBJ_TET + [(1, 5, 2)]))
# a needle: extra apex 1e-9 away from the edge midpoint of a 1-long edge (area/ℓ² = 5e-10 > 1e-14: valid)
w("obj_needle_face.obj", obj(TV + [(0.5, 1e-9, -1e-9)], OBJ_TET + [(1, 2, 5)]))
# a needle below the degeneracy threshold: 1e-16 off the edge (area/ℓ² ~ 5e-17)
w("obj_needle_degenerate.obj", obj(TV + [(0.5, -1e-16, 0)], OBJ_TET + [(1, 2, 5)]))
w("obj_isolated_vertex.obj", obj(TV[:2] + [(5, 5, 5)] + TV[2:], [(1, 4, 2), (1, 2, 5), (1, 5, 4), (2, 4, 5)]))
# non-manifold fan: three triangles sharing the edge (1,2)
w("obj_nonmanifold_fan.obj", obj([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)],
                                 [(1, 2, 3), (2, 1, 4), (1, 2, 5)]))
# a triangle, a quad and a pentagon in one flat fan-able strip
w("obj_mixed_polygons.obj", obj([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0), (3, 0.5, 0), (3, 1.5, 0)],
                                [(1, 2, 4), (2, 5, 6, 3), (5, 7, 8, 6)]))
w("obj_collinear.obj", obj([(0, 0, 0), (1, 1, 1), (2, 2, 2), (3, 3, 3)], [(1, 2, 3), (2, 3, 4)]))
w("obj_crlf.obj", obj(TV, OBJ_TET).replace("\n", "\r\n"))
w("obj_utf8_bom.obj", "\ufeff" + obj(TV, OBJ_TET))  # BOM before the first record
w("obj_bad_number.obj", obj(TV, OBJ_TET).replace("v 1 0 0", "v 1 zero 0"))
w("obj_face_two_corners.obj", obj(TV, OBJ_TET[:3] + [(2, 3)]))

# ---- OFF
w("off_truncated.off", off(TV, TF)[:-7])
w("off_header_only.off", "OFF\n")
w("off_counts_too_large.off", off(TV, TF, counts=(6, 4)))
w("off_counts_too_small.off", off(TV, TF, counts=(4, 2)))  # two faces too many: trailing data
w("off_huge_counts.off", "OFF\n999999999 999999999 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
w("off_crlf.off", off(TV, TF).replace("\n", "\r\n"))
w("off_binary.off", b"OFF BINARY\n" + struct.pack(">3i", 4, 4, 0)
  + b"".join(struct.pack(">3f", *p) for p in TV)
  + b"".join(struct.pack(">4i", 3, *f) for f in TF))
w("off_negative_index.off", off(TV, TF[:3] + [(1, -1, 3)]))
w("off_index_out_of_range.off", off(TV, TF[:1] + [(0, 1, 4)] + TF[2:]))
w("off_inf.off", off(TV[:1] + [("-inf", 0, 0)] + TV[2:], TF))
w("off_nan.off", off(TV[:3] + [(0, 0, "NaN")], TF))
w("off_mixed_polygons.off", off([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0)], [(0, 1, 3), (1, 4, 5, 2)]))
w("off_repeated_vertex.off", off(TV, [(0, 0, 1)] + TF[1:]))
w("off_no_magic.off", "4 4 0\n" + off(TV, TF).split("\n", 2)[2])

# ---- PLY
w("ply_ascii_truncated.ply", ply_ascii(TV, TF)[:-8])
w("ply_binary_truncated.ply", ply_binary(TV, TF)[:-5])
w("ply_header_truncated.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n")
w("ply_ascii_counts_too_large.ply", ply_ascii(TV, TF, nv=5))
w("ply_ascii_counts_too_small.ply", ply_ascii(TV, TF, nf=3))
w("ply_ascii_huge_vertex_count.ply", ply_ascii(TV, TF, nv=4000000000))
w("ply_binary_huge_vertex_count.ply", ply_binary(TV, TF, nv=4000000000))
w("ply_binary_huge_face_count.ply", ply_binary(TV, TF, nf=4294967295))
w("ply_ascii_crlf.ply", ply_ascii(TV, TF).replace("\n", "\r\n"))
w("ply_binary_crlf_header.ply", ply_binary(TV, TF).replace(b"\n", b"\r\n", ply_binary(TV, TF).count(b"\n", 0, ply_binary(TV, TF).index(b"end_header") + 11)))
w("ply_binary_negative_index.ply", ply_binary(TV, TF[:2] + [(0, -7, 2)] + TF[3:]))
w("ply_binary_index_out_of_range.ply", ply_binary(TV, TF[:3] + [(1, 2, 1000)]))
w("ply_binary_nan.ply", ply_binary(TV[:1] + [(float("nan"), 0, 0)] + TV[2:], TF))
w("ply_ascii_mixed_polygons.ply", ply_ascii([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0)], [(0, 1, 3), (1, 4, 5, 2)]))
w("ply_no_xyz.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float u\nproperty float v\nelement face 1\n"
  "property list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n3 0 1 2\n")
w("ply_unknown_format.ply", ply_ascii(TV, TF).replace("format ascii 1.0", "format binary_middle_endian 1.0"))
w("ply_bad_magic.ply", "plx\n" + ply_ascii(TV, TF)[4:])

# ---- STL
w("stl_ascii_truncated.stl", stl_ascii(TET_TRIS)[:-60])
w("stl_binary_truncated.stl", stl_binary(TET_TRIS)[:-20])
w("stl_binary_huge_count.stl", stl_binary(TET_TRIS, count=2**32 - 1))
w("stl_binary_header_only.stl", stl_binary([], count=0))
w("stl_ascii_nan.stl", stl_ascii(TET_TRIS).replace("vertex 1 0 0", "vertex 1 nan 0", 1))
w("stl_binary_inf.stl", stl_binary([[(0, 0, 0), (float("inf"), 0, 0), (0, 1, 0)]] + TET_TRIS[1:]))
w("stl_binary_point_triangle.stl", stl_binary(TET_TRIS + [[(1, 1, 1)] * 3]))
w("stl_ascii_crlf.stl", stl_ascii(TET_TRIS).replace("\n", "\r\n"))

# ---- no format
w("unknown_extension.xyz", obj(TV, OBJ_TET))
w("no_extension", obj(TV, OBJ_TET))

# ---- more hostile cases
# a face list whose 32-bit length prefix claims 2^31 − 1 corners (must not allocate for them)
w("ply_binary_huge_list_count.ply",
  ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
   "element face 1\nproperty list int int vertex_indices\nend_header\n").encode()
  + b"".join(struct.pack("<3f", *p) for p in TV) + struct.pack("<i", 2**31 - 1) + struct.pack("<3i", 0, 1, 2))
w("ply_binary_two_corner_face.ply",
  ply_binary(TV, TF)[:-len(struct.pack("<B3i", 3, 1, 2, 3))] + struct.pack("<B2i", 2, 1, 2))
w("ply_binary_big_endian.ply",
  ("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
   "element face 4\nproperty list uchar uint vertex_indices\nend_header\n").encode()
  + b"".join(struct.pack(">3d", *p) for p in TV) + b"".join(struct.pack(">B3I", 3, *f) for f in TF))
w("ply_ascii_nan.ply", ply_ascii(TV[:2] + [(0, "nan", 0)] + TV[3:], TF))
w("off_huge_corner_count.off", off(TV, TF[:3], counts=(4, 4)) + "1000000000 1 2 3\n")
w("off_negative_counts.off", "OFF\n-1 4 0\n0 0 0\n")
w("obj_index_overflow.obj", obj(TV, OBJ_TET[:3] + [("2", "3", "99999999999999999999")]))
# a binary STL whose 80-byte header starts with "solid", as many exporters write it
w("stl_binary_starts_with_solid.stl", b"solid exported by a CAD tool".ljust(80, b" ") + stl_binary(TET_TRIS)[80:])
# a quad that repeats a corner: fan triangulation turns it into a repeated-index triangle
w("obj_polygon_repeated_corner.obj", obj(TV, OBJ_TET[:3] + [(2, 3, 3, 4)]))

#!/usr/bin/env python3
"""Writes the regression inputs of tests/fuzz_regressions.rs (found while fuzzing, issue #8).

Run from anywhere: `python3 tests/data/fuzz/make.py`. Output is deterministic.
Minimised crash inputs from `cargo fuzz tmin` are committed next to these files as they are.
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
TF = [(1, 3, 2), (1, 2, 4), (1, 4, 3), (2, 3, 4)]


def tet(s):
    v = [("0", "0", "0"), (s, "0", "0"), ("0", s, "0"), ("0", "0", s)]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a} {b} {c}\n" for a, b, c in TF)


# The unit tetrahedron scaled by s: valid for 1e-150 ≤ s ≤ 1e153 (the face areas s²/2 and
# s²·√3/2 are normal doubles and their sum is finite); beyond, the area over- or underflows.
for name, s in [("tet_1.obj", "1"), ("tet_1e100.obj", "1e100"), ("tet_1e153.obj", "1e153"),
                ("tet_1e-150.obj", "1e-150"), ("tet_1e154.obj", "1e154"), ("tet_1e200.obj", "1e200"),
                ("tet_1e-160.obj", "1e-160")]:
    with open(os.path.join(HERE, name), "w") as f:
        f.write(tet(s))

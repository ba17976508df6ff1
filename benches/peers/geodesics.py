#!/usr/bin/env python3
"""Geodesic distances: wfem against potpourri3d and libigl, in one run, on the same meshes.

    python benches/peers/geodesics.py [--meshes DIR] [--large] [--json out.json]

* **Accuracy** on real meshes of the corpus (TOSCA cat0 and david0, the 28K-vertex cat0, the
  bunny, spot, a 252-vertex SHREC'11 shape and a 250-vertex genus-1 one), three sources each,
  against exact polyhedral geodesics (pygeodesic, MMP): mean and max relative error of wfem's
  default (fast marching on the intrinsic Delaunay triangulation), its heat method, its
  ``refine=1``, potpourri3d's ``MeshHeatMethodDistanceSolver`` (``t_coef=1``, robust and not) and
  libigl's ``heat_geodesics`` (``t = h²``).
* **Speed** on icospheres of 41K and (with ``--large``) 655K vertices and on the real meshes:
  prepare once, then the mean of 5 further queries, best of 3; the prepared solver's memory
  (wfem's own statement; the process's RSS growth for every peer).

All in one process on the same cores; ratios are peer / wfem (> 1: wfem is faster or more
accurate). Pinned versions: ``benches/peers/python-api-requirements.txt``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import time
from pathlib import Path

import numpy as np

import wfem

REAL = {
    "cat0": "tosca-bcicp-5k/TOSCA_Isometric/cat0.off",
    "david0": "tosca-bcicp-5k/TOSCA_Isometric/david0.off",
    "cat0-28k": "tosca-kernelmatching/cat0.off",
    "bunny": "potpourri3d-test/bunny_small.ply",
    "spot": "common-3d-test-models/spot.obj",
    "shrec-cat-252": "shrec11-meshcnn500/shrec_16/cat/test/T123.obj",
    "alien-genus1-250": "shrec11-meshcnn500/shrec_16/alien/test/T124.obj",
}


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def errors(d, exact, s):
    keep = np.ones(len(exact), bool)
    keep[s] = False
    r = np.abs(d[keep] - exact[keep]) / exact[keep]
    return r.mean(), r.max()


def methods(V, F):
    """name → (prepare() → solver, query(solver, s) → distances)."""
    import igl
    import potpourri3d as pp3d

    Fi = F.astype(np.int64)
    out = {
        "wfem (default: fast marching)": (lambda: wfem.GeodesicSolver(V, F), lambda s, i: s.distance(i)),
        "wfem heat": (lambda: wfem.GeodesicSolver(V, F, method="heat"), lambda s, i: s.distance(i)),
        "wfem refine=1": (lambda: wfem.GeodesicSolver(V, F, refine=1), lambda s, i: s.distance(i)),
        "potpourri3d (robust)": (
            lambda: pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=True),
            lambda s, i: s.compute_distance(i),
        ),
        "potpourri3d (cotan)": (
            lambda: pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=False),
            lambda s, i: s.compute_distance(i),
        ),
    }

    def igl_prepare():
        h = igl.avg_edge_length(V, Fi)
        data = igl.HeatGeodesicsData()
        igl.heat_geodesics_precompute(V, Fi, h * h, data)
        return data

    out["libigl heat_geodesics"] = (
        igl_prepare,
        lambda d, i: igl.heat_geodesics_solve(d, np.array([i], dtype=np.int64)),
    )
    return out


def accuracy(corpus: Path):
    from pygeodesic import geodesic
    import potpourri3d as pp3d

    rows = []
    for name, rel in REAL.items():
        path = corpus / rel
        if not path.exists():
            continue
        V, F = pp3d.read_mesh(str(path))
        V, F = np.asarray(V, float), np.asarray(F, np.int64)
        exact_solver = geodesic.PyGeodesicAlgorithmExact(V, F.astype(np.int32))
        sources = [0, len(V) // 3, 2 * len(V) // 3]
        exact = [exact_solver.geodesicDistances(np.array([s], np.int32), None)[0] for s in sources]
        for method, (prepare, query) in methods(V, F).items():
            try:
                solver = prepare()
                res = [errors(np.asarray(query(solver, s)).ravel(), e, s) for s, e in zip(sources, exact)]
                mean, mx = float(np.mean([r[0] for r in res])), float(np.max([r[1] for r in res]))
            except Exception as e:  # noqa: BLE001 - a failing peer is reported, not hidden
                mean, mx = float("nan"), float("nan")
                print(f"  {name} {method}: {e}")
            rows.append({"mesh": name, "n": len(V), "method": method, "mean": mean, "max": mx})
            print(f"  {name:18s} {method:32s} mean {mean:.4f} max {mx:.3f}", flush=True)
    return rows


def speed(meshes, repeat=3):
    rows = []
    for name, (V, F) in meshes.items():
        for method, (prepare, query) in methods(V, F).items():
            if "refine" in method or "cotan" in method:
                continue
            best_prep, best_query, mem = float("inf"), float("inf"), float("nan")
            for _ in range(repeat):
                before = rss_mb()
                t = time.perf_counter()
                solver = prepare()
                best_prep = min(best_prep, time.perf_counter() - t)
                mem = getattr(solver, "memory_bytes", None)
                mem = mem / 2**20 if mem else rss_mb() - before
                query(solver, 0)  # first query (caches)
                t = time.perf_counter()
                for i in range(5):
                    query(solver, (i + 1) * len(V) // 7)
                best_query = min(best_query, (time.perf_counter() - t) / 5)
                del solver
            rows.append(
                {"mesh": name, "n": len(V), "method": method, "prepare": best_prep, "query": best_query, "memory_mb": mem}
            )
            print(f"  {name:12s} {method:32s} prepare {best_prep:7.3f} s  query {best_query:7.4f} s  memory {mem:7.1f} MB", flush=True)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    default = os.environ.get("WFEM_MESHES") or str(Path(__file__).resolve().parents[3] / "shared" / "data" / "meshes")
    parser.add_argument("--meshes", default=default)
    parser.add_argument("--large", action="store_true")
    parser.add_argument("--json")
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()}")
    print("accuracy against pygeodesic (exact MMP):")
    acc = accuracy(Path(args.meshes))
    sizes = {"icosphere-41K": wfem.generate.icosphere(6)}
    if args.large:
        sizes["icosphere-655K"] = wfem.generate.icosphere(8)
    print("speed:")
    spd = speed(sizes)
    if args.json:
        Path(args.json).write_text(json.dumps({"accuracy": acc, "speed": spd}, indent=2))
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()

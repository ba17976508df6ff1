"""pyFM's functional-map pipeline (WKS descriptors with five landmarks, the functional map fit,
ZoomOut) on a TOSCA pair with ground truth, with pyFM's own eigen step and with wfem's
(``wfem.pyfm.process``): the same geodesic map error, the time of both eigen steps.

Run: ``python pyfm_zoomout.py MESHES_DIR [cat0 cat2] [--k 200]`` with ``MESHES_DIR`` the shared
corpus (``../shared/data/meshes``); needs ``pip install pyfmaps`` (pyFM).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from pyFM.functional import FunctionalMapping
from pyFM.mesh import TriMesh

import wfem
import wfem.pyfm


def geodesic_error(V, F, area: float, p2p: np.ndarray, gt_a: np.ndarray, gt_b: np.ndarray, samples: int) -> float:
    """Mean geodesic distance on shape A between where the map sends each ground-truth point of B
    and where it should go, over `samples` ground-truth pairs, in units of √area (pyFM's metric)."""
    idx = np.linspace(0, len(gt_a) - 1, samples).astype(int)
    solver = wfem.GeodesicSolver(V, F)
    rows = solver.distance_each(gt_a[idx].tolist())
    mapped = p2p[gt_b[idx]]
    return float(np.mean(rows[np.arange(len(idx)), mapped]) / np.sqrt(area))


def run(folder: Path, a: str, b: str, k: int, route: str) -> tuple[float, float]:
    """(eigen step of both meshes in s, geodesic map error in √A) of one route."""
    eigen, error, _ = run_timed(folder, a, b, k, route)
    return eigen, error


def run_timed(folder: Path, a: str, b: str, k: int, route: str) -> tuple[float, float, float]:
    """(eigen step, geodesic map error, whole pipeline: loading, eigen step, WKS, fit, ZoomOut and
    the point-to-point map, in s) of one route; the error's evaluation is not timed."""
    begin = time.perf_counter()
    meshes = [TriMesh.load(str(folder / f"{name}.off"), area_normalize=True, center=True) for name in (a, b)]
    start = time.perf_counter()
    for m in meshes:
        if route == "wfem":
            wfem.pyfm.process(m, k=k)
        else:
            m.process(k=k)
    eigen = time.perf_counter() - start
    gt_a, gt_b = (np.loadtxt(folder / "corres" / f"{name}.vts", dtype=int) - 1 for name in (a, b))
    landmarks = np.stack([gt_a, gt_b], axis=1)[np.linspace(0, len(gt_a) - 1, 5).astype(int)]
    model = FunctionalMapping(meshes[0], meshes[1])
    # The spectrum is there already: preprocess() only truncates it (k_process = k).
    model.preprocess(n_descr=100, descr_type="WKS", landmarks=landmarks, subsample_step=5, k_process=k)
    model.fit(K=(35, 35), w_descr=1e0, w_lap=1e-2, w_dcomm=1e-1, w_orient=0)
    fm = model.zoomout_refine(nit=15, step=5)
    p2p_ba = model.get_p2p(FM=fm, n_jobs=1)  # each vertex of B to a vertex of A
    total = time.perf_counter() - begin
    error = geodesic_error(meshes[0].vertices, meshes[0].faces, float(meshes[0].area), p2p_ba, gt_a, gt_b, 500)
    return eigen, error, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", type=Path)
    parser.add_argument("pair", nargs="*", default=["cat0", "cat2"])
    parser.add_argument("--k", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=1, help="runs of each route, alternated")
    args = parser.parse_args()
    folder = args.meshes / "tosca-bcicp-5k" / "TOSCA_Isometric"
    a, b = args.pair if len(args.pair) == 2 else ("cat0", "cat2")
    for _ in range(args.repeat):
        for route in ("pyfm", "wfem"):
            eigen, error, total = run_timed(folder, a, b, args.k, route)
            print(f"{route:5s} route: eigen step {eigen:6.2f} s for both meshes (k = {args.k}), "
                  f"whole pipeline {total:6.2f} s, geodesic map error {1e3 * error:.2f} ×1e-3 √A ({a} ← {b})")


if __name__ == "__main__":
    main()

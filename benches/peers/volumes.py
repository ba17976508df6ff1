"""wfem against LaPy on tetrahedral meshes (issue #39 point 5), in one process and one run.

    python benches/peers/volumes.py [--levels 0 1] [--mesh PATH] [--k 50]

For the shared armadillo (TetWild, 18K vertices) and its red refinements (every tetrahedron
into eight, done here in numpy): the assembly of L and B (wfem.operators against LaPy's
Solver(TetMesh, lump=False)), K_t f at t = 1e-3·V^(2/3) (wfem's exact default against one
backward-Euler solve (B + tL)⁻¹Bf by scipy's SuperLU — the cost LaPy's heat.diffusion pays —
and LaPy's heat.diffusion itself), and the k smallest eigenpairs (wfem.eigenbasis against
LaPy's Solver.eigs). Wall times of the calls (best of `--repeat`), on whatever machine runs it.
Needs: a release wheel of wfem, lapy, scipy (benches/peers/volumes-requirements.txt).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import wfem

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT = os.path.join(HERE, "..", "..", "..", "shared", "data", "volumes", "flip-free-parametrization", "armadillo.mesh")


def refine(V: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bey's red refinement: the old vertices, then one per edge; 8 children per tetrahedron."""
    pairs = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
    e = np.sort(T[:, pairs].reshape(-1, 2), axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    mid = (V[uniq[:, 0]] + V[uniq[:, 1]]) / 2
    m = inv.reshape(-1, 6) + len(V)
    a, b, c, d = T.T
    m01, m02, m03, m12, m13, m23 = m.T
    children = [
        (a, m01, m02, m03), (m01, b, m12, m13), (m02, m12, c, m23), (m03, m13, m23, d),
        (m01, m02, m03, m13), (m01, m02, m12, m13), (m02, m03, m13, m23), (m02, m12, m13, m23),
    ]
    return np.vstack([V, mid]), np.vstack([np.column_stack(ch) for ch in children])


def best(f, repeat: int) -> tuple[float, object]:
    out, times = None, []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", default=DEFAULT)
    ap.add_argument("--levels", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--k", type=int, default=50)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--no-lapy-eigs-above", type=int, default=400_000)
    args = ap.parse_args()
    import lapy
    from lapy import Solver, TetMesh

    V0, T0 = wfem.read_volume(args.mesh)
    rows = []
    for level in args.levels:
        V, T = V0, T0
        for _ in range(level):
            V, T = refine(V, T)
        n = len(V)
        vol = wfem.validate_volume(V, T).volume
        t = 1e-3 * vol ** (2 / 3)
        f = V[:, 0].copy()
        ta, (L, B, _) = best(lambda: wfem.operators(V, T), args.repeat)
        tl, solver = best(lambda: Solver(TetMesh(V, T.astype(np.int64)), lump=False), args.repeat)
        assert abs(solver.stiffness - L).max() < 1e-8 * abs(L).max(), "LaPy's stiffness differs"
        th, u = best(lambda: wfem.HeatKernel(V, T).apply(f, t), 1)
        tb, ub = best(lambda: sla.spsolve((B + t * L).tocsc(), B @ f), 1)
        tdiff = float("nan")
        try:
            from lapy import heat

            tdiff, _ = best(lambda: heat.diffusion(TetMesh(V, T.astype(np.int64)), [0], m=1.0), 1)
        except Exception as e:  # noqa: BLE001 — a peer's limitation is reported, not fatal
            print(f"  lapy.heat.diffusion: {type(e).__name__}: {e}")
        te, basis = best(lambda: wfem.eigenbasis(V, T, args.k), 1)
        tle = float("nan")
        if n <= args.no_lapy_eigs_above:
            tle, (ev, _) = best(lambda: solver.eigs(k=args.k), 1)
            err = np.max(np.abs(np.sort(ev)[1:] - basis.values[1:]) / basis.values[1:])
            print(f"  eigenvalues wfem vs LaPy: max relative difference {err:.1e}")
        row = (level, n, len(T), ta, tl, th, tb, tdiff, te, tle)
        rows.append(row)
        print(
            f"level {level}: n = {n}, tets = {len(T)}: assembly wfem {ta:.3f} s / LaPy {tl:.3f} s ({tl / ta:.1f}x); "
            f"K_t f wfem {th:.3f} s, one backward-Euler SuperLU solve {tb:.3f} s, LaPy diffusion {tdiff:.3f} s; "
            f"eigs k={args.k} wfem {te:.3f} s / LaPy {tle:.3f} s",
            flush=True,
        )
    print("\n| level | vertices | tets | assembly wfem | LaPy | ratio | K_t f wfem (exact) | (B+tL)⁻¹ SuperLU | LaPy diffusion | eigs wfem | eigs LaPy | ratio |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for (level, n, m, ta, tl, th, tb, td, te, tle) in rows:
        print(f"| {level} | {n:,} | {m:,} | {ta:.3f} s | {tl:.3f} s | {tl / ta:.1f}× | {th:.2f} s | {tb:.2f} s | {td:.2f} s | {te:.2f} s | {tle:.2f} s | {tle / te:.1f}× |")


if __name__ == "__main__":
    main()

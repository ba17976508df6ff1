"""The exact methods for K_t f on tetrahedral meshes, against LaPy and one CHOLMOD solve (issue #39
point 5: the volume default from a table).

    python benches/peers/volume_methods.py --mesh PATH --levels 0 1 [--cases ...] [--workdir DIR]

For a shared volume and its red refinements (every tetrahedron into eight, `volumes.refine`),
K_t e_i at t = 1e-3·V^(2/3) from a vertex i = n/3, each case in a fresh process (so that its peak
RSS is its own; `os.wait4`, as /usr/bin/time): wfem's methods (the fast path, the rational
method with each backend, the spectral route), one backward-Euler solve (B + tL)⁻¹Bf by
CHOLMOD (scikit-sparse) and by SuperLU, LaPy's `heat.diffusion`, and the assembly alone (wfem
against LaPy's `Solver`). "Kernel" is the time of the call inside the process (the kernel's
preparation and K_t f, or the factorization and the solve; the operators assembled before);
"process" the wall time of the whole process (Python, reading the arrays, assembly, writing).
Every wfem result is compared with the rational LDLᵀ one (relative max-norm).
Needs: a release wheel of wfem and benches/peers/volumes-requirements.txt (lapy, scikit-sparse).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

# name → (what it is, the keyword arguments of wfem.HeatKernel, or None for a peer)
WFEM = {
    "fast": {},
    "rational-ldlt": {"method": "rational", "backend": "ldlt"},
    "rational-lu": {"method": "rational", "backend": "lu"},
    "rational-minres": {"method": "rational", "backend": "minres"},
    "rational-multishift": {"method": "rational", "backend": "multishift"},
    "spectral-200": {"method": "spectral", "k": 200},
}
PEERS = ["cholmod-be", "superlu-be", "lapy-diffusion", "assembly-wfem", "assembly-lapy"]
REFERENCE = "rational-ldlt"


def child(case: str, data: str, out: str) -> None:
    """One case in this process: prints {"kernel": s, "assembly": s} and writes the result."""
    import wfem

    z = np.load(data)
    V, T, t, i = z["V"], z["T"], float(z["t"]), int(z["i"])
    n = len(V)
    f = np.zeros(n)
    f[i] = 1.0
    report = {}
    if case in WFEM:
        t0 = time.perf_counter()
        K = wfem.HeatKernel(V, T, **WFEM[case])
        u = K.apply(f, t)
        report["kernel"] = time.perf_counter() - t0
    elif case in ("cholmod-be", "superlu-be"):
        t0 = time.perf_counter()
        L, B, _ = wfem.operators(V, T)
        report["assembly"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        A = (B + t * L).tocsc()
        if case == "cholmod-be":
            from sksparse.cholmod import cholesky

            u = cholesky(A)(B @ f)
        else:
            import scipy.sparse.linalg as sla

            u = sla.spsolve(A, B @ f)
        report["kernel"] = time.perf_counter() - t0
    elif case == "lapy-diffusion":
        from lapy import TetMesh, heat

        t0 = time.perf_counter()
        u = heat.diffusion(TetMesh(V, T.astype(np.int64)), [i], m=1.0)
        report["kernel"] = time.perf_counter() - t0
    elif case == "assembly-wfem":
        t0 = time.perf_counter()
        wfem.operators(V, T)
        report["kernel"] = time.perf_counter() - t0
        u = None
    elif case == "assembly-lapy":
        from lapy import Solver, TetMesh

        t0 = time.perf_counter()
        Solver(TetMesh(V, T.astype(np.int64)), lump=False)
        report["kernel"] = time.perf_counter() - t0
        u = None
    else:
        raise SystemExit(f"unknown case {case}")
    if u is not None:
        np.save(out, np.asarray(u, dtype=float))
    print(json.dumps(report))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--levels", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--cases", nargs="+", default=list(WFEM) + PEERS)
    ap.add_argument("--repeat", type=int, default=1, help="runs per case (the range is printed)")
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--lapy-below", type=int, default=400_000, help="run LaPy's diffusion only below this n")
    ap.add_argument("--spectral-below", type=int, default=400_000)
    ap.add_argument("--reference", default=REFERENCE, help="the case the others are compared with")
    args = ap.parse_args()
    import wfem
    from peers import run_measured
    from volumes import refine

    work = args.workdir or tempfile.mkdtemp(prefix="wfem-volume-methods-")
    V0, T0 = wfem.read_volume(args.mesh)
    rows = []
    for level in args.levels:
        V, T = V0, T0
        for _ in range(level):
            V, T = refine(V, T)
        n = len(V)
        vol = wfem.validate_volume(V, T).volume
        t = 1e-3 * vol ** (2 / 3)
        data = os.path.join(work, f"level{level}.npz")
        np.savez(data, V=V, T=T.astype(np.int64), t=t, i=n // 3)
        del V, T
        results = {}
        for case in args.cases:
            if case == "lapy-diffusion" and n >= args.lapy_below:
                continue
            if case.startswith("spectral") and n >= args.spectral_below:
                continue
            out = os.path.join(work, f"level{level}-{case}.npy")
            runs = []
            for _ in range(args.repeat):
                wall, rss, code, stdout, stderr = run_measured([sys.executable, __file__, "child", case, data, out])
                if code != 0:
                    print(f"  {case}: exit {code}: {stderr.strip().splitlines()[-1:] }", flush=True)
                    break
                runs.append((json.loads(stdout.strip().splitlines()[-1]), wall, rss))
            if runs:
                results[case] = runs
                k = [r[0]["kernel"] for r in runs]
                print(
                    f"level {level} (n = {n:,}) {case}: kernel {min(k):.3f}–{max(k):.3f} s, process "
                    f"{min(r[1] for r in runs):.2f}–{max(r[1] for r in runs):.2f} s, peak RSS "
                    f"{max(r[2] for r in runs) / 2**20:.0f} MB",
                    flush=True,
                )
        errors = {}
        ref_path = os.path.join(work, f"level{level}-{args.reference}.npy")
        if os.path.exists(ref_path):
            ref = np.load(ref_path)
            for case in results:
                p = os.path.join(work, f"level{level}-{case}.npy")
                if os.path.exists(p) and case != args.reference:
                    errors[case] = float(np.abs(np.load(p) - ref).max() / np.abs(ref).max())
        rows.append((level, n, results, errors))
        print(f"level {level}: errors against {args.reference}: " + ", ".join(f"{c} {e:.1e}" for c, e in errors.items()), flush=True)
        os.remove(data)
    print(f"\n| level | vertices | case | kernel (s) | process (s) | peak RSS (MB) | vs CHOLMOD BE (kernel) | error vs {args.reference} |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|")
    for level, n, results, errors in rows:
        chol = min(r[0]["kernel"] for r in results["cholmod-be"]) if "cholmod-be" in results else float("nan")
        for case, runs in results.items():
            k = [r[0]["kernel"] for r in runs]
            span = lambda x: f"{min(x):.3f}" if len(x) == 1 else f"{min(x):.3f}–{max(x):.3f}"
            w = [r[1] for r in runs]
            rss = max(r[2] for r in runs) / 2**20
            err = f"{errors[case]:.1e}" if case in errors else ("(reference)" if case == args.reference else "—")
            print(f"| {level} | {n:,} | {case} | {span(k)} | {span(w)} | {rss:.0f} | {min(k) / chol:.2f}× | {err} |")


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "child":
        child(*sys.argv[2:5])
    else:
        main()

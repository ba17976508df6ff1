#!/usr/bin/env python3
"""What wfem's users run today, timed on the meshes `cargo xtask bench` writes.

The peers are the Python tools of geometry-processing research code (pyFM, geomfum,
DiffusionNet, libigl tutorials):

* ``hks``: the k smallest eigenpairs of L x = λ B x by ``scipy.sparse.linalg.eigsh`` in
  shift-invert mode (ARPACK + SuperLU, ``sigma=-0.01``, ``which='LM'``, as pyFM does) and the
  heat kernel signature h(i, t) = Σ_k e^{−λ_k t} φ_k(i)² (pyFM's ``HKS`` formula) at the
  automatic times geomspace(4 ln10/λ_k, 4 ln10/λ_2, T) (pyFM ``auto_HKS``), written as .npy;
* ``operators``: libigl's ``cotmatrix`` and ``massmatrix(..., MASSMATRIX_TYPE_FULL)``, written
  as Matrix Market;
* ``cloud-laplacian``: robust_laplacian's ``point_cloud_laplacian`` (L and its lumped mass
  from the k = 30 nearest neighbours) on an (n, 3) ``.npy`` cloud;
* ``heat``: K_t f = exp(−t B⁻¹L) f by CRAM-16 (the best rational approximation of degree 16,
  8 complex SuperLU factorizations of tL − z_j B with the consistent mass B: the same kernel
  as wfem's, the reference of the issues) or by ``scipy.sparse.linalg.expm_multiply`` on
  −t D⁻¹L (the lumped-mass kernel, the only one expm_multiply takes as a sparse matrix).

L is the cotangent stiffness in wfem's sign convention (symmetric positive semidefinite, so
L = −igl.cotmatrix), B the consistent mass. Without libigl the same operators are built with
numpy (the formulas of mesh_fem::assemble); the JSON says which.

Every subcommand prints one JSON object on stdout. ``measure`` runs a command in fresh
processes and reports the wall-clock time and the peak resident set size of each (``os.wait4``,
the ``/usr/bin/time`` numbers), so the peers and wfem's command-line tool are measured the
same way:

    python3 peers.py check
    python3 peers.py measure --repeat 3 -- python3 peers.py hks sphere6.off --k 100 --out h.npy
    python3 peers.py measure -- target/release/wfem hks sphere6.off --eigenpairs 100 -o h.npy
    python3 peers.py compare a.npy b.npy

Pinned versions: benches/peers/requirements.txt.
"""

import argparse
import json
import os
import subprocess
import sys
import time

T_START = time.perf_counter()

# CRAM-16 for exp(−x) ≈ c0 + 2 Re Σ_j c_j/(x − z_j), poles in the upper half plane
# (docs docs/NUMERICS.md §2.3; the same table as shifted_solve::RationalApprox::cram(16)).
CRAM16_C0 = 2.1248537104952237488e-16
CRAM16 = [
    ((-6.4161776990994341857, 1.1941223933701386699), (6.4500878025539644564e1, -2.2459440762652096092e2)),
    ((-5.9481522689511774823, 3.5874573620183223162), (-1.1339775178483930464e2, 1.0194721704215856386e2)),
    ((-4.9931747377179964192, 5.9968817136039421951), (6.2518392463207919933e1, -1.1190391094283228881e1)),
    ((-3.5091036084149180718, 8.4361989858843750942), (-1.5059585270023467196e1, -5.7514052776421820767)),
    ((-1.4193758971856659905, 1.0925363484496722585e1), (1.4793007113558000013, 1.7686588323782937902)),
    ((1.4139284624888862117, 1.3497725698892745388e1), (-4.1023136835410020949e-2, -1.5743466173455468195e-1)),
    ((5.2649713434426468908, 1.6220221473167927305e1), (-2.1151742182466031443e-4, 4.3892969647380673895e-3)),
    ((1.0843917078696988026e1, 1.9277446167181652284e1), (5.0901521865224928712e-7, -2.4220017652852287986e-5)),
]


def versions():
    out = {"python": sys.version.split()[0]}
    for name, module in [("numpy", "numpy"), ("scipy", "scipy"), ("libigl", "igl")]:
        try:
            mod = __import__(module)
            out[name] = getattr(mod, "__version__", None) or _dist_version(name) or "installed"
        except Exception:  # noqa: BLE001 - any import failure means "not installed"
            out[name] = None
    return out


def _dist_version(name):
    try:
        from importlib.metadata import version

        return version(name)
    except Exception:  # noqa: BLE001
        return None


def emit(obj):
    obj.setdefault("process_seconds", time.perf_counter() - T_START)
    json.dump(obj, sys.stdout)
    sys.stdout.write("\n")


# ------------------------------------------------------------------------------------------
# Mesh and operators
# ------------------------------------------------------------------------------------------


def read_off(path):
    """(V, F) of an OFF file (triangles only), by igl.readOFF when available."""
    import numpy as np

    try:
        import igl

        v, f, _ = igl.readOFF(path)
        return np.ascontiguousarray(v, dtype=np.float64), np.ascontiguousarray(f, dtype=np.int64)
    except ImportError:
        pass
    with open(path) as fh:
        header = fh.readline().strip()
        if header != "OFF":
            raise SystemExit(f"{path}: not an OFF file")
        nv, nf, _ = (int(x) for x in fh.readline().split())
        data = np.loadtxt(fh, max_rows=nv, dtype=np.float64, ndmin=2)
        faces = np.loadtxt(fh, max_rows=nf, dtype=np.int64, ndmin=2)
    return data, faces[:, 1:4]


def operators(v, f):
    """(L, B, source): L = −cotmatrix (positive semidefinite), B = consistent mass, CSC."""
    try:
        import igl

        c = igl.cotmatrix(v, f)
        b = igl.massmatrix(v, f, igl.MASSMATRIX_TYPE_FULL)
        return (-c).tocsc(), b.tocsc(), "libigl"
    except ImportError:
        return numpy_operators(v, f) + ("numpy",)


def numpy_operators(v, f):
    """The cotangent stiffness and consistent mass with numpy (mesh_fem::assemble's formulas)."""
    import numpy as np
    import scipy.sparse as sp

    n = v.shape[0]
    p = [v[f[:, k]] for k in range(3)]
    cross = np.cross(p[1] - p[0], p[2] - p[0])
    double_area = np.linalg.norm(cross, axis=1)
    rows, cols, lvals, bvals = [], [], [], []
    for k in range(3):
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        e1, e2 = p[k1] - p[k], p[k2] - p[k]
        cot = np.einsum("ij,ij->i", e1, e2) / double_area
        # The angle at corner k is opposite the edge (k1, k2).
        rows += [f[:, k1], f[:, k2]]
        cols += [f[:, k2], f[:, k1]]
        lvals += [-0.5 * cot, -0.5 * cot]
        bvals += [double_area / 24.0, double_area / 24.0]
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    lo = sp.csc_matrix((np.concatenate(lvals), (rows, cols)), shape=(n, n))
    bo = sp.csc_matrix((np.concatenate(bvals), (rows, cols)), shape=(n, n))
    lap = lo - sp.diags(np.asarray(lo.sum(axis=1)).ravel())
    mass = bo + sp.diags(np.asarray(bo.sum(axis=1)).ravel())
    return lap.tocsc(), mass.tocsc()


# ------------------------------------------------------------------------------------------
# Peers
# ------------------------------------------------------------------------------------------


def cmd_hks(args):
    import numpy as np
    import scipy.sparse.linalg as sla

    v, f = read_off(args.mesh)
    t0 = time.perf_counter()
    lap, mass, source = operators(v, f)
    t1 = time.perf_counter()
    evals, evecs = sla.eigsh(lap, k=args.k, M=mass, sigma=args.sigma, which="LM")
    order = np.argsort(evals)
    evals, evecs = evals[order], evecs[:, order]
    t2 = time.perf_counter()
    # pyFM auto_HKS / HKS: times geomspace(4 ln10/λ_max, 4 ln10/λ_2), coefs e^{−tλ}, Σ_k φ_k².
    abs_ev = np.abs(evals)
    nonzero = abs_ev[abs_ev > 1e-8 * abs_ev.max()]
    times = np.geomspace(4 * np.log(10) / nonzero.max(), 4 * np.log(10) / nonzero.min(), args.scales)
    coefs = np.exp(-np.outer(times, evals))
    hks = np.einsum("tk,nk->nt", coefs, np.square(evecs))
    t3 = time.perf_counter()
    if args.out:
        np.save(args.out, hks)
    emit(
        {
            "peer": f"scipy eigsh (k = {args.k}, sigma = {args.sigma}) + HKS formula",
            "operators": source,
            "n": int(v.shape[0]),
            "operators_seconds": t1 - t0,
            "eigsh_seconds": t2 - t1,
            "hks_seconds": t3 - t2,
            "kernel_seconds": t3 - t1,
            "eigenvalues": evals.tolist(),
        }
    )


def cmd_operators(args):
    import scipy.io

    v, f = read_off(args.mesh)
    t0 = time.perf_counter()
    lap, mass, source = operators(v, f)
    t1 = time.perf_counter()
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        scipy.io.mmwrite(os.path.join(args.out, "stiffness.mtx"), lap)
        scipy.io.mmwrite(os.path.join(args.out, "mass.mtx"), mass)
    emit(
        {
            "peer": "libigl cotmatrix + massmatrix(FULL)" if source == "libigl" else "numpy cotangent L + B",
            "operators": source,
            "n": int(v.shape[0]),
            "kernel_seconds": t1 - t0,
        }
    )


def cmd_cloud_laplacian(args):
    """robust_laplacian's point_cloud_laplacian (k = 30, mollify_factor = 1e-5) on an (n, 3)
    .npy cloud; kernel_seconds is the call alone (the file read excluded)."""
    import numpy as np
    import robust_laplacian

    points = np.load(args.points)
    t0 = time.perf_counter()
    lap, mass = robust_laplacian.point_cloud_laplacian(points, mollify_factor=1e-5, n_neighbors=30)
    t1 = time.perf_counter()
    emit(
        {
            "peer": "robust_laplacian point_cloud_laplacian",
            "n": int(points.shape[0]),
            "nnz": int(lap.nnz),
            "kernel_seconds": t1 - t0,
        }
    )


def cmd_heat(args):
    import numpy as np
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla

    v, f = read_off(args.mesh)
    lap, mass, source = operators(v, f)
    field = np.load(args.field) if args.field else v[:, 0].copy()
    t = args.t
    t0 = time.perf_counter()
    if args.method == "cram16":
        bf = (mass @ field).astype(np.complex128)
        g = CRAM16_C0 * field
        for (zr, zi), (cr, ci) in CRAM16:
            lu = sla.splu((t * lap - complex(zr, zi) * mass).tocsc())
            g = g + 2.0 * np.real(complex(cr, ci) * lu.solve(bf))
        peer = "CRAM-16 (8 complex SuperLU factorizations, consistent B)"
    else:
        lumped = np.asarray(mass.sum(axis=1)).ravel()
        a = (-t * sp.diags(1.0 / lumped) @ lap).tocsr()
        g = sla.expm_multiply(a, field)
        peer = "expm_multiply on -t D^-1 L (lumped mass)"
    t1 = time.perf_counter()
    if args.out:
        np.save(args.out, g)
    emit({"peer": peer, "operators": source, "n": int(v.shape[0]), "kernel_seconds": t1 - t0})


def cmd_compare(args):
    """Relative differences of two arrays: max |a − b| / max |b| and per-column worst."""
    import numpy as np

    a, b = np.load(args.a), np.load(args.b)
    if a.shape != b.shape:
        emit({"error": f"shapes differ: {a.shape} vs {b.shape}"})
        return
    a2, b2 = a.reshape(a.shape[0], -1), b.reshape(b.shape[0], -1)
    scale = np.abs(b2).max(axis=0)
    per_col = np.abs(a2 - b2).max(axis=0) / np.where(scale > 0, scale, 1.0)
    emit({"max_rel": float(per_col.max()), "per_column": per_col.tolist()})


def cmd_check(_args):
    emit(versions())


def cmd_measure(args):
    """Runs the command `repeat` times in fresh processes: wall seconds and peak RSS bytes."""
    cmd = args.cmd[1:] if args.cmd and args.cmd[0] == "--" else args.cmd
    if not cmd:
        raise SystemExit("measure: no command")
    walls, rss, out = [], [], ""
    for _ in range(args.repeat):
        wall, maxrss, code, stdout, stderr = run_measured(cmd)
        if code != 0:
            emit({"error": stderr[-2000:], "returncode": code, "cmd": cmd})
            return
        walls.append(wall)
        rss.append(maxrss)
        out = stdout
    emit({"wall": walls, "maxrss_bytes": rss, "stdout": out, "returncode": 0, "cmd": cmd})


def run_measured(cmd):
    """(wall seconds, peak RSS bytes, exit code, stdout, stderr) of one fresh process, reaped
    with os.wait4 (its ru_maxrss is the child's own high-water mark, as /usr/bin/time shows)."""
    import tempfile

    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        pid = os.fork()
        if pid == 0:  # child
            try:
                os.dup2(out.fileno(), 1)
                os.dup2(err.fileno(), 2)
                os.execvp(cmd[0], cmd)
            finally:
                os._exit(127)
        _, status, usage = os.wait4(pid, 0)
        wall = time.perf_counter() - start
        # ru_maxrss is in KiB on Linux and in bytes on macOS.
        maxrss = usage.ru_maxrss * (1 if sys.platform == "darwin" else 1024)
        out.seek(0)
        err.seek(0)
        return (
            wall,
            maxrss,
            os.waitstatus_to_exitcode(status),
            out.read().decode(errors="replace"),
            err.read().decode(errors="replace"),
        )


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("check", help="installed versions as JSON").set_defaults(run=cmd_check)
    p = sub.add_parser("measure", help="wall time and peak RSS of fresh processes")
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("cmd", nargs=argparse.REMAINDER)
    p.set_defaults(run=cmd_measure)
    p = sub.add_parser("hks", help="scipy eigsh + HKS formula")
    p.add_argument("mesh")
    p.add_argument("--k", type=int, default=100)
    p.add_argument("--scales", type=int, default=16)
    p.add_argument("--sigma", type=float, default=-0.01)
    p.add_argument("--out")
    p.set_defaults(run=cmd_hks)
    p = sub.add_parser("operators", help="libigl cotmatrix + massmatrix(FULL)")
    p.add_argument("mesh")
    p.add_argument("--out")
    p.set_defaults(run=cmd_operators)
    p = sub.add_parser("heat", help="K_t f by CRAM-16 (SuperLU) or expm_multiply")
    p.add_argument("mesh")
    p.add_argument("--t", type=float, default=0.01)
    p.add_argument("--field", help=".npy with f (default: the x coordinate)")
    p.add_argument("--method", choices=["cram16", "expm"], default="cram16")
    p.add_argument("--out")
    p.set_defaults(run=cmd_heat)
    p = sub.add_parser("cloud-laplacian", help="robust_laplacian point_cloud_laplacian on an .npy cloud")
    p.add_argument("points")
    p.set_defaults(run=cmd_cloud_laplacian)
    p = sub.add_parser("compare", help="relative difference of two .npy arrays")
    p.add_argument("a")
    p.add_argument("b")
    p.set_defaults(run=cmd_compare)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()

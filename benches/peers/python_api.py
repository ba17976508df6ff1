#!/usr/bin/env python3
"""wfem from Python against what its users run today, in one process, on the same meshes.

    python benches/peers/python_api.py [--repeat 3] [--meshes DIR] [--json out.json]

For each mesh (generated icospheres of 10K and 41K vertices, and real meshes of the corpus when
``$WFEM_MESHES`` or ``../shared/data/meshes`` exists), the best of ``--repeat`` wall-clock times of:

* **operators** — ``wfem.operators(V, F)`` (L, B, D) against libigl (``cotmatrix`` +
  ``massmatrix(FULL)``), potpourri3d (``cotan_laplacian`` + ``vertex_areas``) and
  robust_laplacian (``mesh_laplacian``);
* **HKS, k = 100, 16 times** — ``wfem.hks`` (its own shift-invert block Lanczos) against pyFM
  (``TriMesh.process(k=100)`` + ``mesh_HKS``), geomfum (``laplacian.find_spectrum(100)`` +
  ``HeatKernelSignature``) and the scipy code both wrap (``eigsh(L, 100, B, sigma=-0.01)`` on
  libigl's operators + the formula ``Σ e^{−λt} φ²``), at the same automatic times;
* **K_t f** (one f, t = 0.01·A/4π, A the area) from (V, F) — ``wfem.HeatKernel(V, F).apply``
  (the fast exact method) against CRAM-16 in scipy (libigl's L and B, 8 complex SuperLU
  factorizations of tL − z_j B: the same kernel, error ≈ 1e−14) and
  ``scipy.sparse.linalg.expm_multiply`` on −t D⁻¹L (the lumped kernel, the only one it takes);
  plus ``apply`` alone on a kernel already built, and the max-norm difference of each result to
  wfem's (expm_multiply against wfem's lumped kernel).

Ratios are peer time / wfem time (> 1: wfem is faster). Everything runs on the same cores
(numpy/scipy's BLAS and wfem's rayon pool use all of them). Peers that cannot be imported are
reported as missing, never silently replaced; geomfum needs ``importlib.util`` imported first
(its 1.0.0 forgets to). Pinned versions: ``benches/peers/python-api-requirements.txt``.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util  # noqa: F401 - geomfum 1.0.0 uses importlib.util without importing it
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import wfem

# CRAM-16 (the table of shifted_solve::RationalApprox::cram(16)): one copy, in peers.py.
sys.path.insert(0, str(Path(__file__).resolve().parent))
from peers import CRAM16, CRAM16_C0  # noqa: E402

K_EIGS = 100
N_TIMES = 16


def optional(name: str):
    try:
        return importlib.import_module(name)
    except Exception:  # noqa: BLE001 - a peer that does not import is reported as missing
        return None


igl = optional("igl")
pp3d = optional("potpourri3d")
robust_laplacian = optional("robust_laplacian")


def best(fn, repeat):
    """(best wall time, last result)."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def auto_times(lam):
    """pyFM's auto_HKS times: geomspace(4 ln10/λ_max, 4 ln10/λ_2, T)."""
    nz = lam[lam > 1e-8 * lam.max()]
    return np.geomspace(4 * np.log(10) / lam.max(), 4 * np.log(10) / nz.min(), N_TIMES)


def igl_operators(V, F):
    return -igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL)


def scipy_hks(V, F, times):
    L, B = igl_operators(V, F)
    lam, phi = sla.eigsh(L.tocsc(), k=K_EIGS, M=B.tocsc(), sigma=-0.01, which="LM")
    return (phi**2) @ np.exp(-np.outer(lam, times))


def pyfm_hks(V, F):
    from pyFM.mesh import TriMesh
    from pyFM.signatures.HKS_functions import mesh_HKS

    m = TriMesh(V, F)
    m.process(k=K_EIGS, intrinsic=False, verbose=False)
    return mesh_HKS(m, N_TIMES, k=K_EIGS)


def geomfum_hks(V, F):
    from geomfum.descriptor.spectral import HeatKernelSignature
    from geomfum.shape import TriangleMesh

    m = TriangleMesh(V, F)
    m.laplacian.find_spectrum(spectrum_size=K_EIGS, set_as_basis=True)
    return HeatKernelSignature(n_domain=N_TIMES)(m)


def cram16(L, B, f, t):
    A = (t * L).astype(np.complex128).tocsc()
    Bc = B.astype(np.complex128).tocsc()
    Bf = B @ f
    g = CRAM16_C0 * f
    for (zr, zi), (cr, ci) in CRAM16:
        z, c = complex(zr, zi), complex(cr, ci)
        g = g + 2.0 * (c * sla.splu((A - z * Bc).tocsc()).solve(Bf.astype(np.complex128))).real
    return g


def expm_lumped(L, D, f, t):
    Dinv = sp.diags(1.0 / D.diagonal())
    return sla.expm_multiply((-t * (Dinv @ L)).tocsc(), f)


def meshes(corpus: Path | None):
    out = [("icosphere 10K", *wfem.generate.icosphere(5)), ("icosphere 41K", *wfem.generate.icosphere(6))]
    if corpus is not None:
        for name, rel in [
            ("TOSCA cat0", "tosca-bcicp-5k/TOSCA_Isometric/cat0.off"),
            ("spot", "odedstein-meshes/spot/spot.obj"),
            ("armadillo", "odedstein-meshes/armadillo/armadillo.obj"),
        ]:
            p = corpus / rel
            if p.exists():
                V, F = wfem.read_mesh(p)
                if wfem.validate(V, F).usable:
                    out.append((name, V, F))
    return out


def run_mesh(name, V, F, repeat):
    n = len(V)
    r: dict = {"mesh": name, "n": n}
    print(f"--- {name}: {n} vertices", file=sys.stderr, flush=True)

    # operators
    r["operators"] = {"wfem": best(lambda: wfem.operators(V, F), repeat)[0]}
    if igl:
        r["operators"]["libigl"] = best(lambda: igl_operators(V, F), repeat)[0]
    if pp3d:
        r["operators"]["potpourri3d"] = best(lambda: (pp3d.cotan_laplacian(V, F), pp3d.vertex_areas(V, F)), repeat)[0]
    if robust_laplacian:
        r["operators"]["robust_laplacian"] = best(lambda: robust_laplacian.mesh_laplacian(V, F), repeat)[0]

    # HKS, k = 100, the automatic times of the wfem spectrum (the same for every peer)
    t_w, (h_w, times) = best(lambda: wfem.hks(V, F, k=K_EIGS, num_times=N_TIMES, return_times=True), repeat)
    r["hks"] = {"wfem": t_w}
    if igl:
        t_s, h_s = best(lambda: scipy_hks(V, F, times), repeat)
        r["hks"]["scipy eigsh + formula"] = t_s
        r["hks_max_rel_diff_scipy"] = float(np.abs(h_s - h_w).max() / np.abs(h_w).max())
    for label, fn in [("pyFM", pyfm_hks), ("geomfum", geomfum_hks)]:
        try:
            r["hks"][label] = best(lambda: fn(V, F), repeat)[0]
        except Exception as e:  # noqa: BLE001 - reported, not hidden
            r["hks"][label] = None
            r.setdefault("missing", {})[label] = f"{type(e).__name__}: {e}"[:200]

    # K_t f from (V, F)
    L, B, D = wfem.operators(V, F)
    area = B.sum()
    t = 0.01 * area / (4 * np.pi)
    f = V[:, 0] + np.sin(3 * V[:, 1])
    t_we, g_w = best(lambda: wfem.HeatKernel(V, F).apply(f, t), repeat)
    K = wfem.HeatKernel(V, F)
    t_wa, _ = best(lambda: K.apply(f, t), repeat)
    r["heat"] = {"wfem (V, F → K_t f)": t_we, "wfem apply only": t_wa}
    if igl:
        t_c, g_c = best(lambda: cram16(*igl_operators(V, F), f, t), repeat)
        r["heat"]["scipy CRAM-16 (libigl L, B)"] = t_c
        r["heat_max_rel_diff_cram16"] = float(np.abs(g_c - g_w).max() / np.abs(f).max())
        t_e, g_e = best(lambda: expm_lumped(-igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_BARYCENTRIC), f, t), repeat)
        r["heat"]["scipy expm_multiply (lumped D)"] = t_e
        g_wl = wfem.HeatKernel(V, F, kernel="lumped").apply(f, t)
        r["heat_max_rel_diff_expm_vs_wfem_lumped"] = float(np.abs(g_e - g_wl).max() / np.abs(f).max())
    return r


def markdown(results):
    lines = []
    for section, title, ref in [
        ("operators", "Operators L, B (D)", "wfem"),
        ("hks", f"HKS, k = {K_EIGS}, {N_TIMES} times", "wfem"),
        ("heat", "One K_t f from (V, F)", "wfem (V, F → K_t f)"),
    ]:
        peers = []
        for r in results:
            for k in r[section]:
                if k not in peers:
                    peers.append(k)
        lines.append(f"\n**{title}** (seconds; ratio = peer / {ref})\n")
        lines.append("| mesh | n | " + " | ".join(peers) + " |")
        lines.append("|---|---|" + "---|" * len(peers))
        for r in results:
            w = r[section][ref]
            cells = []
            for p in peers:
                v = r[section].get(p)
                if v is None:
                    cells.append("—")
                elif p == ref:
                    cells.append(f"{v:.3f}")
                else:
                    cells.append(f"{v:.3f} ({v / w:.1f}×)")
            lines.append(f"| {r['mesh']} | {r['n']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def versions():
    out = {"python": platform.python_version(), "wfem": wfem.__version__}
    for dist in ["numpy", "scipy", "libigl", "potpourri3d", "robust_laplacian", "pyfmaps", "geomfum"]:
        try:
            from importlib.metadata import version

            out[dist] = version(dist)
        except Exception:  # noqa: BLE001
            out[dist] = None
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--meshes", type=Path, default=None)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--only", default=None, help="comma-separated mesh names")
    args = ap.parse_args()
    corpus = args.meshes or Path(os.environ.get("WFEM_MESHES", Path(__file__).resolve().parents[3] / "shared/data/meshes"))
    corpus = corpus if corpus.is_dir() else None
    todo = meshes(corpus)
    if args.only:
        keep = set(args.only.split(","))
        todo = [m for m in todo if m[0] in keep]
    results = [run_mesh(name, V, F, args.repeat) for name, V, F in todo]
    report = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform()}, "versions": versions(),
              "results": results}
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
    print(json.dumps(report["versions"]))
    print(markdown(results))


if __name__ == "__main__":
    main()

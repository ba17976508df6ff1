"""wfem's eigensolver for pyFM's functional maps: a drop-in for ``pyFM.mesh.TriMesh.process``.

pyFM computes every mesh's Laplace–Beltrami eigenpairs with scipy's shift-invert ``eigsh``,
which its maintainer names the bottleneck of the pipeline (pyFM #11). :func:`process` fills the
same attributes from wfem — the same operators (pyFM's cotangent, intrinsic or robust Laplacian
with the barycentric lumped mass), their eigenpairs by wfem's block Lanczos — so everything
after it (WKS descriptors, ``FunctionalMapping``, ZoomOut) runs unchanged::

    from pyFM.mesh import TriMesh
    import wfem.pyfm

    mesh = TriMesh("cat0.off", area_normalize=True, center=True)
    wfem.pyfm.process(mesh, k=150, intrinsic=True)   # instead of mesh.process(k=150, intrinsic=True)

The eigenvalues equal pyFM's to the eigensolver's tolerance; eigenvectors may differ in sign,
which functional maps do not see. ``pip install pyfmaps`` provides pyFM (``pip install pyFM`` is
an unrelated package).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ._mesh import operators
from ._spectral import Eigenbasis

__all__ = ["process", "operators_of"]


#: pyFM's own default of ``TriMesh.process(k)``, kept so that the drop-in is one.
PYFM_PROCESS_K = 200

def operators_of(mesh: Any, *, intrinsic: bool = False, robust: bool = False) -> tuple[sp.csc_matrix, sp.dia_matrix, str]:
    """pyFM's stiffness W (positive semidefinite), its barycentric lumped mass A and the name of
    its discretization, computed by wfem: ``"cotan"`` (pyFM's ``cotangent_weights`` and
    ``dia_area_mat``), ``"intrinsic"`` (robust_laplacian without mollification) or ``"robust"``
    (robust_laplacian, mollification 1e-5), chosen as ``TriMesh.compute_operators`` does."""
    V = np.asarray(mesh.vertices, dtype=float)
    faces = getattr(mesh, "faces", None)
    if faces is None or len(faces) == 0:
        robust = True  # pyFM forces the robust Laplacian on point clouds
    method = "robust" if robust else ("intrinsic" if intrinsic else "cotan")
    if faces is None or len(faces) == 0:
        L, _, D = operators(V)
    elif method == "cotan":
        L, _, D = operators(V, np.asarray(faces, dtype=np.int64))
    else:
        L, _, D = operators(
            V,
            np.asarray(faces, dtype=np.int64),
            laplacian="robust",
            mollify_factor=1e-5 if method == "robust" else 0.0,
        )
    return sp.csc_matrix(L), sp.diags(np.asarray(D.diagonal()), format="dia"), method


def process(mesh: Any, k: int = PYFM_PROCESS_K, *, intrinsic: bool = False, robust: bool = False, **_: Any) -> Any:
    """Fills ``mesh.stiffness``, ``mesh.mass``, ``mesh.eigenvalues`` (k,) and
    ``mesh.eigenvectors`` (n, k, mass-orthonormal) of a pyFM ``TriMesh`` from wfem, as
    ``mesh.process(k, intrinsic=, robust=)`` would, and returns the mesh. Other keywords of
    ``process`` (``skip_normals``, ``verbose``) are accepted and ignored."""
    W, A, method = operators_of(mesh, intrinsic=intrinsic, robust=robust)
    basis = Eigenbasis.from_operators(W, A, int(k))
    mesh.stiffness = W
    mesh.mass = A
    mesh.eigenvalues = np.asarray(basis.values)
    mesh.eigenvectors = np.asarray(basis.vectors)
    if hasattr(mesh, "_laplacian_method"):
        mesh._laplacian_method = method
    if hasattr(mesh, "_intrinsic"):
        mesh._intrinsic = method == "intrinsic"
    return mesh

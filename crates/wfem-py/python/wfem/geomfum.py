"""wfem's eigen step for geomfum: a drop-in for ``mesh.laplacian.find_spectrum``.

geomfum (the functional-map library of the geometric-deep-learning community) computes every
shape's Laplace–Beltrami eigenpairs with robust_laplacian's operators and scipy's shift-invert
``eigsh``. :func:`find_spectrum` fills the same objects from wfem — the same operators
(robust_laplacian's intrinsic Delaunay Laplacian with mollification 1e-5 and its lumped mass,
geomfum's default ``"robust"`` finder) and their eigenpairs by wfem's block Lanczos — so that
every descriptor, functional map and refinement of geomfum after it runs unchanged::

    from geomfum.shape import TriangleMesh
    import wfem.geomfum

    mesh = TriangleMesh.from_file("cat0.off")
    wfem.geomfum.find_spectrum(mesh, spectrum_size=100)  # instead of mesh.laplacian.find_spectrum(100)

The pieces plug into geomfum's own classes too: :class:`MeshLaplacianFinder` is a Laplacian
finder (``mesh.laplacian.find(wfem.geomfum.MeshLaplacianFinder())``) and :class:`Eigsh` an
eigensolver (``LaplacianSpectrumFinder(eig_solver=wfem.geomfum.Eigsh(100))``).

Eigenvalues equal geomfum's to the eigensolver's tolerance; eigenvectors may differ in sign,
which functional maps do not see. geomfum needs ``torch`` only for its learning modules: ``pip
install --no-deps geomfum gsops`` beside numpy, scipy, scikit-learn, meshio, pyfmaps and
robust-laplacian is enough for this module.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ._errors import InvalidInputError
from ._mesh import operators
from ._spectral import Eigenbasis

__all__ = ["find_spectrum", "MeshLaplacianFinder", "Eigsh", "GEOMFUM_SPECTRUM_SIZE", "GEOMFUM_MOLLIFY_FACTOR"]

#: geomfum's own default of ``find_spectrum(spectrum_size)``, kept so that the drop-in is one.
GEOMFUM_SPECTRUM_SIZE = 100
#: geomfum's (and robust_laplacian's) default intrinsic mollification.
GEOMFUM_MOLLIFY_FACTOR = 1e-5


class MeshLaplacianFinder:
    """geomfum's ``"robust"`` Laplacian finder computed by wfem: the intrinsic Delaunay stiffness
    (positive semidefinite) and lumped mass of robust_laplacian, as ``scipy.sparse`` CSC
    matrices. ``mollify_factor=0`` gives the intrinsic Delaunay Laplacian without mollification."""

    def __init__(self, mollify_factor: float = GEOMFUM_MOLLIFY_FACTOR):
        self.mollify_factor = mollify_factor

    def __call__(self, shape: Any) -> tuple[sp.csc_matrix, sp.csc_matrix]:
        V = np.asarray(shape.vertices, dtype=float)
        F = np.asarray(shape.faces, dtype=np.int64)
        L, _, D = operators(V, F, laplacian="robust", mollify_factor=float(self.mollify_factor))
        return sp.csc_matrix(L), sp.diags(np.asarray(D.diagonal())).tocsc()


class Eigsh:
    """geomfum's eigensolver interface (``spectrum_size``; ``__call__(A, M) -> (vals, vecs)``,
    the smallest eigenpairs of ``A v = λ M v``, ascending, M-orthonormal) by wfem's shift-invert
    block Lanczos instead of scipy's ``eigsh``."""

    def __init__(self, spectrum_size: int = GEOMFUM_SPECTRUM_SIZE):
        self.spectrum_size = spectrum_size

    def __call__(self, A: Any, M: Any = None) -> tuple[np.ndarray, np.ndarray]:
        if M is None:
            raise InvalidInputError("wfem.geomfum.Eigsh needs the mass matrix M (the generalised problem A v = λ M v)")
        basis = Eigenbasis.from_operators(sp.csc_matrix(A), sp.csc_matrix(M), int(self.spectrum_size))
        return np.asarray(basis.values), np.asarray(basis.vectors)


def find_spectrum(
    mesh: Any,
    spectrum_size: int = GEOMFUM_SPECTRUM_SIZE,
    *,
    set_as_basis: bool = True,
    mollify_factor: float = GEOMFUM_MOLLIFY_FACTOR,
) -> tuple[np.ndarray, np.ndarray]:
    """Fills a geomfum ``TriangleMesh``'s Laplacian (stiffness, mass) and its eigenbasis from
    wfem, as ``mesh.laplacian.find_spectrum(spectrum_size, set_as_basis=)`` would with geomfum's
    defaults, and returns ``(eigenvalues, eigenvectors)`` as geomfum does. Operators already on
    the mesh are kept (as geomfum does) unless they are missing."""
    from geomfum.laplacian import LaplacianSpectrumFinder

    if isinstance(spectrum_size, bool) or not isinstance(spectrum_size, (int, np.integer)) or spectrum_size < 1:
        raise InvalidInputError(f"spectrum_size must be a positive integer, got {spectrum_size!r}")
    mesh.laplacian.find(MeshLaplacianFinder(mollify_factor))
    finder = LaplacianSpectrumFinder(eig_solver=Eigsh(int(spectrum_size)))
    return mesh.laplacian.find_spectrum(laplacian_spectrum_finder=finder, set_as_basis=set_as_basis, recompute=True)

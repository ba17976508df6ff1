"""wfem — the wFEM heat kernel on triangle meshes, from Python.

The heat kernel ``K_t = exp(−t B⁻¹L)`` applied to functions **without computing the spectrum**
(exact to ≈1e−12), diffusion distances, heat kernel signatures (both conventions), SI-HKS,
DHK1–3, feature points, the feature-driven approximation, vocabularies and bags of features,
retrieval metrics and an embedded SQLite retrieval index; ``wfem.batch`` runs descriptors and
bags over a collection on any ``concurrent.futures.Executor`` (e.g. Dask).

Conventions (those of libigl): ``V`` float64 (n, 3), ``F`` int (m, 3); any object with
``.vertices``/``.faces`` (trimesh, pyFM) works in place of ``V, F``. Sparse operators are
``scipy.sparse.csc_matrix`` with **L positive semidefinite** (positive diagonal,
``L = −igl.cotmatrix(V, F)``); the paper prints the opposite sign. Equation numbers refer to
Patanè & Falcidieno, "wFEM heat kernel: discretization and applications to shape analysis and
retrieval".

Quick start::

    import wfem
    V, F = wfem.generate.bumpy(4)             # or wfem.read_mesh("/path/to/cat.off")
    L, B, D = wfem.operators(V, F)            # L = −igl.cotmatrix
    K = wfem.HeatKernel(V, F)                 # wFEM kernel, exact fast method
    smooth = K.apply(V[:, 2], 1e-3, time_unit="area")  # K_t f at t = 1e-3·area
    h = wfem.hks(V, F, times=[1e-3, 1e-2], time_unit="area")  # (n, 2)
"""

from __future__ import annotations

from . import _wfem
from ._errors import (
    ConvergenceError,
    IllConditionedError,
    InternalError,
    InvalidInputError,
    InvalidTypeError,
    MeshError,
    MeshFileError,
    RetrievalError,
    SolverError,
    StoreError,
    RefusedShapesWarning,
    TimeWarning,
    WfemError,
)
from ._choices import choices
from ._heat import (
    APPROX_COEFFICIENTS,
    APPROX_SAMPLINGS,
    APPROX_NOISE_RULES,
    MASSES,
    METHODS,
    ApproximationWarning,
    DiffusionDistance,
    HeatKernel,
)
from ._geodesic import GEODESIC_METHODS, GeodesicSolver, GeodesicWarning, geodesic_distance
from ._cloud import DEFAULT_NEIGHBORS, LAPLACIANS, cloud_operators, read_points
from ._mesh import (
    RepairReport,
    ValidationReport,
    extrema,
    fill_holes,
    mesh_stats,
    operators,
    read_mesh,
    repair,
    validate,
)
from ._volume import VolumeReport, read_volume, repair_volume, validate_volume
from ._retrieval import (
    CheckReport,
    DESCRIPTORS,
    PAPER_DESCRIPTORS,
    Hit,
    VectorStore,
    RetrievalIndex,
    Vocabulary,
    average_precision,
    descriptor,
    descriptors,
    evaluate,
    kmeans,
    l1_distance,
    mean_average_precision,
    pairwise_l1,
    sparse_features,
)
from ._spectral import GLOBAL_KINDS, HKS_CONVENTIONS, HKS_METHODS, Eigenbasis, eigenbasis, hks, shape_dna, sihks, wks
from . import generate

__version__: str = _wfem.__version__

#: Old names kept for one release (issue #37): reading one warns and gives the new one.
_OLD_NAMES = {"KERNELS": "MASSES", "IndexStore": "VectorStore"}


def __getattr__(name: str):
    if name in _OLD_NAMES:
        import warnings

        new = _OLD_NAMES[name]
        warnings.warn(f"wfem.{name} is the old name of wfem.{new}; it will be removed", DeprecationWarning, stacklevel=2)
        return globals()[new]
    raise AttributeError(f"module 'wfem' has no attribute {name!r}")

#: Largest mesh for the dense eigendecomposition (``k=None``, ``method="dense"``).
DENSE_MAX_VERTICES: int = _wfem.DENSE_MAX_VERTICES

__all__ = [
    # meshes and operators
    "read_mesh",
    "read_points",
    "read_volume",
    "validate_volume",
    "repair_volume",
    "VolumeReport",
    "cloud_operators",
    "LAPLACIANS",
    "DEFAULT_NEIGHBORS",
    "validate",
    "repair",
    "fill_holes",
    "mesh_stats",
    "operators",
    "extrema",
    "ValidationReport",
    "RepairReport",
    "generate",
    # heat kernel
    "HeatKernel",
    "DiffusionDistance",
    "METHODS",
    "MASSES",
    "choices",
    "APPROX_COEFFICIENTS",
    "APPROX_SAMPLINGS",
    "APPROX_NOISE_RULES",
    "ApproximationWarning",
    # geodesic distances
    "GeodesicSolver",
    "geodesic_distance",
    "GEODESIC_METHODS",
    "GeodesicWarning",
    # spectrum and signatures
    "Eigenbasis",
    "eigenbasis",
    "hks",
    "sihks",
    "wks",
    "shape_dna",
    "HKS_CONVENTIONS",
    "HKS_METHODS",
    "GLOBAL_KINDS",
    # retrieval
    "DESCRIPTORS",
    "PAPER_DESCRIPTORS",
    "descriptors",
    "descriptor",
    "sparse_features",
    "Vocabulary",
    "kmeans",
    "l1_distance",
    "pairwise_l1",
    "evaluate",
    "mean_average_precision",
    "average_precision",
    "VectorStore",
    "RetrievalIndex",
    "Hit",
    "CheckReport",
    # errors
    "WfemError",
    "InvalidInputError",
    "InvalidTypeError",
    "MeshError",
    "MeshFileError",
    "RetrievalError",
    "SolverError",
    "ConvergenceError",
    "IllConditionedError",
    "StoreError",
    "InternalError",
    "RefusedShapesWarning",
    "TimeWarning",
    "DENSE_MAX_VERTICES",
    "__version__",
]

# Every error out of the public API is a WfemError (bare OverflowError/TypeError of argument
# conversions included): see _guard.py.
from ._guard import guard_namespace as _guard_namespace  # noqa: E402

_guard_namespace(globals(), __all__)
_guard_namespace(vars(generate), generate.__all__)

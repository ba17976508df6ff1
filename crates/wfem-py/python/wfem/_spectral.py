"""Eigenpairs ``L x = λ M x`` (paper, Eq. (4)) and the heat kernel signatures built on them."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _choices, _wfem
from ._arrays import as_float_array, as_mesh, as_sparse, as_vector, points_of
from ._errors import InvalidInputError, warn_user

#: The library's default parameters by group (one place: the Rust crates).
_DEFAULTS = _wfem.DEFAULTS

__all__ = [
    "Eigenbasis", "eigenbasis", "hks", "sihks", "wks", "shape_dna", "HKS_CONVENTIONS", "HKS_METHODS", "GLOBAL_KINDS",
]

#: The two HKS conventions, named by what they are (see :func:`hks`).
HKS_CONVENTIONS = _choices.names("convention")
#: How :func:`hks` evaluates the signature.
HKS_METHODS = _choices.names("hks_method")
#: The global signatures of :func:`shape_dna` (``kind=``).
GLOBAL_KINDS = _choices.names("global_kind")


class Eigenbasis:
    """Eigenpairs of ``L x_i = λ_i M x_i`` (paper, Eq. (4)), λ ascending, with **M-orthonormal**
    eigenvectors ``Xᵀ M X = I`` (B-orthonormal for the wFEM kernel). L is positive
    semidefinite (= −igl.cotmatrix), so λ ≥ 0; λ₁ ≈ 0 with the constant eigenvector on a
    connected mesh.

    Build with :func:`eigenbasis` (from a mesh) or :meth:`from_operators`.
    """

    _b: Any

    def __init__(self, inner: Any) -> None:
        self._b = inner

    @classmethod
    def from_operators(
        cls,
        L: Any,
        M: Any,
        k: int | None = None,
        *,
        tol: float = _DEFAULTS["eigen"]["tol"],
        block_size: int = _DEFAULTS["eigen"]["block_size"],
        max_dim: int | None = None,
        seed: int = _DEFAULTS["eigen"]["seed"],
        shift: float | None = None,
        max_restarts: int = _DEFAULTS["eigen"]["max_restarts"],
    ) -> "Eigenbasis":
        """The k smallest eigenpairs of any (L PSD = −igl.cotmatrix, M SPD) by shift-invert
        block Lanczos, or all of them (``k=None``, dense, n ≤ 5000)."""
        return cls(
            _wfem.Eigenbasis.from_operators(
                as_sparse(L, "L"), as_sparse(M, "M"), k, tol, block_size, max_dim, seed, shift, max_restarts
            )
        )

    def __repr__(self) -> str:
        return f"Eigenbasis(n={self._b.n}, k={self._b.k})"

    def __len__(self) -> int:
        return int(self._b.k)

    @property
    def values(self) -> np.ndarray:
        """Eigenvalues λ (k,), ascending."""
        return np.asarray(self._b.values)

    @property
    def vectors(self) -> np.ndarray:
        """Eigenvectors X (n, k), M-orthonormal: ``X.T @ M @ X = I``."""
        return np.asarray(self._b.vectors)

    def project(self, f: Any) -> np.ndarray:
        """Coefficients ``c = Xᵀ M f`` = ``⟨f, x_i⟩_M`` (paper, Eq. (5)); f (n,) → (k,), (n, m) → (k, m)."""
        a = as_float_array(f, "f", (1, 2))
        c = self._b.project(a.reshape(a.shape[0], -1))
        return c[:, 0] if a.ndim == 1 else c

    def reconstruct(self, c: Any) -> np.ndarray:
        """``X c``: the function with coefficients c (k,) or (k, m)."""
        a = as_float_array(c, "c", (1, 2))
        out = self._b.reconstruct(a.reshape(a.shape[0], -1))
        return out[:, 0] if a.ndim == 1 else out

    def heat(self, f: Any, t: float) -> np.ndarray:
        """The truncated heat kernel ``F_k = X_k e^{−tΛ_k} X_kᵀ M f`` (paper, Eq. (8)); exact
        when k = n. Its error, about e^{−tλ_{k+1}}‖f‖, is large at small t (Fig. 3)."""
        return np.asarray(self._b.heat(as_vector(f, "f"), float(t)))

    def inverse_heat(self, f: Any, t: float) -> tuple[np.ndarray, dict[str, float]]:
        """``K_{−t} f`` truncated to the basis, ``X_k e^{+tΛ_k} X_kᵀ M f`` (Sect. 4), with a report
        of what was dropped (``relative_dropped``) and the amplification e^{tλ_k}."""
        g, r = self._b.inverse_heat(as_vector(f, "f"), float(t))
        return np.asarray(g), dict(r)

    def reproducing_kernel(self, v: Any, t: float) -> tuple[np.ndarray, dict[str, float]]:
        """The reproducing kernel ``H_t v = X D_{−t} Xᵀ v`` (Prop. 3.1 B, Eq. (15), (20)),
        truncated to the basis, with its truncation report."""
        g, r = self._b.reproducing_kernel(as_vector(v, "v"), float(t))
        return np.asarray(g), dict(r)

    def hks(
        self,
        times: Any = None,
        *,
        num_times: int = _wfem.DEFAULT_NUM_TIMES,
        convention: str | None = None,
        scaled: bool = False,
        normalization: str | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """HKS of this basis: ``(values (n, T), times (T,))``; see :func:`hks`."""
        t = None if times is None else [float(x) for x in as_vector(np.atleast_1d(times), "times")]
        values, used = self._b.hks(t, num_times, convention, scaled, normalization)
        return np.asarray(values), np.asarray(used)

    def wks(self, num_energies: int = _wfem.DEFAULT_ENERGIES) -> tuple[np.ndarray, np.ndarray]:
        """WKS of this basis: ``(values (n, N), log-energies (N,))``; see :func:`wks`."""
        values, energies, _ = self._b.wks(int(num_energies))
        return np.asarray(values), np.asarray(energies)

    def shape_dna(
        self,
        m: int = _DEFAULTS["global"]["eigenvalues"],
        *,
        kind: str | None = None,
        measure: float | None = None,
        dimension: int = _DEFAULTS["global"]["dimension"],
    ) -> np.ndarray:
        """The global signature of the first ``m`` nonzero eigenvalues of this basis (Shape-DNA
        by default); ``measure`` the area (``dimension=2``) or volume (``dimension=3``) of the
        shape, by default ``1ᵀM1``; see :func:`shape_dna`."""
        return np.asarray(
            self._b.global_signature(int(m), kind, None if measure is None else float(measure), int(dimension))
        )

    def sihks(
        self,
        *,
        alpha: float = _DEFAULTS["sihks"]["alpha"],
        tau_min: float = _DEFAULTS["sihks"]["tau_min"],
        tau_max: float = _DEFAULTS["sihks"]["tau_max"],
        tau_step: float = _DEFAULTS["sihks"]["tau_step"],
        time_unit: float = _DEFAULTS["sihks"]["time_unit"],
        num_frequencies: int = _DEFAULTS["sihks"]["num_frequencies"],
        convention: str | None = None,
    ) -> np.ndarray:
        """SI-HKS of this basis (n, num_frequencies); see :func:`sihks`."""
        return np.asarray(
            self._b.sihks(alpha, tau_min, tau_max, tau_step, time_unit, num_frequencies, convention)
        )



def eigenbasis(
    V: Any,
    F: Any = None,
    k: int | None = _DEFAULTS["eigen"]["k"],
    *,
    mass: str | None = None,
    tol: float = _DEFAULTS["eigen"]["tol"],
    block_size: int = _DEFAULTS["eigen"]["block_size"],
    max_dim: int | None = None,
    seed: int = _DEFAULTS["eigen"]["seed"],
    shift: float | None = None,
    max_restarts: int = _DEFAULTS["eigen"]["max_restarts"],
    kernel: str | None = None,
    lumped: str | None = None,
    laplacian: str | None = None,
    n_neighbors: int | None = None,
) -> Eigenbasis:
    """The k smallest eigenpairs of ``L x = λ M x`` on a mesh (paper, Eq. (4)), M = B for the
    wFEM kernel (D for a lumped ``mass``, I for ``"identity"``); ``k=None`` gives all n (dense,
    n ≤ 5000). Shift-invert thick-restart block Lanczos with one sparse Cholesky of ``L − σM``:
    a basis of at most ``max_dim`` vectors (default max(2k, k + 4b) + b), restarted at most
    ``max_restarts`` times (then ``ConvergenceError`` carrying the converged pairs)."""
    mass = _choices.mass_of(mass, kernel, lumped)
    from ._volume import tets_of, volume_pencil

    tets = tets_of(V, F)
    P = None if tets is not None else points_of(V, F)
    if tets is not None or P is not None:
        from ._cloud import cloud_pencil

        if tets is not None:
            L, M = volume_pencil(*tets, mass)
        else:
            L, M = cloud_pencil(P, mass, laplacian=laplacian, n_neighbors=n_neighbors)
        return Eigenbasis.from_operators(
            L, M, k, tol=tol, block_size=block_size, max_dim=max_dim,
            seed=seed, shift=shift, max_restarts=max_restarts,
        )
    v, f = as_mesh(V, F)
    return Eigenbasis(
        _wfem.Eigenbasis.from_mesh(v, f, k, mass, tol, block_size, max_dim, seed, shift, max_restarts, laplacian)
    )


def hks(
    V: Any,
    F: Any = None,
    times: Any = None,
    *,
    k: int = _DEFAULTS["eigen"]["k"],
    num_times: int | None = None,
    convention: str | None = None,
    scaled: bool = False,
    normalization: str | None = None,
    mass: str | None = None,
    basis: Eigenbasis | None = None,
    method: str | None = None,
    return_times: bool = False,
    exact: bool = False,
    kernel: str | None = None,
    time_unit: str | None = None,
    laplacian: str | None = None,
    n_neighbors: int | None = None,
) -> Any:
    """The heat kernel signature h(i, t) at every vertex and time, shape (n, T): the same
    computation as ``wfem hks`` (one library routine).

    ``V, F`` is a mesh, or ``V`` alone a point cloud (n, 3) (operators from its ``n_neighbors``,
    default 30, nearest neighbours); ``laplacian=`` chooses the Laplacian of a mesh
    (:data:`wfem.LAPLACIANS`; the robust one for non-manifold or degenerate meshes).

    In one of two conventions (``convention=``, :data:`HKS_CONVENTIONS`):

    * ``"kernel-value"`` (default; Sun, Ovsjanikov & Guibas 2009, pyFM):
      ``h(i, t) = Σ_k e^{−λ_k t} x_k(i)²`` = diag(X D_t Xᵀ), the continuous kernel's value
      k_t(p_i, p_i) (units 1/area);
    * ``"operator-diagonal"`` (the paper): ``h(i, t) = (X D_t Xᵀ B)_ii``, the diagonal
      of the wFEM heat operator of Eq. (6); dimensionless, sums to the heat trace.

    Args:
        times: explicit positive times; ``None`` = ``num_times`` (default 16) times log-spaced
            between ``4 ln10/λ_max`` and ``4 ln10/λ_2`` (pyFM's ``auto_HKS``).
        k: eigenpairs of the truncated sum (ignored when ``basis`` is given).
        scaled: divide each column by the heat trace ``Σ_k e^{−λ_k t}`` (pyFM ``scaled=True``).
        normalization: ``None``, ``"max-eigenvalue"`` (λ/λ_max, DHK3) or ``"area"`` (λ·A).
        mass: the kernel's mass (default ``"consistent"``, the wFEM kernel; ``"voronoi"`` gives
            the paper's DHK1).
        basis: a precomputed :class:`Eigenbasis` of the same mass to reuse.
        method: ``"auto"`` (default): per time, the truncated sum where its truncation error
            (Weyl-law estimate: the omitted eigenvalues grow like ``λ_k j/k``) is below 1e−3, and
            the exact diagonal of the kernel (selected inversion, :meth:`HeatKernel.diagonal`)
            at the smaller times where it is not; ``"exact"``: the exact diagonal at every time
            (no eigenpairs with explicit ``times``); ``"spectral"``: the truncated sum only
            (pyFM's HKS). ``scaled`` and ``normalization`` keep the spectral sum.
        return_times: also return the times used (in the mesh's units).
        time_unit: the unit of ``times``: ``"absolute"`` (default), ``"area"`` (t = τ·A) or
            ``"edge"`` (t = τ·ℓ̄², potpourri3d's convention); see :meth:`HeatKernel.apply`.
        exact, kernel: older spellings of ``method="exact"`` and ``mass=`` (DeprecationWarning).

    Returns:
        (n, T) array, or ``(values, times)`` with ``return_times=True``.
    """
    import warnings

    if exact:
        warn_user("exact=True is now method='exact'", DeprecationWarning)
        method = _wfem.canonical("hks_method", "exact") if method is None else method
    mass = _choices.mass_of(mass, kernel, None)
    from ._volume import tets_of

    if tets_of(V, F) is not None:
        # A volume: the truncated sum of its eigenbasis (the exact diagonal is for surfaces).
        if method is not None or time_unit is not None or laplacian is not None:
            raise InvalidInputError(
                "on a volume hks takes times in absolute units and the spectral sum (method, time_unit, laplacian not given)",
                "InvalidParameter",
                name="method" if method is not None else "time_unit" if time_unit is not None else "laplacian",
            )
        b = basis if basis is not None else eigenbasis(V, F, k, mass=mass)
        kw = {} if num_times is None else {"num_times": num_times}
        hv, ht = b.hks(times, convention=convention, scaled=scaled, normalization=normalization, **kw)
        return (hv, ht) if return_times else hv
    P = points_of(V, F)
    if P is not None:
        v, f = P, None
    else:
        v, f = as_mesh(V, F)
    t = None if times is None else [float(x) for x in as_vector(np.atleast_1d(times), "times")]
    cloud_unit = None
    if t is not None and time_unit is not None:
        if f is None:
            # Measured on the cloud's neighbourhood mesh once its operators are built.
            cloud_unit = time_unit
        else:
            unit = float(_wfem.mesh_time_unit(v, f, time_unit))
            t = [x * unit for x in t]
    values, used, _, _ = _wfem.mesh_hks(
        v, f, t, num_times, k, mass, method, convention, scaled, normalization,
        None if basis is None else basis._b, laplacian=laplacian, n_neighbors=n_neighbors,
        cloud_time_unit=cloud_unit,
    )
    h = np.asarray(values)
    return (h, np.asarray(used)) if return_times else h


def sihks(
    V: Any,
    F: Any = None,
    *,
    k: int = _DEFAULTS["eigen"]["k"],
    alpha: float = _DEFAULTS["sihks"]["alpha"],
    tau_min: float = _DEFAULTS["sihks"]["tau_min"],
    tau_max: float = _DEFAULTS["sihks"]["tau_max"],
    tau_step: float = _DEFAULTS["sihks"]["tau_step"],
    time_unit: float = _DEFAULTS["sihks"]["time_unit"],
    num_frequencies: int = _DEFAULTS["sihks"]["num_frequencies"],
    convention: str | None = None,
    mass: str | None = None,
    basis: Eigenbasis | None = None,
    kernel: str | None = None,
) -> np.ndarray:
    """The scale-invariant HKS of Bronstein & Kokkinos (CVPR 2010), shape (n, num_frequencies).

    ``log h(x, t₀α^τ)`` sampled for τ = τ_min, τ_min + Δτ, …, τ_max, differentiated in τ (removes
    the additive −2 log β of a scaling by β) and Fourier-transformed (the modulus removes the
    shift in τ); the first ``num_frequencies`` magnitudes are kept. Choose the window (``time_unit``
    t₀, ``tau_*``) so that it covers t·λ_max ≪ 1 to t·λ_2 ≫ 1 for your units.
    """
    if basis is None:
        basis = eigenbasis(V, F, k, mass=_choices.mass_of(mass, kernel, None))
    return basis.sihks(
        alpha=alpha,
        tau_min=tau_min,
        tau_max=tau_max,
        tau_step=tau_step,
        time_unit=time_unit,
        num_frequencies=num_frequencies,
        convention=convention,
    )


def wks(
    V: Any = None,
    F: Any = None,
    *,
    num_energies: int = _wfem.DEFAULT_ENERGIES,
    k: int = _DEFAULTS["eigen"]["k"],
    mass: str | None = None,
    basis: Any = None,
    laplacian: str | None = None,
    n_neighbors: int | None = None,
    return_energies: bool = False,
) -> Any:
    """The wave kernel signature (Aubry, Schlickewei & Cremers 2011) at every vertex, (n, N):

    ``WKS(x, e) = Σ_k C_k(e) φ_k(x)² / Σ_k C_k(e)``, ``C_k(e) = exp(−(e − log λ_k)²/2σ²)``

    over the nonzero eigenvalues (above 1e−8·λ_max) with M-orthonormal eigenvectors, at the
    energies of pyFM's ``auto_WKS`` and geomfum's ``WaveKernelSignature``: ``num_energies`` (N)
    log-energies from log λ_first (the first nonzero eigenvalue) to log λ_max, σ = 7·range/N,
    both ends trimmed by 2σ — the same values as ``pyFM.signatures.WKS_functions.mesh_WKS`` on
    the same eigenpairs.

    Args:
        V, F: a mesh (or V alone a point cloud); its ``k`` eigenpairs of the kernel of ``mass``
            (default ``"consistent"``, the wFEM kernel; ``"barycentric"`` is pyFM's spectrum).
        basis: an :class:`Eigenbasis`, or a pair ``(eigenvalues (k,), eigenvectors (n, k))``
            (e.g. pyFM's ``mesh.eigenvalues, mesh.eigenvectors``) instead of V, F.
        return_energies: also return the log-energies.
    """
    if basis is None:
        if V is None:
            raise InvalidInputError("give a mesh (V, F), a point cloud or basis=", "Missing", name="V")
        basis = eigenbasis(V, F, k, mass=mass, laplacian=laplacian, n_neighbors=n_neighbors)
    if isinstance(basis, Eigenbasis):
        values, energies = basis.wks(num_energies)
    else:
        try:
            evals, evecs = basis
        except (TypeError, ValueError):
            raise InvalidInputError(
                "basis must be an Eigenbasis or a pair (eigenvalues, eigenvectors)", "Invalid", name="basis"
            ) from None
        lam = [float(x) for x in as_vector(np.asarray(evals, dtype=float).ravel(), "eigenvalues")]
        vec = np.ascontiguousarray(np.asarray(evecs, dtype=float))
        v, e, _ = _wfem.eigenpairs_wks(lam, vec, int(num_energies))
        values, energies = np.asarray(v), np.asarray(e)
    return (values, energies) if return_energies else values


def shape_dna(
    V: Any,
    F: Any = None,
    m: int = _DEFAULTS["global"]["eigenvalues"],
    *,
    kind: str | None = None,
    mass: str | None = None,
    basis: Eigenbasis | None = None,
    return_eigenvalues: bool = False,
) -> Any:
    """Shape-DNA (Reuter, Wolter & Peinecke 2006) of a surface (V, F) or a solid (V, T): the first
    ``m`` nonzero eigenvalues of ``L x = λ M x`` normalised by Weyl's law in the shape's
    dimension, ``g_i = λ_i / λ_i^Weyl`` ≈ 1 — ``λ_i A/(4πi)`` on a surface of area A,
    ``λ_i V^{2/3}/(6π²i)^{2/3}`` in a solid of volume V — so it is invariant to scale.

    ``kind`` (:data:`GLOBAL_KINDS`) picks another global signature of the same eigenpairs:
    ``ln(λ_i μ^{2/d})``, or the histogram of biharmonic distances. ``basis`` reuses an
    :class:`Eigenbasis` of at least m + 1 pairs. Returns ``g`` (m,), or ``(g, λ₀…λ_m)`` with
    ``return_eigenvalues``.
    """
    from ._volume import tets_of, validate_volume

    tets = tets_of(V, F)
    if basis is None:
        basis = eigenbasis(V, F, int(m) + 1, mass=mass)
    if tets is not None:
        # The geometry's volume, whatever the kernel's mass.
        g = basis.shape_dna(m, kind=kind, measure=validate_volume(*tets).volume, dimension=3)
    else:
        g = basis.shape_dna(m, kind=kind)
    return (g, basis.values[: int(m) + 1]) if return_eigenvalues else g

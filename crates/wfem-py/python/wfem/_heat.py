"""The wFEM heat kernel ``K_t = exp(−t M⁻¹L) = X D_t Xᵀ M`` (paper, Eq. (6)) without the spectrum."""

from __future__ import annotations

import warnings
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp

from . import _choices, _wfem
from ._errors import InvalidInputError, TimeWarning, warn_user
from ._arrays import as_float_array, as_indices, as_mesh, as_sparse, as_times, as_vector, points_of, to_csc

#: The library's default parameters by group (one place: the Rust crates).
_DEFAULTS = _wfem.DEFAULTS

__all__ = [
    "HeatKernel",
    "DiffusionDistance",
    "METHODS",
    "MASSES",
    "APPROX_COEFFICIENTS",
    "APPROX_SAMPLINGS",
    "APPROX_NOISE_RULES",
    "ApproximationWarning",
]

#: Names accepted by ``method=`` (the library's registry; aliases are accepted too).
METHODS = _choices.names("method")
#: Names accepted by ``mass=`` (paper, Table 1): which mass M the kernel exp(−t M⁻¹L) uses.
MASSES = _choices.names("mass")
#: Names accepted by ``feature_approximation(coefficients=)``, default first (the library's registry).
APPROX_COEFFICIENTS = _choices.names("coefficients")
#: Names accepted by ``feature_approximation(sampling=)``, default first (the library's registry).
APPROX_SAMPLINGS = _choices.names("sampling")
#: Names accepted by ``feature_approximation(noise=)``, default first (the library's registry).
APPROX_NOISE_RULES = _choices.names("noise")


class ApproximationWarning(UserWarning):
    """:meth:`HeatKernel.feature_approximation` stays farther than 3 % of the range from f at
    every scale; the message names the option to change."""


class HeatKernel:
    """The heat kernel of a triangle mesh, built once and applied to many functions and times.

    ``K_t = exp(−t M⁻¹L) = X D_t Xᵀ M``, ``D_t = diag(e^{−λ_i t})`` (paper, Eq. (6)), where
    ``L x_i = λ_i M x_i``. **L is the cotangent stiffness, symmetric positive semidefinite**
    (positive diagonal, ``L @ 1 = 0``; ``L = −igl.cotmatrix(V, F)``), and M the kernel's mass
    (``mass=``, :data:`MASSES`; ``wfem.choices()["mass"]`` has the help of each):

    * ``"consistent"`` (default; alias ``"wfem"``): the consistent mass B, the paper's wFEM kernel;
    * ``"barycentric"`` (alias ``"lumped"``): the diagonal lumped mass D of Eq. (7), the kernel
      of most libraries; ``"voronoi"``: D of mixed Voronoi areas (the paper's DHK1 kernel);
    * ``"identity"`` (alias ``"linear"``): M = I, the linear FEM kernel ``X D_t Xᵀ``.

    Methods (``method=``):

    * ``"fast"`` (default): shift-and-invert rational Krylov on (M + γtL)⁻¹M, one real sparse
      Cholesky per t; exact to ≈1e−12 relative. No spectrum.
    * ``"rational"``: the paper's Chebyshev rational method (Eq. (11)–(13)),
      ``K_t f ≈ c₀f + 2 Re Σ_j c_j (tL − z_j M)⁻¹ M f``; ``degree`` (default 16, error
      ≈ 9.3⁻ᵈᵉᵍʳᵉᵉ, Eq. (14)) and ``backend`` ("ldlt", "lu", "minres", "multishift").
    * ``"spectral"``: the truncated sum over the ``k`` smallest eigenpairs (Eq. (8)); its error
      e^{−tλ_{k+1}} is large at small t.
    * ``"dense"``: all eigenpairs (n ≤ 5000), exact to rounding.
    * ``"taylor"`` (Eq. (9)) and ``"backward-euler"``: first-order steps, for comparison only.

    Args:
        V, F: vertices (n, 3) and triangles (m, 3), or one object with ``.vertices``/``.faces``;
            or a **point cloud** P (n, 3) without F (operators from the ``n_neighbors``
            nearest neighbours, :func:`wfem.cloud_operators`).
        laplacian: ``"cotan"`` (default for meshes) or ``"robust"`` (intrinsic Delaunay L of the
            tufted cover; for non-manifold or degenerate meshes; names in ``wfem.LAPLACIANS``).

    ``kernel=`` and ``lumped=`` are the older spellings of ``mass=`` (DeprecationWarning).

    Raises:
        MeshError: the mesh cannot be assembled (names the face or vertex).
        InvalidInputError: an unknown mass/method or a bad option.

    Example::

        K = wfem.HeatKernel(V, F)              # wFEM kernel, fast exact method
        g = K.apply(f, 0.01)                   # K_t f, shape of f
        G = K.apply(f, [0.01, 0.1, 1.0])       # (3, n): one factorization per t, all columns
    """

    _k: Any

    def __init__(
        self,
        V: Any,
        F: Any = None,
        mass: str | None = None,
        method: str | None = None,
        *,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
        kernel: str | None = None,
        lumped: str | None = None,
        laplacian: str | None = None,
        n_neighbors: int | None = None,
    ) -> None:
        mass = _choices.mass_of(mass, kernel, lumped)
        from ._volume import tets_of

        tets = tets_of(V, F)
        if tets is not None:
            if laplacian is not None:
                raise InvalidInputError("a volume has the linear FEM Laplacian only (laplacian=None)", "InvalidParameter", name="laplacian")
            self._k = _wfem.HeatKernel.from_volume(*tets, mass, method, degree, k, backend)
            return
        P = points_of(V, F)
        if P is not None:
            p = as_float_array(P, "P", (2,))
            self._k = _wfem.HeatKernel.from_cloud(p, mass, method, degree, k, backend, laplacian, n_neighbors)
            return
        v, f = as_mesh(V, F)
        self._k = _wfem.HeatKernel.from_mesh(v, f, mass, method, degree, k, backend, laplacian)

    @classmethod
    def from_operators(
        cls,
        L: Any,
        M: Any,
        method: str | None = None,
        *,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
    ) -> "HeatKernel":
        """The kernel ``exp(−t M⁻¹L)`` of any stiffness L and mass M (scipy.sparse or dense).

        **L must be symmetric positive semidefinite with a non-negative diagonal** — the
        negative of ``igl.cotmatrix`` — and M symmetric positive definite. For example
        robust_laplacian's output: ``L, M = robust_laplacian.mesh_laplacian(V, F)`` (already PSD).
        The sparsity patterns of L and M may differ.

        Raises:
            InvalidInputError: NaN/inf entries, asymmetry, sizes, a negative diagonal entry of L
                (``kind="InvalidOperatorEntry"``, e.g. igl's cotmatrix passed without ``-``), or
                a mass that is not positive definite.
        """
        self = cls.__new__(cls)
        self._k = _wfem.HeatKernel.from_operators(
            as_sparse(L, "L"), as_sparse(M, "M"), method, degree, k, backend
        )
        return self

    def __repr__(self) -> str:
        return f"HeatKernel(n={self.n}, mass={self.mass_name!r}, method={self.method!r})"

    @property
    def n(self) -> int:
        """Number of vertices."""
        return int(self._k.n)

    @property
    def mass_name(self) -> str | None:
        """The name of the kernel's mass (one of :data:`MASSES`), or None for
        :meth:`from_operators`; the matrix itself is :attr:`mass`."""
        name = self._k.mass_name
        return None if name is None else str(name)

    @property
    def kernel(self) -> str:
        """Older name of :attr:`mass_name` (``"custom"`` for :meth:`from_operators`)."""
        return self.mass_name or "custom"

    @property
    def method(self) -> str:
        """The evaluation method's name."""
        return str(self._k.method)

    @property
    def stiffness(self) -> sp.csc_matrix:
        """L (positive semidefinite, = −igl.cotmatrix for a mesh)."""
        return to_csc(self._k.stiffness())

    @property
    def mass(self) -> sp.csc_matrix:
        """The kernel's mass M (B, D or I)."""
        return to_csc(self._k.mass())

    @property
    def vertex_areas(self) -> np.ndarray:
        """``M @ 1`` (n,)."""
        return np.asarray(self._k.vertex_areas())

    def _times(self, times: list[float], time_unit: str | None, distance: str | None = None) -> list[float]:
        """The times in the mesh's units (``t = τ·unit``), after a :class:`TimeWarning` for
        those whose result (K_t f, or the distance of kind ``distance``) carries no information."""
        unit = float(self._k.time_unit_value(time_unit))
        absolute = [x * unit for x in times]
        name = _choices.canonical("time_unit", time_unit) if time_unit is not None else _choices.default("time_unit")
        kind = None if distance is None else (distance or _choices.default("distance"))
        for text in self._k.time_warnings(absolute, unit, name, kind):
            warn_user(text, TimeWarning)
        return absolute

    def apply(self, f: Any, t: Any, *, time_unit: str | None = None) -> np.ndarray:
        """``K_t f = exp(−t M⁻¹L) f`` (paper, Eq. (6)).

        Args:
            f: (n,) or (n, k): one function per column; all columns share one factorization.
            t: a positive time, or a 1-D array of times (each t is factored once for all
                columns, at the method's full accuracy; :meth:`apply_times` shares one
                factorization between the times of each span of three decades).
            time_unit: the unit of t: ``"absolute"`` (default; the mesh's squared length
                units), ``"area"`` (t = τ·A, the same τ on any scaling of the shape) or
                ``"edge"`` (t = τ·ℓ̄², ℓ̄ the mean edge length: potpourri3d's convention).
                A time so small that K_t f = f, or past the time at infinity (a constant
                result), gives a :class:`TimeWarning` naming the sensible range.

        Returns:
            Shape of ``f`` for a scalar t; ``(T,) + f.shape`` for T times (``out[j] = K_{t_j} f``).

        The constants of each connected component are deflated exactly, so the mass ``1ᵀM K_t f``
        is conserved to rounding. Releases the GIL; Ctrl-C interrupts between times.

        Raises:
            InvalidInputError: t ≤ 0 or not finite (``kind="InvalidTime"``, ``t``), f of the
                wrong length (``expected``, ``found``) or with NaN (``row``, ``column``).
            ConvergenceError: the fast method missed its tolerance (``column``, ``estimate``).
        """
        a = as_float_array(f, "f", (1, 2))
        times, scalar = as_times(t)
        times = self._times(times, time_unit)
        m = a.reshape(a.shape[0], -1) if a.ndim == 2 else a.reshape(-1, 1)
        out = self._k.apply(m, times)  # (T, n, k)
        out = out.reshape((len(times),) + a.shape)
        return out[0] if scalar else out

    def apply_times(self, f: Any, times: Any) -> tuple[np.ndarray, list[float | None]]:
        """``K_t f`` for every t of ``times`` from **one** factorization and Krylov space for the
        whole window (fast method), with the per-t error estimate (relative, M-norm; None for
        methods exact to their stated accuracy). Returns ``((T,) + f.shape, estimates)``.
        Cheaper than :meth:`apply` for many times; measured on the 5K TOSCA cat its max-norm
        error at the smallest times is ≈1e−10 relative (per-t :meth:`apply`: ≈1e−12)."""
        a = as_float_array(f, "f", (1, 2))
        ts, _ = as_times(np.atleast_1d(times))
        values, estimates = self._k.apply_times(a.reshape(a.shape[0], -1), ts)
        return values.reshape((len(ts),) + a.shape), list(estimates)

    def diagonal(
        self,
        times: Any,
        convention: str | None = None,
        *,
        method: str | None = None,
        tol: float = _DEFAULTS["diagonal"]["tol"],
        max_columns: int = _DEFAULTS["diagonal"]["max_columns"],
        block: int = _DEFAULTS["diagonal"]["block"],
        return_info: bool = False,
    ) -> Any:
        """The diagonal of the heat kernel at every t, **without eigenpairs**: the exact heat
        kernel signature (n, T), accurate at small t where any truncated spectrum fails.

        * ``convention="kernel-value"`` (default): ``K̃_t(i, i) = (K_t M⁻¹)_ii = Σ_k e^{−λ_k t} x_k(i)²``;
        * ``convention="operator-diagonal"``: ``K_t(i, i)``, the diagonal of Eq. (6).

        ``method="selected-inversion"`` (default): the kernel matrix on the sparsity pattern by
        selected inversion of the rational method's eight complex LDLᵀ factors — exact to
        rounding at every t, 0.03 s per t at 5K vertices, 0.3 s at 28K.
        ``method="probing"`` (Tang & Saad): a distance-p colouring of the mesh chosen so that
        the kernel's tail beyond p edges is below ``tol`` relative, one block evaluation of all
        times per block of probes; large t (a non-local kernel) needs too many probes and is
        refused (``max_columns``). ``method="unit-columns"``: n unit columns (a reference).
        """
        ts, _ = as_times(np.atleast_1d(times))
        values, info = self._k.diagonal(ts, convention, method, tol, max_columns, block)
        return (np.asarray(values), dict(info)) if return_info else np.asarray(values)

    def apply_kernel_matrix(self, G: Any, t: float) -> np.ndarray:
        """``K̃_t G = K_t M⁻¹ G = X D_t Xᵀ G``: column i of the kernel matrix K̃_t is the heat
        kernel k_t(·, p_i), whose value at p_i is the HKS (kernel-value convention); K̃_{2t} is
        the Gram matrix of the diffusion distances. G (n,) or (n, k)."""
        a = as_float_array(G, "G", (1, 2))
        out = self._k.apply_kernel_matrix(a.reshape(a.shape[0], -1), float(t))
        return out.reshape(a.shape)

    def canonical_basis(self, anchors: Any, t: float) -> np.ndarray:
        """The canonical basis functions ``K_t e_i`` of the anchors (paper, Sect. 4.1, Eq. (21)),
        column j = K_t e_{anchors[j]}, shape (n, |A|); one factorization for all anchors."""
        return np.asarray(self._k.canonical_basis(as_indices(anchors, "anchors"), float(t)))

    def canonical_limit(self, anchors: Any) -> np.ndarray:
        """``lim_{t→∞} K_t e_i = c_i·1`` with ``c_i = (M1)_i / 1ᵀM1`` (Sect. 4.1, corrected by
        the factor 1/area the paper omits)."""
        return np.asarray(self._k.canonical_limit(as_indices(anchors, "anchors")))

    def inner_product(self, f: Any, g: Any) -> float:
        """The mass inner product ``⟨f, g⟩_M = fᵀ M g`` (paper, Eq. (4); B for the wFEM kernel)."""
        return float(self._k.mass_inner_product(as_vector(f, "f"), as_vector(g, "g")))

    def heat_inner_product(self, f: Any, g: Any, t: float) -> float:
        """The time-dependent inner product ``⟨f, g⟩_t = ⟨K_t f, g⟩_M = fᵀ M K_t g``
        (paper, Prop. 3.1 A, Eq. (16))."""
        return float(self._k.heat_inner_product(as_vector(f, "f"), as_vector(g, "g"), float(t)))

    def diffusion_embedding(self, vertices: Any, t: float) -> np.ndarray:
        """The diffusion embeddings ``h_i = K_{t/2} e_i`` (Eq. (18b)) as columns (n, m), so that
        ``⟨h_i, h_j⟩_M = S_t(i, j)``."""
        return np.asarray(self._k.diffusion_embeddings(as_indices(vertices, "vertices"), float(t)))

    def inverse(
        self,
        f: Any,
        t: float,
        *,
        max_amplification: float = _DEFAULTS["inverse"]["max_amplification"],
        tol: float = _DEFAULTS["inverse"]["tol"],
        max_iter: int = _DEFAULTS["inverse"]["max_iter"],
        stall_window: int = _DEFAULTS["inverse"]["stall_window"],
    ) -> tuple[np.ndarray, dict[str, float]]:
        """``K_{−t} f = K_t⁻¹ f`` (paper, Sect. 4, inversion property) by conjugate gradients on
        ``K_t g = f`` — refused (:class:`IllConditionedError`) when the amplification
        ``‖g‖_M/‖f‖_M`` exceeds ``max_amplification``, since ``‖K_{−t}‖ = e^{tλ_max}``.

        Returns ``(g, report)`` with ``iterations``, ``relative_residual``, ``amplification``.
        """
        g, report = self._k.inverse(
            as_vector(f, "f"), float(t), max_amplification, tol, max_iter, stall_window
        )
        return np.asarray(g), dict(report)

    def largest_eigenvalue(self, *, tol: float = _DEFAULTS["largest_eigenvalue"]["tol"], max_iter: int = _DEFAULTS["largest_eigenvalue"]["max_iter"]) -> float:
        """λ_max of ``L x = λ M x`` (Lanczos on M⁻¹L; paper, Sect. 5)."""
        return float(self._k.largest_eigenvalue(tol, max_iter))

    def distance(
        self,
        t: float,
        kind: str | None = None,
        *,
        block: int = _DEFAULTS["distance"]["block"],
        diagonal: str | None = None,
        diagonal_tol: float = _DEFAULTS["distance"]["diagonal_tol"],
        time_unit: str | None = None,
    ) -> "DiffusionDistance":
        """Diffusion distances at time t through this kernel (paper, Sect. 3, Eq. (18)).

        * ``kind="diffusion"`` (default): ``d_t²(i,j) = Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²``, from
          ``A = K̃_{2t} = K_{2t} M⁻¹``;
        * ``kind="mass-weighted"``: the paper's ``‖h_i − h_j‖_M²``, ``h_i = K_{t/2} e_i``
          (Eq. (18b)), from ``A = S_t = M K_t``.

        ``d²(i,j) = A_ii − 2A_ij + A_jj``; a whole row needs diag(A): by selected inversion
        (``diagonal="selected-inversion"``, default; exact at every t, about a second at 50K
        vertices; the mass-weighted Gram matrix is probed instead), probing
        (``diagonal="probing"``, relative tail ``diagonal_tol``) or n unit columns
        (``diagonal="unit-columns"``). ``time_unit`` reads t as in :meth:`apply` (with the same
        :class:`TimeWarning`; the diffusion distance is made of kernel values at 2t).
        """
        (t_abs,) = self._times([float(t)], time_unit, kind or "")
        return DiffusionDistance(self._k.distance(t_abs, kind, block, diagonal, diagonal_tol))

    def feature_approximation(
        self,
        f: Any,
        *,
        k: int | None = None,
        num_times: int | None = None,
        persistence: float | None = None,
        absolute: bool = False,
        coefficients: str | None = None,
        sampling: str | None = None,
        noise: str | None = None,
        scales: int | None = None,
    ) -> dict[str, Any]:
        """The feature-driven approximation ``f = f_glob + f_loc`` (paper, Sect. 4.2, Fig. 12–13).

        The anchors A are the critical points of f with persistence ≥ ``persistence`` (relative
        to the range of f, default 0.1; absolute with ``absolute=True``), most persistent
        first. At ``num_times`` times (default 10; the paper's "scales", and ``scales=`` is the
        old name of this argument, which warns) sampled by ``sampling`` (one of
        :data:`APPROX_SAMPLINGS`; default geometric from 1/λ_max, the mesh's resolution, to
        1/λ_k, k = 20; ``"paper"``: t_i = (i/10)/λ_k) f splits into f_glob and
        ``f_loc = f − f_glob``. ``coefficients`` is one of :data:`APPROX_COEFFICIENTS`; the
        default, ``"anchored"``, is ``f_glob = K_t f + Σ_j c_j K_t e_(a_j)`` with f_glob = f at
        every anchor resolved at t (the persistent features keep their values; within 2 % of
        f at the finest scale on every mesh of docs/APPROX-RESULTS.md); ``"feature-values"``
        is the paper's printed ``Σ f(a_j) K_t e_(a_j)`` (≈ 0 between sparse anchors);
        ``"smooth"`` is ``K_t f`` without anchors.

        ``noise`` (one of :data:`APPROX_NOISE_RULES`) says what to do about noise in f. The
        default, ``"auto"``, estimates the noise level σ̂ and a scale t* from f alone
        (area-weighted generalized cross-validation of ``K_t f``, no clean map needed); when
        smoothing at t* lowers the estimated error and the noise's expected largest value
        ``σ̂ √(2 ln n)`` exceeds the paper's 2 % of the range, the anchors are the persistent
        critical points of the denoised map ``K_t* f`` with values from ``K_t f`` at a quarter
        of t*, and t* joins the scales: ``result["scales"][result["chosen"]]["global_"]`` is
        the denoised map and its ``local`` the noise. A smooth map is left as with
        ``"keep"`` (f taken as clean: anchors at f's critical points keep f's values);
        ``"always"`` always denoises.

        Returns a dict: ``coefficients`` and ``formula`` (the rule), ``sampling``, ``anchors``,
        ``anchor_values`` and ``anchor_persistence``, ``threshold`` and ``range`` (units of
        f), ``lambda_k``, ``lambda_max``, ``input_critical_points``, ``persistent_extrema``,
        ``noise_rule``, ``noise`` (None with ``"keep"``, else a dict: ``sigma`` = σ̂ in units
        of f, ``t`` = t*, ``gcv_sigma``, ``smoothing_helps``, the GCV ``scores`` and
        ``trace_fraction`` of its candidate times), ``chosen`` (the index of t* in
        ``scales`` when denoised, else None), ``warning`` (or None) and ``scales``, a list
        of dicts with ``t``, ``global_``, ``local``, ``anchors``
        and ``coefficients`` (f_glob's basis functions K_t e_a and their coefficients),
        ``linf_error``, ``relative_linf_error``, ``anchor_error``, ``critical_points``,
        ``significant_critical_points``, ``persistent_extrema``. When f_glob stays more than
        3 % of the range from f at every scale, an :class:`ApproximationWarning` names the
        option to change. Needs a kernel built from a mesh (V, F) or a point cloud P (on its
        neighbourhood mesh), not from operators.
        """
        if scales is not None:
            warnings.warn(
                "feature_approximation(scales=) is the old name of num_times=; it will be removed",
                DeprecationWarning,
                stacklevel=2,
            )
            if num_times is not None:
                raise InvalidInputError("give num_times= or its old name scales=, not both", "InvalidParameter")
            num_times = scales
        out = dict(
            self._k.feature_approximation(
                as_vector(f, "f"), k, num_times, persistence, absolute, coefficients, sampling, noise
            )
        )
        if out["warning"] is not None:
            warn_user(out["warning"], ApproximationWarning)
        return out


class DiffusionDistance:
    """Diffusion distances of one kind at one time (see :meth:`HeatKernel.distance`)."""

    def __init__(self, inner: Any) -> None:
        self._d = inner

    def __repr__(self) -> str:
        return f"DiffusionDistance(kind={self.kind!r}, t={self.t}, n={self._d.n})"

    @property
    def t(self) -> float:
        return float(self._d.t)

    @property
    def kind(self) -> str:
        return str(self._d.kind)

    def row(self, i: int) -> np.ndarray:
        """``d(i, ·)`` (n,): one kernel column plus the cached diagonal."""
        return np.asarray(self._d.rows(as_indices([i], "i")))[0]

    def rows(self, sources: Sequence[int]) -> np.ndarray:
        """``d(i, ·)`` for each source (m, n)."""
        return np.asarray(self._d.rows(as_indices(sources, "sources")))

    def pairs(self, pairs: Any) -> np.ndarray:
        """``d(i, j)`` for each pair (m,), from an (m, 2) integer array or list of pairs."""
        p = np.asarray(pairs)
        if p.size == 0:
            return np.zeros(0)
        if p.ndim != 2 or p.shape[1] != 2:
            from ._errors import InvalidInputError

            raise InvalidInputError(f"pairs must have shape (m, 2), got {p.shape}", "Shape", name="pairs")
        flat = as_indices(p.reshape(-1), "pairs")
        return np.asarray(self._d.pairs(list(zip(flat[0::2], flat[1::2]))))

    def diagonal(self) -> np.ndarray:
        """diag(A) of the distance's Gram matrix (n,)."""
        return np.asarray(self._d.diagonal())

    def all_pairs(self, out: Any, progress: Any = None, block_rows: int | None = None) -> str:
        """The n × n matrix ``d(i, j)`` (row i from vertex i) streamed to the ``.npy`` file
        ``out`` in blocks of rows: memory holds the kernel and 64 MB of rows whatever n. The file
        appears complete or not at all; an interrupted call leaves a partial file beside it that
        the same call continues. ``progress("done/total")`` is called after each block;
        ``block_rows`` rows are computed at a time (default: 64 MB of them). Returns the path."""
        import os

        from ._progress import user_callback

        path, _ = self._d.all_pairs(os.fspath(out), user_callback(progress), block_rows)
        return str(path)

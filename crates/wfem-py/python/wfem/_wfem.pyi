# Type stubs of the compiled module wfem._wfem (crates/wfem-py/src). The public API is the
# pure-Python layer (wfem/__init__.py and its modules), which converts arguments before calling
# these functions. tests/test_stubs.py checks this file against the module (mypy.stubtest).

from os import PathLike
from typing import Any, Callable, final

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_F32 = npt.NDArray[np.float32]
_I64 = npt.NDArray[np.int64]
# CSC index arrays: int32 when every index fits (what scipy keeps), int64 otherwise.
_Index = npt.NDArray[np.int32] | npt.NDArray[np.int64]
_Sparse = tuple[_Index, _Index, _F64, tuple[int, int]]
_Mesh = tuple[_F64, _I64]
_Path = str | PathLike[str]

__version__: str
DENSE_MAX_VERTICES: int
DEFAULT_DEGREE: int
DEFAULT_SPIKE_THRESHOLD: float
DEFAULT_MAX_HOLE_PERIMETER: float
DEFAULT_TARGET_ROUGHNESS: float
DEFAULT_VERTICES_PER_EIGENPAIR: float
DEFAULT_SPATIAL_TIME: float
DEFAULT_SPATIAL: float | None
DEFAULT_WORDS: int
SHIPPED_DEGREES: list[int]
PAPER_DESCRIPTORS: list[str]
DEFAULT_NUM_TIMES: int
#: The library's default parameters by group ({"eigen": {"tol": …, …}, …}), read by the Python layer.
DEFAULTS: dict[str, dict[str, Any]]

# the registries of the library's choices
def choices() -> dict[str, Any]: ...
def canonical(argument: str, text: str) -> str: ...
DEFAULT_NEIGHBORS: int

# meshes
def read_mesh(path: _Path, triangulate: bool = False) -> tuple[_Mesh, str]: ...
def validate_mesh(v: _F64, f: _I64) -> str: ...
def read_volume(path: _Path) -> tuple[tuple[_F64, _I64], str]: ...
def validate_volume(v: _F64, t: _I64) -> str: ...
def repair_volume(
    v: _F64, t: _I64, orient: bool = True, degenerate: bool = True, unreferenced: bool = True
) -> tuple[tuple[_F64, _I64], str]: ...
def volume_operators(v: _F64, t: _I64, lumped_mass: str | None = None) -> tuple[_Sparse, _Sparse, _Sparse]: ...
def repair_mesh(
    v: _F64,
    f: _I64,
    merge_duplicate_vertices: float | None = None,
    drop_degenerate_faces: bool = False,
    drop_duplicate_faces: bool = False,
    orient_faces: bool = False,
    drop_unreferenced_vertices: bool = False,
) -> tuple[_Mesh, str]: ...
def fill_holes(v: _F64, f: _I64, max_perimeter: float = ...) -> tuple[_Mesh, int]: ...
def mesh_stats(v: _F64, f: _I64) -> str: ...
def operators(
    v: _F64,
    f: _I64,
    lumped_mass: str | None = None,
    laplacian: str | None = None,
    mollify_factor: float | None = None,
) -> tuple[_Sparse, _Sparse, _Sparse]: ...

# point clouds
def cloud_operators(
    p: _F64,
    normals: _F64 | None = None,
    lumped_mass: str | None = None,
    n_neighbors: int = ...,
    mollify_factor: float | None = None,
    laplacian: str | None = None,
) -> tuple[_Sparse, _Sparse, _Sparse, str]: ...
def read_points(path: _Path) -> tuple[_F64, _F64 | None]: ...
def mass_matrix(mass: str | None = None) -> tuple[str, str]: ...
def extrema(v: _F64, f: _I64, field: _F64, persistence: float | None = None) -> list[int]: ...
def icosphere(level: int) -> _Mesh: ...
def uv_sphere(rings: int, segments: int) -> _Mesh: ...
def grid(nx: int, ny: int) -> _Mesh: ...
def torus(major: float, minor: float, nu: int, nv: int) -> _Mesh: ...
def irregular_sphere(level: int, s: float) -> _Mesh: ...
def bumpy(level: int) -> _Mesh: ...

# heat kernel
@final
class HeatKernel:
    @staticmethod
    def from_mesh(
        v: _F64,
        f: _I64,
        mass: str | None = None,
        method_name: str | None = None,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
        laplacian: str | None = None,
    ) -> HeatKernel: ...
    @staticmethod
    def from_volume(
        v: _F64,
        t: _I64,
        mass: str | None = None,
        method_name: str | None = None,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
    ) -> HeatKernel: ...
    @staticmethod
    def from_cloud(
        p: _F64,
        mass: str | None = None,
        method_name: str | None = None,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
        laplacian: str | None = None,
        n_neighbors: int | None = None,
    ) -> HeatKernel: ...
    @staticmethod
    def from_operators(
        l: _Sparse,
        m: _Sparse,
        method_name: str | None = None,
        degree: int | None = None,
        k: int | None = None,
        backend: str | None = None,
    ) -> HeatKernel: ...
    @property
    def n(self) -> int: ...
    @property
    def method(self) -> str: ...
    @property
    def mass_name(self) -> str | None: ...
    def stiffness(self) -> _Sparse: ...
    def mass(self) -> _Sparse: ...
    def vertex_areas(self) -> _F64: ...
    def time_unit_value(self, name: str | None = None) -> float: ...
    def time_warnings(
        self, times: list[float], unit: float, unit_name: str, distance_kind: str | None = None
    ) -> list[str]: ...
    def apply(self, f: _F64, times: list[float]) -> _F64: ...
    def apply_times(self, f: _F64, times: list[float]) -> tuple[_F64, list[float | None]]: ...
    def diagonal(
        self,
        times: list[float],
        convention: str | None = None,
        method: str | None = None,
        tol: float = ...,
        max_columns: int = ...,
        block: int = ...,
    ) -> tuple[_F64, dict[str, Any]]: ...
    def hks_by_method(
        self,
        eigenvalues: list[float],
        spectral: _F64,
        times: list[float],
        convention: str | None = None,
        method: str | None = None,
        tol: float = ...,
    ) -> tuple[_F64, list[tuple[str, float]]]: ...
    def apply_kernel_matrix(self, g: _F64, t: float) -> _F64: ...
    def canonical_basis(self, anchors: list[int], t: float) -> _F64: ...
    def canonical_limit(self, anchors: list[int]) -> _F64: ...
    def mass_inner_product(self, f: _F64, g: _F64) -> float: ...
    def heat_inner_product(self, f: _F64, g: _F64, t: float) -> float: ...
    def diffusion_embeddings(self, vertices: list[int], t: float) -> _F64: ...
    def inverse(
        self,
        f: _F64,
        t: float,
        max_amplification: float = ...,
        tol: float = ...,
        max_iter: int = ...,
        stall_window: int = ...,
    ) -> tuple[_F64, dict[str, float]]: ...
    def largest_eigenvalue(self, tol: float = ..., max_iter: int = ..., seed: int = ...) -> float: ...
    def feature_approximation(
        self,
        f: _F64,
        k: int | None = None,
        num_times: int | None = None,
        persistence: float | None = None,
        absolute: bool = False,
        coefficients: str | None = None,
        sampling: str | None = None,
        noise: str | None = None,
    ) -> dict[str, Any]: ...
    def distance(
        self,
        t: float,
        kind: str | None = None,
        block: int = ...,
        diagonal: str | None = None,
        diagonal_tol: float = ...
    ) -> DiffusionDistance: ...

@final
class DiffusionDistance:
    @property
    def t(self) -> float: ...
    @property
    def kind(self) -> str: ...
    @property
    def n(self) -> int: ...
    def rows(self, sources: list[int]) -> _F64: ...
    def pairs(self, pairs: list[tuple[int, int]]) -> _F64: ...
    def all_pairs(self, out: _Path, progress: Any = None, block_rows: int | None = None) -> tuple[str, int]: ...
    def diagonal(self) -> _F64: ...

# geodesic distances
DEFAULT_T_COEF: float
MAX_REFINE: int

@final
class GeodesicSolver:
    @staticmethod
    def from_mesh(
        v: _F64,
        f: _I64,
        method: str | None = None,
        t_coef: float = ...,
        use_robust: bool = True,
        refine: int = ...,
    ) -> GeodesicSolver: ...
    @staticmethod
    def from_volume(
        v: _F64,
        t: _I64,
        method: str | None = None,
        t_coef: float = ...,
    ) -> GeodesicSolver: ...
    @staticmethod
    def from_cloud(
        p: _F64,
        method: str | None = None,
        t_coef: float = ...,
        n_neighbors: int | None = None,
    ) -> GeodesicSolver: ...
    @property
    def n(self) -> int: ...
    @property
    def t(self) -> float | None: ...
    @property
    def mean_edge_length(self) -> float: ...
    @property
    def memory_bytes(self) -> int: ...
    def distance(
        self, vertices: list[int], points: list[tuple[int, float, float, float]]
    ) -> tuple[_F64, tuple[int, int]]: ...
    def distance_each(self, vertices: list[int]) -> _F64: ...
    def all_pairs(self, out: _Path, progress: Any = None, block_rows: int | None = None) -> tuple[str, int]: ...

# spectrum and signatures
DEFAULT_ENERGIES: int

def eigenpairs_wks(values: list[float], vectors: _F64, num_energies: int = ...) -> tuple[_F64, list[float], float]: ...
@final
class Eigenbasis:
    @staticmethod
    def from_mesh(
        v: _F64,
        f: _I64,
        k: int | None = None,
        mass: str | None = None,
        tol: float = ...,
        block_size: int = ...,
        max_dim: int | None = None,
        seed: int = ...,
        shift: float | None = None,
        max_restarts: int = ...,
        laplacian: str | None = None,
    ) -> Eigenbasis: ...
    @staticmethod
    def from_operators(
        l: _Sparse,
        m: _Sparse,
        k: int | None = None,
        tol: float = ...,
        block_size: int = ...,
        max_dim: int | None = None,
        seed: int = ...,
        shift: float | None = None,
        max_restarts: int = ...,
    ) -> Eigenbasis: ...
    @property
    def values(self) -> _F64: ...
    @property
    def vectors(self) -> _F64: ...
    @property
    def n(self) -> int: ...
    @property
    def k(self) -> int: ...
    def project(self, f: _F64) -> _F64: ...
    def reconstruct(self, c: _F64) -> _F64: ...
    def heat(self, f: _F64, t: float) -> _F64: ...
    def inverse_heat(self, f: _F64, t: float) -> tuple[_F64, dict[str, float]]: ...
    def reproducing_kernel(self, v: _F64, t: float) -> tuple[_F64, dict[str, float]]: ...
    def hks(
        self,
        times: list[float] | None = None,
        num_times: int = ...,
        convention: str | None = None,
        scaled: bool = False,
        normalization: str | None = None,
    ) -> tuple[_F64, list[float]]: ...
    def wks(self, num_energies: int = ...) -> tuple[_F64, list[float], float]: ...
    def global_signature(
        self, eigenvalues: int, kind: str | None = None, measure: float | None = None, dimension: int = ...
    ) -> list[float]: ...
    def sihks(
        self,
        alpha: float = ...,
        tau_min: float = ...,
        tau_max: float = ...,
        tau_step: float = ...,
        time_unit: float = ...,
        num_frequencies: int = ...,
        convention: str | None = None,
    ) -> _F64: ...
def mesh_time_unit(v: _F64, f: _I64, name: str | None = None) -> float: ...
def mesh_hks(
    v: _F64,
    f: _I64 | None,
    times: list[float] | None = None,
    num_times: int | None = None,
    k: int = ...,
    mass: str | None = None,
    method: str | None = None,
    convention: str | None = None,
    scaled: bool = False,
    normalization: str | None = None,
    basis: Eigenbasis | None = None,
    tol: float = ...,
    laplacian: str | None = None,
    n_neighbors: int | None = None,
    cloud_time_unit: str | None = None,
) -> tuple[_F64, list[float], list[tuple[str, float]], list[float] | None]: ...

# retrieval
def descriptors(
    v: _F64,
    f: _I64,
    kinds: list[str],
    k: int = ...,
    times: list[float] | None = None,
    num_times: int = ...,
    sihks: dict[str, Any] | None = None,
) -> dict[str, _F64]: ...
def sparse_features(
    v: _F64,
    f: _I64,
    detector: str | None = None,
    k: int = ...,
    feature_time_factor: float = ...,
    feature_rings: int = ...,
    persistence_fraction: float = ...,
) -> tuple[list[int], float]: ...
def kmeans_clusters(
    points: _F64, k: int, max_iter: int = ..., seed: int = ...
) -> tuple[_F64, list[int], float, int, bool]: ...
def evaluate_retrieval(
    distances: _F64, labels: list[int]
) -> tuple[list[float | None], float, list[tuple[int, float, int]]]: ...
def pairwise_l1(bags: _F64) -> _F64: ...
@final
class Vocabulary:
    def __new__(cls, words: _F64, sigma: float) -> Vocabulary: ...
    @staticmethod
    def train(
        descriptors: _F64,
        size: int = ...,
        max_iter: int = ...,
        seed: int = ...,
        sigma: float | None = None,
        max_training_points: int | None = None,
    ) -> Vocabulary: ...
    @property
    def words(self) -> _F64: ...
    @property
    def sigma(self) -> float: ...
    @property
    def size(self) -> int: ...
    def soft_assignment(self, descriptors: _F64) -> _F64: ...
    def bag(self, descriptors: _F64, weights: _F64) -> _F64: ...
    def spatially_sensitive_bag(self, descriptors: _F64, kernel: HeatKernel, t: float) -> _F64: ...

# (version, checksums, metadata, shapes, chunks, [(record, reason)], text)
_CheckTuple = tuple[int, bool, int, int, int, list[tuple[str, str]], str]

@final
class VectorStore:
    @staticmethod
    def create(path: _Path, dimension: int, chunk_rows: int = ..., overwrite: bool = False) -> VectorStore: ...
    @staticmethod
    def open(path: _Path, readonly: bool = False) -> VectorStore: ...
    @staticmethod
    def check(path: _Path) -> _CheckTuple: ...
    @staticmethod
    def upgrade(path: _Path) -> _CheckTuple: ...
    @property
    def checksummed(self) -> bool: ...
    @property
    def path(self) -> str: ...
    @property
    def dimension(self) -> int: ...
    def __len__(self) -> int: ...
    def meta(self, key: str) -> bytes | None: ...
    def set_meta(self, key: str, value: bytes) -> None: ...
    def add(self, names: list[str], infos: list[str], vectors: _F64) -> list[int]: ...
    def search(self, query: _F64, k: int = ..., metric: str | None = None) -> list[tuple[int, str, str, float]]: ...
    def shapes(self) -> list[tuple[int, str, str]]: ...
    def find(self, name: str) -> tuple[int, str] | None: ...
    def vectors(self) -> _F32: ...
    def vector(self, id: int) -> _F32 | None: ...

@final
class RetrievalIndex:
    @staticmethod
    def build(
        paths: list[str],
        out: str,
        vocabulary: str | None = None,
        words: int | None = None,
        seed: int = ...,
        despike: float | None = ...,
        fill_holes: float | None = ...,
        denoise: float | None = ...,
        overwrite: bool = ...,
        spatial: float | None = ...,
        strict: bool = False,
        progress: Callable[[str], object] | None = None,
        laplacian: str | None = None,
        spatial_groups: int | None = None,
        refine: float | None = ...,
    ) -> tuple[RetrievalIndex, list[tuple[str, str]]]: ...
    @staticmethod
    def open(path: str) -> RetrievalIndex: ...
    @staticmethod
    def check(path: str) -> _CheckTuple: ...
    @property
    def path(self) -> str: ...
    def names(self) -> list[str]: ...
    def settings(self) -> str: ...
    def add_paths(
        self, paths: list[str], strict: bool = False, progress: Callable[[str], object] | None = None
    ) -> tuple[int, list[tuple[str, str]]]: ...
    def query(
        self, v: _F64, f: _I64 | None = None, k: int = ..., laplacian: str | None = None
    ) -> list[tuple[str, float]]: ...
    def query_id(self, name: str, k: int = ...) -> tuple[str, list[tuple[str, float]]]: ...
    def evaluate(self, classes: list[str] | None = None, class_from: str | None = None) -> tuple[str, str]: ...
    def __len__(self) -> int: ...

def _live_workers() -> int: ...

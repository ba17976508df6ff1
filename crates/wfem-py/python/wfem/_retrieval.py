"""Shape descriptors, vocabularies, bags of features, retrieval metrics and the SQLite index
(paper, Sect. 5)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np

from . import _choices, _wfem
from ._arrays import as_float_array, as_indices, as_mesh, as_vector, points_of
from ._errors import InvalidInputError, RefusedShapesWarning, warn_user
from ._heat import HeatKernel
from ._progress import ProgressArg, reporter

#: The library's default parameters by group (one place: the Rust crates).
_DEFAULTS = _wfem.DEFAULTS

__all__ = [
    "DESCRIPTORS",
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
    "Hit",
    "CheckReport",
    "RetrievalIndex",
]

#: Every dense descriptor name (the library's registry; aliases such as "sihks" are accepted).
DESCRIPTORS = _choices.names("descriptor")
#: The four dense descriptors of the paper's Sect. 5 (Tables 3–4), computed by default.
PAPER_DESCRIPTORS = tuple(_wfem.PAPER_DESCRIPTORS)


def descriptors(
    V: Any,
    F: Any = None,
    kinds: Sequence[str] = PAPER_DESCRIPTORS,
    *,
    k: int = _DEFAULTS["descriptor"]["k"],
    times: Any = None,
    num_times: int = _DEFAULTS["descriptor"]["num_times"],
    sihks: dict[str, Any] | None = None,
) -> dict[str, np.ndarray]:
    """Dense per-vertex descriptors of the paper's Sect. 5, sharing one eigenbasis per mass:

    * ``"dhk1"``: HKS of the lumped Voronoi-cot kernel, spectrum of (L, D_voronoi) (Eq. (7));
    * ``"dhk2"``: HKS of the wFEM kernel, spectrum of (L, B) (Eq. (6));
    * ``"dhk3"``: scale-invariant wFEM HKS, eigenvalues divided by λ_max (times in units of
      1/λ_max);
    * ``"si-hks"`` (or ``"sihks"``): the scale-invariant HKS of Bronstein & Kokkinos on the wFEM spectrum
      (options in ``sihks``: alpha, tau_min, tau_max, tau_step, time_unit, num_frequencies,
      convention).
    * ``"wks"``: the wave kernel signature at pyFM's 100 energies (:func:`wfem.wks`);
    * ``"si-hks+wks"``: the SI-HKS and the WKS side by side (columns of the first, then of the
      second; ``sihks`` applies to the first part).

    HKS are in the kernel-value convention ``Σ_k e^{−λ_k t} x_k(i)²``. ``times`` explicit or
    ``num_times`` automatic log-spaced times per shape (give explicit times to compare shapes).

    Returns ``{kind: (n, d) array}``.
    """
    v, f = as_mesh(V, F)
    if isinstance(kinds, str):
        kinds = [kinds]
    t = None if times is None else [float(x) for x in as_vector(np.atleast_1d(times), "times")]
    return dict(_wfem.descriptors(v, f, list(kinds), k, t, num_times, sihks))


def descriptor(V: Any, F: Any = None, kind: str | None = None, **options: Any) -> np.ndarray:
    """One dense descriptor (n, d), by default SI-HKS; see :func:`descriptors`."""
    kind = _choices.default("descriptor") if kind is None else kind
    return descriptors(V, F, [kind], **options)[kind]


def sparse_features(
    V: Any,
    F: Any = None,
    detector: str | None = None,
    *,
    k: int = _DEFAULTS["descriptor"]["k"],
    feature_time_factor: float = _DEFAULTS["descriptor"]["feature_time_factor"],
    feature_rings: int = _DEFAULTS["descriptor"]["feature_rings"],
    persistence_fraction: float = _DEFAULTS["descriptor"]["persistence_fraction"],
    return_time: bool = False,
) -> Any:
    """Sparse feature points (paper, Sect. 5, Table 4): local maxima of the wFEM HKS at
    ``t_f = feature_time_factor · 4 ln10/λ_2`` (``"shk1"``), or those of persistence at least
    ``persistence_fraction`` of the range (``"shk2"``). Returns sorted vertex indices (and t_f)."""
    v, f = as_mesh(V, F)
    idx, t = _wfem.sparse_features(v, f, detector, k, feature_time_factor, feature_rings, persistence_fraction)
    out = np.asarray(idx, dtype=np.int64)
    return (out, float(t)) if return_time else out


class Vocabulary:
    """A vocabulary of V geometric words (V, d) with soft-assignment width σ (Shape Google).

    ``Vocabulary(words, sigma)`` or :meth:`train` (k-means++ then Lloyd on pooled descriptors).
    """

    _v: Any

    def __init__(self, words: Any, sigma: float) -> None:
        self._v = _wfem.Vocabulary(as_float_array(words, "words", (2,)), float(sigma))

    @classmethod
    def train(
        cls,
        descriptors: Any,
        size: int = _DEFAULTS["vocabulary"]["size"],
        *,
        max_iter: int = _DEFAULTS["vocabulary"]["max_iter"],
        seed: int = _DEFAULTS["vocabulary"]["seed"],
        sigma: float | None = None,
        max_training_points: int | None = None,
    ) -> "Vocabulary":
        """Learns ``size`` words by k-means on the rows of ``descriptors`` (N, d) (or a seeded
        subset of ``max_training_points`` rows); σ defaults to the median nearest-word distance.
        Training on the collection you then index is optimistic: prefer disjoint shapes."""
        self = cls.__new__(cls)
        self._v = _wfem.Vocabulary.train(
            as_float_array(descriptors, "descriptors", (2,)), size, max_iter, seed, sigma, max_training_points
        )
        return self

    def __repr__(self) -> str:
        return f"Vocabulary(size={self.size}, dimension={self.words.shape[1]}, sigma={self.sigma:.4g})"

    @property
    def words(self) -> np.ndarray:
        return np.asarray(self._v.words)

    @property
    def sigma(self) -> float:
        return float(self._v.sigma)

    @property
    def size(self) -> int:
        return int(self._v.size)

    def soft_assignment(self, descriptors: Any) -> np.ndarray:
        """Θ (n, V): ``θ_i(x) ∝ exp(−‖p(x) − p_i‖²/2σ²)``, rows summing to 1."""
        return np.asarray(self._v.soft_assignment(as_float_array(descriptors, "descriptors", (2,))))

    def bag(self, descriptors: Any, weights: Any, *, normalize: bool = True) -> np.ndarray:
        """The bag of features ``Θᵀ a`` (V,) with vertex weights ``a`` (e.g. areas ``B @ 1``),
        divided by ``Σ a`` when ``normalize`` (a histogram summing to 1)."""
        w = as_vector(weights, "weights")
        b = np.asarray(self._v.bag(as_float_array(descriptors, "descriptors", (2,)), w))
        if normalize:
            total = float(np.sum(w))
            if not total > 0:
                raise InvalidInputError("the weights sum to zero: cannot normalise the bag", "Empty")
            b = b / total
        return b

    def spatially_sensitive_bag(self, descriptors: Any, kernel: HeatKernel, t: float) -> np.ndarray:
        """The spatially sensitive bag ``Θᵀ M K_t Θ`` (V, V) with the kernel's mass and method
        (Shape Google; the paper's wFEM weights). Its entries sum to the area."""
        return np.asarray(
            self._v.spatially_sensitive_bag(as_float_array(descriptors, "descriptors", (2,)), kernel._k, float(t))
        )

    def to_dict(self) -> dict[str, Any]:
        return {"words": self.words.tolist(), "sigma": self.sigma}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Vocabulary":
        return cls(np.asarray(d["words"], dtype=np.float64), float(d["sigma"]))


def kmeans(points: Any, k: int, *, max_iter: int = _DEFAULTS["kmeans"]["max_iter"], seed: int = _DEFAULTS["kmeans"]["seed"]) -> dict[str, Any]:
    """k-means++ and Lloyd: ``centers`` (k, d), ``assignment`` (N,), ``inertia``, ``iterations``,
    ``converged``."""
    c, a, inertia, it, conv = _wfem.kmeans_clusters(as_float_array(points, "points", (2,)), k, max_iter, seed)
    return {
        "centers": np.asarray(c),
        "assignment": np.asarray(a, dtype=np.int64),
        "inertia": float(inertia),
        "iterations": int(it),
        "converged": bool(conv),
    }


def l1_distance(a: Any, b: Any) -> float:
    """``Σ |a_i − b_i|`` (Shape Google's bag distance)."""
    x, y = as_vector(a, "a"), as_vector(b, "b")
    if x.shape != y.shape:
        raise InvalidInputError(f"a has {x.size} values and b {y.size}", "DimensionMismatch")
    return float(_wfem.pairwise_l1(np.stack([x, y]))[0, 1])


def pairwise_l1(bags: Any) -> np.ndarray:
    """Pairwise L1 distances between the rows of ``bags`` (m, V) → (m, m)."""
    return np.asarray(_wfem.pairwise_l1(as_float_array(bags, "bags", (2,))))


def evaluate(distances: Any, labels: Any) -> dict[str, Any]:
    """Leave-one-out retrieval on a square distance matrix with class labels: every item is a
    query against all others. Returns ``average_precision`` (per query, None when its class has
    no other member), ``mean_average_precision`` (mAP) and ``per_class`` {label: (mAP, queries)}."""
    ap, m, per = _wfem.evaluate_retrieval(as_float_array(distances, "distances", (2,)), as_indices(labels, "labels"))
    return {
        "average_precision": ap,
        "mean_average_precision": float(m),
        "per_class": {int(label): (float(v), int(n)) for label, v, n in per},
    }


def mean_average_precision(distances: Any, labels: Any) -> float:
    """The mAP of :func:`evaluate`."""
    return float(evaluate(distances, labels)["mean_average_precision"])


def average_precision(relevance: Sequence[bool]) -> float | None:
    """``AP = (1/R) Σ_k P(k)·rel(k)`` of one ranked relevance list; None if nothing is relevant."""
    rel = [bool(r) for r in relevance]
    hits = 0
    total = 0.0
    for i, r in enumerate(rel):
        if r:
            hits += 1
            total += hits / (i + 1)
    return total / hits if hits else None


@dataclass(frozen=True)
class Hit:
    """One query result: the shape's id (insertion order), name, info text and distance."""

    id: int
    name: str
    info: str
    distance: float


@dataclass(frozen=True)
class CheckReport:
    """What :meth:`VectorStore.check` / :meth:`RetrievalIndex.check` found in an index file.

    ``damage`` lists every damaged record as ``(record, reason)`` (``'metadata "KEY"'``,
    ``'shape ID ("NAME")'``, ``'chunk C (shapes A to B)'``, ``'the file'``, …); ``checksums``
    is False for a file of format version 1, which has none, so that its contents could not be
    verified (:meth:`VectorStore.upgrade` adds them). ``text`` is what ``wfem retrieval check``
    prints."""

    path: str
    version: int
    checksums: bool
    metadata: int
    shapes: int
    chunks: int
    damage: list[tuple[str, str]]
    text: str

    @property
    def verified(self) -> bool:
        """Nothing is damaged and every record was verified against its checksum."""
        return self.checksums and not self.damage


def _check_report(path: str | os.PathLike[str], t: Any) -> CheckReport:
    version, checksums, metadata, shapes, chunks, damage, text = t
    return CheckReport(
        os.fspath(path), int(version), bool(checksums), int(metadata), int(shapes), int(chunks),
        [(str(r), str(why)) for r, why in damage], str(text),
    )


class VectorStore:
    """The embedded SQLite store of a retrieval index (one file; see the crate retrieval-store).

    Metadata (bytes per key), and per shape an id, a unique name, an info string and one
    vector of the store's dimension (kept as float32). :meth:`search` is an exact parallel
    top-k scan; :meth:`add` appends in one transaction (nothing is rebuilt). WAL mode: any
    number of readers (``readonly=True``) alongside one writer; a crash during ``add`` loses
    nothing committed before. Every record carries a checksum: opening verifies the metadata,
    every read what it reads (a damaged record raises :class:`StoreError` with ``kind ==
    "CorruptIndex"`` naming it), and :meth:`check` the whole file.
    """

    _s: Any

    def __init__(self, inner: Any) -> None:
        self._s = inner

    @classmethod
    def create(
        cls, path: str | os.PathLike[str], dimension: int, *, chunk_rows: int = _DEFAULTS["index"]["chunk_rows"], overwrite: bool = False
    ) -> "VectorStore":
        return cls(_wfem.VectorStore.create(os.fspath(path), dimension, chunk_rows, overwrite))

    @classmethod
    def open(cls, path: str | os.PathLike[str], *, readonly: bool = False) -> "VectorStore":
        return cls(_wfem.VectorStore.open(os.fspath(path), readonly))

    @staticmethod
    def check(path: str | os.PathLike[str]) -> CheckReport:
        """Verifies every record of the store file at ``path`` (checksums, SQLite's structure,
        the chunk table, finite values) and reports all damage rather than raising at the first;
        raises only when nothing can be checked (not a store, unreadable)."""
        return _check_report(path, _wfem.VectorStore.check(os.fspath(path)))

    @staticmethod
    def upgrade(path: str | os.PathLike[str]) -> CheckReport:
        """Adds checksums in place to a store of format version 1 (which is read unchecked and
        not written to); a store with damage is refused. Returns the check afterwards."""
        return _check_report(path, _wfem.VectorStore.upgrade(os.fspath(path)))

    @property
    def checksummed(self) -> bool:
        """Whether every record carries a checksum (False: format version 1, see :meth:`upgrade`)."""
        return bool(self._s.checksummed)

    def __len__(self) -> int:
        return len(self._s)

    def __repr__(self) -> str:
        return f"VectorStore({str(self.path)!r}, shapes={len(self)}, dimension={self.dimension})"

    @property
    def path(self) -> str:
        return os.fspath(self._s.path)

    @property
    def dimension(self) -> int:
        return int(self._s.dimension)

    def meta(self, key: str) -> bytes | None:
        return self._s.meta(key)

    def set_meta(self, key: str, value: bytes | str) -> None:
        self._s.set_meta(key, value.encode() if isinstance(value, str) else bytes(value))

    def add(self, names: Sequence[str], vectors: Any, infos: Sequence[str] | None = None) -> list[int]:
        """Appends shapes (one transaction, all or none); returns their ids."""
        names = [str(n) for n in names]
        infos = [""] * len(names) if infos is None else [str(i) for i in infos]
        v = as_float_array(vectors, "vectors", (1, 2))
        v = v.reshape(1, -1) if v.ndim == 1 else v
        return list(self._s.add(names, infos, v))

    def search(self, query: Any, k: int = _DEFAULTS["index"]["k"], *, metric: str | None = None) -> list[Hit]:
        """The k nearest shapes, nearest first (ties by id); ``metric`` one of
        ``wfem.choices()["metric"]`` (default "l1")."""
        return [Hit(*h) for h in self._s.search(as_vector(query, "query"), int(k), metric)]

    def shapes(self) -> list[tuple[int, str, str]]:
        """Every shape as (id, name, info), by id."""
        return list(self._s.shapes())

    def find(self, name: str) -> tuple[int, str] | None:
        return self._s.find(name)

    def vectors(self) -> np.ndarray:
        """All vectors (n, d) float32, by id."""
        return np.asarray(self._s.vectors())


def _report_refused(refused: list[tuple[str, str]], what: str) -> list[tuple[str, str]]:
    """One :class:`RefusedShapesWarning` naming every refused file; the list back."""
    refused = [(str(f), str(why)) for f, why in refused]
    if refused:
        lines = "".join(f"\n  {f}: {why}" for f, why in refused)
        warn_user(f"{len(refused)} file(s) {what} (strict=True refuses instead):{lines}", RefusedShapesWarning)
    return refused


class RetrievalIndex:
    """The retrieval index of wfem, shared with the command line: one SQLite file holding the
    recipe (descriptor, time window, z-score statistics, vocabulary, bag settings, distance) and
    one signature per shape. A file built here is queried by ``wfem retrieval query`` and a file
    built by ``wfem retrieval build`` opens here.

    The default recipe (paper Sect. 5, beyond Shape Google): SI-HKS of the wFEM kernel with
    times in units of the surface area (exactly scale invariant), z-scored dimensions, 512
    words, soft assignment, bags weighted by vertex areas capped at 3 medians, χ² distance
    (SHREC'11 mAP 0.990, TOSCA-76 0.997: docs/RETRIEVAL-RESULTS.md), after spikes are put back,
    noisy shapes denoised, holes closed and thin handles cut, in that order (see ``build``).
    Training the vocabulary on the indexed shapes themselves is optimistic when the same shapes
    are then used to measure retrieval (:meth:`evaluate` says so): train one on other shapes
    with ``wfem retrieval vocab`` and pass it as ``vocabulary`` — the recommended route.
    Adding shapes appends in one transaction (nothing is rebuilt); a query is one descriptor
    computation and a parallel scan of the file.
    """

    def __init__(self, inner: Any) -> None:
        self._i = inner
        #: Files the last ``build`` / ``add_meshes`` of this object left out: ``[(path, reason)]``.
        self.refused: list[tuple[str, str]] = []

    @classmethod
    def build(
        cls,
        paths: Iterable[str | os.PathLike[str]],
        out: str | os.PathLike[str],
        *,
        vocabulary: str | os.PathLike[str] | None = None,
        words: int | None = None,
        seed: int = _DEFAULTS["index"]["seed"],
        despike: float | None = _wfem.DEFAULT_SPIKE_THRESHOLD,
        fill_holes: float | None = _wfem.DEFAULT_MAX_HOLE_PERIMETER,
        denoise: float | None = _wfem.DEFAULT_TARGET_ROUGHNESS,
        overwrite: bool = False,
        spatial: float | None = _wfem.DEFAULT_SPATIAL,
        spatial_groups: int | None = None,
        strict: bool = False,
        progress: ProgressArg = None,
        laplacian: str | None = None,
        refine: float | None = _wfem.DEFAULT_VERTICES_PER_EIGENPAIR,
    ) -> "RetrievalIndex":
        """Indexes mesh and point-cloud files with the default recipe into a new file ``out``.

        A file holds a mesh (``.obj``, ``.off``, ``.stl``, a ``.ply`` with faces) or a point
        cloud (a ``.ply`` without faces, ``.xyz``, ``.pts``, ``.csv``, ``.npy``); one index may
        mix them. A cloud is described with the robust Laplacian of its 30-nearest-neighbour
        triangulations; ``laplacian`` (a name of :data:`wfem.LAPLACIANS`, default the cotangent
        L) is the Laplacian of the meshes, recorded in the index (queries and added shapes are
        described with it; with ``vocabulary`` it must be the vocabulary's).

        An existing ``out`` raises :class:`StoreError` unless ``overwrite=True`` (then it is
        replaced atomically); ``out`` is never one of the inputs, a directory or a FIFO.

        Every shape is cleaned first: a vertex farther than ``despike`` local edge lengths from
        the centroid of its neighbours (an isolated spike) is put back, every hole whose rim
        is at most ``fill_holes`` times the square root of the area is closed by a smooth
        patch (which is not itself described), and a shape rougher
        than ``denoise`` edge lengths is smoothed by the heat kernel until it is not (clean
        shapes are left as they are); last, a mesh with fewer than ``refine`` vertices per
        eigenpair (default 20, i.e. 2,000) has every triangle split into four (the same
        surface) until it has that many, so its eigenbasis is accurate while the shape is still
        described at its own vertices. ``None`` turns a step off. All are recorded in the
        index, so queries are cleaned the same way. With ``vocabulary``, its own settings are
        used instead. Point clouds are despiked only: denoising, hole filling and the repair of
        pinches and handles are repairs of a triangulation, which a cloud does not have.

        ``spatial``: spatially sensitive bags (Shape Google Sect. 4.2; off by default), the bag
        also holding the heat that flows between words in time ``spatial · area`` (e.g.
        ``wfem._wfem.DEFAULT_SPATIAL_TIME`` = 2⁻⁸); ``spatial_groups``: measure that flow between
        so many groups of similar words instead (G(G+1)/2 numbers per shape instead of
        V(V+1)/2); ``None`` for plain bags. ``words`` defaults to 512
        (``wfem._wfem.DEFAULT_WORDS``).

        A file that cannot be read or described is left out: the index holds every usable
        shape, a :class:`RefusedShapesWarning` names each refused file with its reason, and
        :attr:`refused` lists them; with ``strict=True`` the first such file raises instead
        (no index is written). No usable file at all always raises.

        ``progress``: ``None`` (default) shows a tqdm bar when tqdm is installed and standard
        error is a terminal; ``True`` always reports (tqdm, or a line per shape), ``False``
        never; a callable is called as ``progress(done, total, name)`` after each shape, on the
        calling thread."""
        ps = [os.fspath(p) for p in paths]
        voc = None if vocabulary is None else os.fspath(vocabulary)
        with reporter(progress, len(ps), "describing shapes") as step:
            inner, refused = _wfem.RetrievalIndex.build(
                ps, os.fspath(out), voc, words, seed, despike, fill_holes, denoise, overwrite, spatial, strict, step,
                laplacian, spatial_groups, refine,
            )
        index = cls(inner)
        index.refused = _report_refused(refused, "left out of the index")
        return index

    @classmethod
    def open(cls, path: str | os.PathLike[str]) -> "RetrievalIndex":
        """Opens an index file (checked: format, settings against their checksum, sizes)."""
        return cls(_wfem.RetrievalIndex.open(os.fspath(path)))

    @staticmethod
    def check(path: str | os.PathLike[str]) -> CheckReport:
        """Verifies the whole index file at ``path`` — every record against its checksum, the
        recipe, every stored bag — and reports all damage (``wfem retrieval check``); raises
        only when nothing can be checked."""
        return _check_report(path, _wfem.RetrievalIndex.check(os.fspath(path)))

    def __len__(self) -> int:
        return int(self._i.__len__())

    def __repr__(self) -> str:
        return f"RetrievalIndex({self.path!r}, shapes={len(self)})"

    @property
    def path(self) -> str:
        return str(self._i.path)

    @property
    def names(self) -> list[str]:
        """The indexed names (the paths as given), in insertion order."""
        return list(self._i.names())

    @property
    def settings(self) -> dict[str, Any]:
        """The recipe recorded in the file."""
        return dict(json.loads(self._i.settings()))

    def add_meshes(
        self,
        paths: Iterable[str | os.PathLike[str]],
        *,
        strict: bool = False,
        progress: ProgressArg = None,
    ) -> int:
        """Appends mesh or point-cloud files (named by the path as given) in one transaction;
        returns how many were added. Unusable files are left out and reported as in
        :meth:`build` (``strict``, ``progress`` and :attr:`refused` alike)."""
        ps = [os.fspath(p) for p in paths]
        with reporter(progress, len(ps), "describing shapes") as step:
            added, refused = self._i.add_paths(ps, strict, step)
        self.refused = _report_refused(refused, "not added")
        return int(added)

    def evaluate(
        self,
        classes: Sequence[str] | dict[str, str] | None = None,
        *,
        class_from: str | None = None,
    ) -> dict[str, Any]:
        """Leave-one-out evaluation of the indexed shapes, as ``wfem retrieval eval``: every
        shape ranks all the others from its **stored** signature (nothing is described again)
        and the standard measures are averaged overall and per class — mAP, nearest neighbour
        (``nn``), first and second tier, E-measure (first 32 results), normalised DCG — with
        the most confused class pairs.

        ``classes``: one class per indexed name (in :attr:`names` order) or a mapping name →
        class; without it, each name's class by ``class_from`` (``"folder"``: the folder holding
        the file, the default; ``"stem"``: the file name without extension and digits).

        Returns the report as a dict (``overall``, ``per_class``, ``confusions``,
        ``per_query``, ``vocabulary`` …) with its text under ``"text"``. An index whose
        vocabulary was trained on the indexed shapes gives optimistic numbers (the report says
        so): build it with a vocabulary trained on other shapes for an honest evaluation."""
        if isinstance(classes, dict):
            missing = [n for n in self.names if n not in classes]
            if missing:
                raise InvalidInputError(f"classes: no class for {missing[0]!r}", kind="Labels", name="classes")
            classes = [str(classes[n]) for n in self.names]
        elif classes is not None:
            classes = [str(c) for c in classes]
        text_json, text = self._i.evaluate(classes, class_from)
        report: dict[str, Any] = json.loads(text_json)
        report["text"] = text
        return report

    def query_mesh(
        self, V: Any, F: Any = None, k: int = _DEFAULTS["index"]["k"], *, laplacian: str | None = None
    ) -> list[tuple[str, float]]:
        """The k indexed shapes nearest to a mesh ``V, F`` or a point cloud ``V`` (n, 3) alone:
        ``[(name, distance)]``, nearest first.

        The query is described as the indexed shapes were, with the index's Laplacian
        (``settings["vocabulary"]["descriptor"]["laplacian"]``); ``laplacian``, if given, must name it
        (another one raises :class:`InvalidInputError`: its bag would not be comparable)."""
        P = points_of(V, F)
        if P is not None:
            return [(str(n), float(d)) for n, d in self._i.query(P, None, k, laplacian)]
        v, f = as_mesh(V, F)
        return [(str(n), float(d)) for n, d in self._i.query(v, f, k, laplacian)]

    def query_id(self, name: str, k: int = _DEFAULTS["index"]["k"]) -> list[tuple[str, float]]:
        """The k indexed shapes nearest to the **indexed** shape ``name``: ``[(name, distance)]``,
        nearest first, the shape itself left out — as ``wfem retrieval query INDEX --id NAME``.

        Ranked from its stored signature: nothing is read or described again, so it takes
        milliseconds where :meth:`query_mesh` takes the description of a shape. ``name`` is the
        name as indexed (see :attr:`names`), its file name or its stem (``cat0``); one that names
        no indexed shape, or more than one, raises :class:`InvalidInputError` naming the
        candidates."""
        _resolved, hits = self._i.query_id(str(name), int(k))
        return [(str(n), float(d)) for n, d in hits]

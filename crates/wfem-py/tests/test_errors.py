"""Every failure raises a typed wfem exception that keeps the culprit — never a panic, a hang or
a NaN."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import wfem


def tet():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return V, F


def test_hierarchy():
    assert issubclass(wfem.InvalidInputError, ValueError)
    assert issubclass(wfem.MeshError, ValueError)
    assert issubclass(wfem.MeshFileError, OSError) and issubclass(wfem.MeshFileError, wfem.MeshError)
    assert issubclass(wfem.SolverError, RuntimeError)
    assert issubclass(wfem.ConvergenceError, wfem.SolverError)
    assert issubclass(wfem.IllConditionedError, wfem.SolverError)
    assert issubclass(wfem.StoreError, OSError)
    for cls in (wfem.InvalidInputError, wfem.MeshError, wfem.SolverError, wfem.RetrievalError,
                wfem.StoreError, wfem.InternalError):
        assert issubclass(cls, wfem.WfemError)


def test_face_index_out_of_range_names_the_face():
    V, F = tet()
    F = F.copy()
    F[2, 1] = 9
    with pytest.raises(wfem.MeshError) as e:
        wfem.operators(V, F)
    assert e.value.kind == "IndexOutOfRange"
    assert (e.value.face, e.value.index, e.value.n_vertices) == (2, 9, 4)
    assert e.value.details["face"] == 2


def test_negative_index_and_non_finite_vertex():
    V, F = tet()
    with pytest.raises(wfem.InvalidInputError) as e:
        wfem.operators(V, F - 1)
    assert e.value.kind == "NegativeIndex" and e.value.face == 0
    W = V.copy()
    W[3, 1] = np.nan
    with pytest.raises(wfem.MeshError) as e2:
        wfem.HeatKernel(W, F)
    assert e2.value.kind == "NonFiniteCoordinate" and e2.value.vertex == 3


def test_degenerate_face_and_validation_report():
    V, F = tet()
    V = V.copy()
    V[3] = [0.5, 0.5, 0.0]  # face 3 and others become flat? keep: coplanar point
    F = np.vstack([F, [[0, 1, 1]]])
    report = wfem.validate(V, F)
    assert not report.usable
    kinds = {p["kind"] for p in report.problems}
    assert "RepeatedIndex" in kinds
    bad = [p for p in report.problems if p["kind"] == "RepeatedIndex"][0]
    assert bad["face"] == 4 and bad["severity"] == "Error"
    with pytest.raises(wfem.MeshError) as e:
        wfem.HeatKernel(V, F)
    assert e.value.kind in ("RepeatedIndex", "Invalid", "DegenerateFace")


def test_repair_report():
    V, F = tet()
    V2 = np.vstack([V, [[5.0, 5.0, 5.0]]])  # an unreferenced vertex
    with pytest.raises(wfem.MeshError) as e:
        wfem.HeatKernel(V2, F)
    # The remedy in Python's words, also as an attribute (issue #37: remedies are data).
    assert e.value.remedy == "wfem.repair(V, F, drop_unreferenced_vertices=True)"
    assert str(e.value).endswith("; fix: " + e.value.remedy) and "Options::" not in str(e.value)
    V3, F3, report = wfem.repair(V2, F, drop_unreferenced_vertices=True)
    assert report.dropped_vertices == 1 and report.vertex_map[4] is None
    assert not report.unchanged and "unreferenced" in report.summary.lower() or report.summary
    np.testing.assert_array_equal(V3, V)
    wfem.HeatKernel(V3, F3)
    assert V2.shape == (5, 3)  # the input is untouched


@pytest.mark.parametrize("t", [0.0, -1.0, np.inf, np.nan])
def test_bad_time(t):
    K = wfem.HeatKernel(*wfem.generate.icosphere(1))
    with pytest.raises(wfem.InvalidInputError) as e:
        K.apply(np.ones(K.n), t)
    assert e.value.kind == "InvalidTime"
    assert e.value.t == t or (np.isnan(t) and np.isnan(e.value.t))


def test_bad_functions():
    K = wfem.HeatKernel(*wfem.generate.icosphere(1))
    f = np.ones(K.n)
    f[7] = np.nan
    with pytest.raises(wfem.InvalidInputError) as e:
        K.apply(f, 0.1)
    assert e.value.kind == "NonFiniteInput" and e.value.row == 7
    with pytest.raises(wfem.InvalidInputError) as e2:
        K.apply(np.ones(K.n + 1), 0.1)
    assert (e2.value.expected, e2.value.found) == (K.n, K.n + 1)
    with pytest.raises(wfem.InvalidInputError):
        K.apply(np.ones((K.n, 2, 2)), 0.1)
    with pytest.raises(wfem.InvalidInputError):
        K.apply(np.ones(K.n, dtype=complex), 0.1)
    with pytest.raises(wfem.InvalidInputError):
        K.apply(["a"] * K.n, 0.1)
    with pytest.raises(wfem.InvalidInputError):
        K.apply(np.ones(K.n), [])


def test_bad_options():
    V, F = wfem.generate.icosphere(1)
    with pytest.raises(wfem.InvalidInputError) as e:
        wfem.HeatKernel(V, F, method="nonsense")
    assert e.value.name == "method"
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, F, mass="nonsense")
    with pytest.raises(wfem.InvalidInputError) as e2:
        wfem.HeatKernel(V, F, method="rational", degree=9)
    assert e2.value.kind == "UnsupportedDegree" and 16 in e2.value.available
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, F, method="spectral")  # k missing
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, F, method="fast", degree=8)
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(V, F, lumped="nope")
    with pytest.raises(wfem.InvalidInputError) as e3:
        wfem.HeatKernel(V, F).distance(0.1).row(10_000)
    assert e3.value.kind == "VertexOutOfRange" and e3.value.vertex == 10_000
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, F).canonical_basis([-1], 0.1)
    with pytest.raises(wfem.InvalidInputError):
        wfem.eigenbasis(V, F, 0)
    with pytest.raises(wfem.InvalidInputError):
        wfem.generate.grid(1, 5)
    with pytest.raises(wfem.InvalidInputError):
        wfem.generate.icosphere(40)
    with pytest.raises(wfem.InvalidInputError):
        wfem.generate.torus(1.0, 2.0, 10, 10)
    with pytest.raises(wfem.InvalidInputError):
        wfem.sihks(V, F, k=10, tau_step=1e-9)


def test_dense_refused_above_the_limit():
    V, F = wfem.generate.icosphere(5)  # 10242 vertices
    with pytest.raises(wfem.InvalidInputError) as e:
        wfem.eigenbasis(V, F, None)
    assert e.value.kind == "TooLargeForDense" and e.value.limit == wfem.DENSE_MAX_VERTICES


def test_eigensolver_non_convergence_keeps_the_converged_pairs():
    V, F = wfem.generate.bumpy(3)
    with pytest.raises(wfem.ConvergenceError) as e:
        wfem.eigenbasis(V, F, 40, max_dim=48, block_size=2, max_restarts=0)
    err = e.value
    assert err.kind == "EigenNoConvergence" and err.requested == 40 and err.converged < 40
    values, vectors = err.found
    assert len(values) == err.converged and vectors.shape == (len(V), err.converged)


def test_ill_conditioned_inverse_is_refused():
    V, F = wfem.generate.icosphere(2)
    K = wfem.HeatKernel(V, F)
    rough = np.random.default_rng(1).standard_normal(K.n)
    with pytest.raises(wfem.IllConditionedError) as e:
        K.inverse(rough, 1.0)
    assert e.value.kind == "IllConditionedInverse" and e.value.t == 1.0 and e.value.cap == 1e6


def test_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        wfem.read_mesh(tmp_path / "missing.off")
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n")
    with pytest.raises(wfem.MeshError) as e:
        wfem.read_mesh(bad)
    assert e.value.kind == "Parse" and e.value.line == 5 and e.value.path.endswith("bad.off")
    quad = tmp_path / "quad.obj"
    quad.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    with pytest.raises(wfem.MeshError) as e2:
        wfem.read_mesh(quad)
    assert e2.value.kind == "Polygon" and e2.value.corners == 4
    assert "triangulate=True" in str(e2.value) and "LoadOptions" not in str(e2.value)
    V, F = wfem.read_mesh(quad, triangulate=True)
    assert F.shape == (2, 3)
    (tmp_path / "x.xyz").write_text("")
    with pytest.raises(wfem.MeshError) as e3:
        wfem.read_mesh(tmp_path / "x.xyz")
    assert e3.value.kind == "UnknownFormat"
    d = tmp_path / "dir.off"
    d.mkdir()
    with pytest.raises(wfem.MeshFileError) as e4:
        wfem.read_mesh(d)
    assert isinstance(e4.value, OSError) and e4.value.kind == "Io"


def test_exceptions_pickle_with_their_culprit():
    V, F = tet()
    try:
        wfem.operators(V, F + 10)
    except wfem.MeshError as e:
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is type(e) and back.face == e.face and str(back) == str(e) and back.kind == e.kind
    else:
        raise AssertionError("no error")


def test_no_nan_from_extreme_but_valid_input():
    V, F = wfem.generate.icosphere(2)
    K = wfem.HeatKernel(V * 1e-6, F)
    g = K.apply(V[:, 0], 1e-14)
    assert np.isfinite(g).all()
    K2 = wfem.HeatKernel(V * 1e6, F)
    assert np.isfinite(K2.apply(V[:, 0], 1e10)).all()


def test_fill_holes_closes_a_punched_sphere_and_checks_its_bound():
    V, F = wfem.generate.icosphere(3)
    keep = ~np.isin(F, [0, 40]).any(axis=1)
    V1, F1, report = wfem.repair(V, F[keep], drop_unreferenced_vertices=True)
    assert wfem.mesh_stats(V1, F1)["n_boundary_loops"] == 2
    V2, F2, closed = wfem.fill_holes(V1, F1)
    assert closed == 2
    np.testing.assert_array_equal(V2[: len(V1)], V1)
    np.testing.assert_array_equal(F2[: len(F1)], F1)
    stats = wfem.mesh_stats(V2, F2)
    assert stats["n_boundary_loops"] == 0 and stats["genus"] == 0
    def area(V, F):
        return 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()

    assert abs(area(V2, F2) - area(V, F)) < 0.01 * area(V, F)
    # Nothing to do on a closed mesh; a bound that is not a positive number is refused.
    assert wfem.fill_holes(V, F)[2] == 0
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(wfem.InvalidInputError):
            wfem.fill_holes(V1, F1, max_perimeter=bad)

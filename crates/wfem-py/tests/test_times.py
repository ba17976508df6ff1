"""Issue #25: times in a unit of the mesh (``time_unit=``) and a ``wfem.TimeWarning`` for a
time whose result carries no information."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import wfem


def small_sphere():
    V, F = wfem.generate.icosphere(3)
    return V * np.sqrt(0.057 / wfem.mesh_stats(V, F)["area"]), F


def test_units_scale_the_times():
    V, F = small_sphere()
    K = wfem.HeatKernel(V, F)
    s = wfem.mesh_stats(V, F)
    f = np.zeros(len(V))
    f[0] = 1.0
    t = 1e-3
    by_area = K.apply(f, t / s["area"], time_unit="area")
    by_edge = K.apply(f, t / s["mean_edge_length"] ** 2, time_unit="edge")
    plain = K.apply(f, t)
    assert np.allclose(by_area, plain, rtol=0, atol=1e-12)
    assert np.allclose(by_edge, plain, rtol=0, atol=1e-12)
    h_area = wfem.hks(V, F, times=[t / s["area"]], time_unit="AREA", method="exact")
    h = wfem.hks(V, F, times=[t], method="exact")
    assert np.allclose(h_area, h, rtol=1e-12, atol=0)
    with pytest.raises(wfem.InvalidInputError, match="time unit"):
        K.apply(f, t, time_unit="fortnight")


def test_meaningless_times_warn():
    V, F = small_sphere()
    K = wfem.HeatKernel(V, F)
    f = np.zeros(len(V))
    f[0] = 1.0
    with pytest.warns(wfem.TimeWarning, match="past the time at infinity") as record:
        g = K.apply(f, 0.1)
    assert "sensible times for this mesh" in str(record[0].message)
    assert np.ptp(g) <= 1e-11 * np.max(np.abs(g))  # the warning is true: constant
    with pytest.warns(wfem.TimeWarning, match=r"time_unit='area'"):
        K.apply(f, 100.0, time_unit="area")
    with pytest.warns(wfem.TimeWarning, match="too small"):
        K.apply(f, 1e-20)
    with pytest.warns(wfem.TimeWarning, match="past the time at infinity"):
        K.distance(0.1).row(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", wfem.TimeWarning)
        K.apply(f, 1e-3)
        K.distance(1e-3)
    # Given operators: no mesh, the area unit from M, no edge unit; negligible times only.
    L, B, _ = wfem.operators(V, F)
    K2 = wfem.HeatKernel.from_operators(L, B)
    with pytest.warns(wfem.TimeWarning, match="too small"):
        K2.apply(f, 1e-20)
    with pytest.raises(wfem.InvalidInputError, match="needs the mesh"):
        K2.apply(f, 1.0, time_unit="edge")

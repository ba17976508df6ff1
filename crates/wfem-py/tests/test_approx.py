"""Issue #24: the feature-driven approximation (paper Sect. 4.2) from Python, on the small cases
of the benchmark (docs/APPROX-RESULTS.md, `cargo xtask approx-eval`): the defaults meet the paper's
2 % at the finest scale, keep f's values at the anchors, record what defines f_glob, and warn with
the option to change."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import wfem

# shrec_bench::approx_eval::SMALL_CASES
SMALL_CASES = ["shrec07-fourleg/398.off", "common-3d-test-models/spot.obj"]


def check_default(out: dict, f: np.ndarray) -> None:
    assert out["coefficients"] == wfem.APPROX_COEFFICIENTS[0] == "anchored"
    assert out["sampling"] == wfem.APPROX_SAMPLINGS[0]
    assert out["warning"] is None
    scales = out["scales"]
    assert len(scales) == 10
    assert abs(scales[0]["t"] * out["lambda_max"] - 1) < 1e-12
    assert abs(scales[-1]["t"] * out["lambda_k"] - 1) < 1e-12
    assert all(a["t"] < b["t"] for a, b in zip(scales, scales[1:]))
    assert scales[0]["relative_linf_error"] < 0.02
    rng = np.ptp(f)
    anchors = np.asarray(out["anchors"])
    for s in scales:
        np.testing.assert_allclose(s["global_"] + s["local"], f, atol=1e-12 * np.max(np.abs(f)))
        assert len(s["anchors"]) == len(s["coefficients"])
        kept = np.asarray(s["anchors"], dtype=int)
        assert np.max(np.abs(s["global_"][kept] - f[kept]), initial=0) <= 1e-6 * rng
        if len(kept) == len(anchors):
            assert s["anchor_error"] <= 1e-6
        assert s["persistent_extrema"] <= out["persistent_extrema"]


@pytest.mark.parametrize("rel", SMALL_CASES)
def test_issue_24_defaults_on_the_benchmark_small_cases(corpus, rel):
    V, F = wfem.read_mesh(corpus / rel)
    K = wfem.HeatKernel(V, F)
    z = np.ascontiguousarray(V[:, 2])
    with warnings.catch_warnings():
        warnings.simplefilter("error", wfem.ApproximationWarning)
        out = K.feature_approximation(z)
        check_default(out, z)
        # The diffusion distance from the highest vertex at t = 1/λ₂₀ (a benchmark field).
        d = K.distance(1.0 / out["lambda_k"]).row(int(np.argmax(z)))
        check_default(K.feature_approximation(d), d)
    # The noisy coordinate (5 % of the range): the warning names the persistence and the
    # smooth rule.
    noisy = z + 0.05 * np.ptp(z) * np.random.default_rng(24).standard_normal(len(z))
    with pytest.warns(wfem.ApproximationWarning, match=r"persistence=.*coefficients=\"smooth\""):
        K.feature_approximation(noisy)
    smooth = K.feature_approximation(noisy, coefficients="smooth")
    assert smooth["warning"] is None and all(s["anchors"] == [] for s in smooth["scales"])
    # The paper's printed formula on its scales: far from f, and the warning says what to use.
    with pytest.warns(wfem.ApproximationWarning, match="coefficients=\"anchored\""):
        literal = K.feature_approximation(z, coefficients="feature-values", sampling="paper")
    assert min(s["relative_linf_error"] for s in literal["scales"]) > 0.3
    assert literal["lambda_max"] is None
    for s in literal["scales"]:
        np.testing.assert_allclose(s["coefficients"], z[np.asarray(s["anchors"], dtype=int)])


def test_feature_approximation_rejects_unknown_names():
    V, F = wfem.generate.bumpy(2)
    K = wfem.HeatKernel(V, F)
    f = V[:, 2]
    with pytest.raises(wfem.InvalidInputError, match="coefficients"):
        K.feature_approximation(f, coefficients="magic")
    with pytest.raises(wfem.InvalidInputError, match="sampling"):
        K.feature_approximation(f, sampling="log")
    with pytest.raises(wfem.InvalidInputError, match="absolute"):
        K.feature_approximation(f, absolute=True)
    assert set(wfem.APPROX_COEFFICIENTS) >= {"anchored", "feature-values", "smooth"}

"""Issues #24 and #40: the feature-driven approximation (paper Sect. 4.2) from Python, on the
small cases of the benchmark (docs/APPROX-RESULTS.md, `cargo xtask approx-eval`): the defaults meet
the paper's 2 % at the finest scale on smooth maps, keep f's values at the anchors, record what
defines f_glob, denoise a noisy map without options (reporting t* and σ̂), and warn with the
option to change."""

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
    assert out["noise_rule"] == wfem.APPROX_NOISE_RULES[0] == "auto"
    # A smooth map: the noise is estimated, and f is taken as clean.
    assert out["chosen"] is None and out["noise"]["sigma"] >= 0
    np.testing.assert_array_equal(out["anchor_values"], f[np.asarray(out["anchors"], dtype=int)])
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
    # The noisy coordinate (5 % of the range): the default denoises it without options.
    sigma = 0.05 * np.ptp(z)
    noise = sigma * np.random.default_rng(24).standard_normal(len(z))
    noisy = z + noise
    with warnings.catch_warnings():
        warnings.simplefilter("error", wfem.ApproximationWarning)
        out = K.feature_approximation(noisy)
    chosen = out["scales"][out["chosen"]]
    assert chosen["t"] == out["noise"]["t"] and len(out["scales"]) == 11
    assert abs(out["noise"]["sigma"] - sigma) < 0.15 * sigma
    # Closer to the clean map than f (on the coarse SHREC'07 398 the RMS error is about half σ).
    assert np.max(np.abs(chosen["global_"] - z)) < np.max(np.abs(noise))
    assert np.sqrt(np.mean((chosen["global_"] - z) ** 2)) < 0.7 * sigma
    assert np.corrcoef(chosen["local"], noise)[0, 1] > 0.8
    # Taken as clean, the anchors keep the noise: the warning names the noise rule.
    with pytest.warns(wfem.ApproximationWarning, match=r"noise=\"auto\".*persistence="):
        kept = K.feature_approximation(noisy, noise="keep")
    assert kept["noise"] is None and kept["chosen"] is None
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
    with pytest.raises(wfem.InvalidInputError, match="noise"):
        K.feature_approximation(f, noise="off")
    with pytest.raises(wfem.InvalidInputError, match="absolute"):
        K.feature_approximation(f, absolute=True)
    assert set(wfem.APPROX_COEFFICIENTS) >= {"anchored", "feature-values", "smooth"}


def test_scales_is_the_old_name_of_num_times():
    """Issue #37, point 4: the number of times is `num_times` (a scale is never a time); the
    old keyword `scales=` still works for one release, with a warning."""
    V, F = wfem.generate.bumpy(2)
    K = wfem.HeatKernel(V, F)
    f = V[:, 2]
    new = K.feature_approximation(f, num_times=3, noise="keep")
    with pytest.warns(DeprecationWarning, match="old name of num_times"):
        old = K.feature_approximation(f, scales=3, noise="keep")
    assert len(new["scales"]) == len(old["scales"]) == 3
    np.testing.assert_array_equal(new["scales"][-1]["global_"], old["scales"][-1]["global_"])
    with pytest.raises(wfem.InvalidInputError, match="not both"), pytest.warns(DeprecationWarning):
        K.feature_approximation(f, scales=3, num_times=3)

"""Vocabularies, bags (plain and spatially sensitive), k-means and retrieval metrics."""

from __future__ import annotations

import numpy as np
import pytest

import wfem


def test_vocabulary_and_bags():
    rng = np.random.default_rng(0)
    D = np.vstack([rng.normal(c, 0.05, size=(50, 3)) for c in (0.0, 1.0, 2.0)])
    voc = wfem.Vocabulary.train(D, 3, seed=1)
    assert voc.size == 3 and voc.words.shape == (3, 3) and voc.sigma > 0
    theta = voc.soft_assignment(D)
    np.testing.assert_allclose(theta.sum(axis=1), 1.0, rtol=1e-12)
    w = np.ones(len(D))
    bag = voc.bag(D, w)
    np.testing.assert_allclose(bag.sum(), 1.0, rtol=1e-12)
    np.testing.assert_allclose(np.sort(bag), [1 / 3] * 3, atol=0.02)
    np.testing.assert_allclose(voc.bag(D, w, normalize=False), theta.T @ w, rtol=1e-12)
    same = wfem.Vocabulary(voc.words, voc.sigma)
    np.testing.assert_array_equal(same.soft_assignment(D), theta)
    with pytest.raises(wfem.InvalidInputError):
        wfem.Vocabulary.train(D[:2], 3)
    with pytest.raises(wfem.InvalidInputError):
        voc.bag(D[:, :2], w)


def test_spatially_sensitive_bag_sums_to_the_area():
    V, F = wfem.generate.bumpy(2)
    K = wfem.HeatKernel(V, F)
    D = wfem.descriptor(V, F, "dhk2", k=20, times=[0.1, 1.0])
    voc = wfem.Vocabulary.train(D, 5, seed=0)
    S = voc.spatially_sensitive_bag(D, K, 0.1)
    assert S.shape == (5, 5)
    np.testing.assert_allclose(S.sum(), K.vertex_areas.sum(), rtol=1e-10)
    np.testing.assert_allclose(S, S.T, atol=1e-10 * abs(S).max())


def test_kmeans_metrics_and_map():
    rng = np.random.default_rng(2)
    P = np.vstack([rng.normal(c, 0.01, size=(20, 2)) for c in ((0, 0), (5, 5))])
    km = wfem.kmeans(P, 2, seed=0)
    assert km["converged"] and len(set(km["assignment"][:20])) == 1
    bags = np.array([[1, 0, 0], [0.9, 0.1, 0], [0, 1, 0], [0, 0.9, 0.1]], dtype=float)
    Dm = wfem.pairwise_l1(bags)
    assert Dm.shape == (4, 4) and Dm[0, 1] == pytest.approx(0.2)
    assert wfem.l1_distance(bags[0], bags[2]) == pytest.approx(2.0)
    r = wfem.evaluate(Dm, [0, 0, 1, 1])
    assert r["mean_average_precision"] == 1.0 and wfem.mean_average_precision(Dm, [0, 0, 1, 1]) == 1.0
    assert r["per_class"] == {0: (1.0, 2), 1: (1.0, 2)}
    assert wfem.average_precision([True, False, True]) == pytest.approx((1 + 2 / 3) / 2)
    assert wfem.average_precision([False]) is None

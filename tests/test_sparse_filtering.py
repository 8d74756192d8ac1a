"""Ground truth of sparse filtering (armlab.estimation.sparse_filtering; Ngiam et al. 2011, the
unsupervised layers of seed paper 001's phi): the analytic gradient, and the recovery of sparse
sources mixed into the inputs."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from armlab.estimation.sparse_filtering import fit_sparse_filter, sparse_filter_loss


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(0)
    X, k = rng.normal(size=(40, 5)), 3
    w = rng.normal(size=k * 5)
    _, grad = sparse_filter_loss(w, X, k)
    eps = 1e-6  # central differences: truncation ~eps^2, rounding ~1e-16 |f| / eps ~ 1e-9
    fd = np.array(
        [
            (sparse_filter_loss(w + e, X, k)[0] - sparse_filter_loss(w - e, X, k)[0]) / (2 * eps)
            for e in eps * np.eye(w.size)
        ]
    )
    assert_allclose(grad, fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())


def test_one_active_source_per_example_gives_one_feature_per_source():
    """x = A s with exactly one of 4 sources active per example: the trained layer answers each
    pure source direction with one feature alone (a permutation), and the objective reaches its
    floor n (every example one-hot, l1 = 1). The objective is not convex: another start can stop
    with one source split over two features (seen with generator seed 1); this seed's does not."""
    rng = np.random.default_rng(0)
    k, d, n = 4, 8, 2000
    A = rng.normal(size=(d, k))
    S = np.zeros((n, k))
    S[np.arange(n), rng.integers(k, size=n)] = rng.exponential(1.0, n) * rng.choice([-1.0, 1.0], n)
    X = S @ A.T
    sf = fit_sparse_filter(X, (k,), rng, max_iter=400)
    Y = sf(A.T)  # (k sources, k features)
    assert_allclose(np.sort(Y.max(axis=1)), 1.0, atol=1e-3)  # each source one feature
    assert sorted(np.argmax(Y, axis=1)) == list(range(k))  # a permutation
    assert sparse_filter_loss(sf.weights[0].ravel(), X, k)[0] < 1.01 * n
    two = fit_sparse_filter(X, (6, 4), rng, max_iter=100)  # stacked: the last layer's size, unit rows
    assert_allclose(np.linalg.norm(two(X[:5]), axis=1), 1.0)

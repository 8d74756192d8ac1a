"""Tests for armlab.estimation.spd_stiffness (seed paper 001, Eqs. (16)-(19)): the spec's acceptance
check 3 against a direct numerical minimisation of the area criterion, on displacement/torque data
from the arm's true stiffness (models/arm_5dof) with noise, so the data are not exactly SPD-consistent."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import optimize

from armlab.errors import DataError, EstimationError
from armlab.estimation import area_criterion, chen_mcinroy, symmetric_part
from armlab.models import analytic_stiffness, load_arm_5dof

ARM = load_arm_5dof()


def _data(seed: int, n: int = 50, noise: float = 0.3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """50 disturbances of ~0.08 rad along +-each joint (paper Sec. 3) with 10 % cross-talk between
    joints, torque changes from the true K plus `noise` N m of error."""
    rng = np.random.default_rng(seed)
    K = analytic_stiffness(ARM, rng.uniform(0.05, 0.3, 12))
    dirs = np.eye(5)[rng.integers(0, 5, n)] * rng.choice([-1, 1], (n, 1))
    A = 0.08 * dirs + 0.008 * rng.normal(size=(n, 5))
    B = A @ K.T + noise * rng.normal(size=(n, 5))
    return A, B, K


def _numeric_minimum(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """argmin of f(Y)^2 = tr(P X) + tr(Q X^-1) - 2 tr(A^T B) over X = L L^T (Eq. (16)), BFGS on the
    15 entries of a lower-triangular L with the analytic gradient."""
    P, Q = A.T @ A, B.T @ B
    il = np.tril_indices(5)
    scale = np.trace(Q) / np.trace(P)

    def fg(x: np.ndarray) -> tuple[float, np.ndarray]:
        L = np.zeros((5, 5))
        L[il] = x
        X = L @ L.T
        Xi = np.linalg.inv(X)
        f = np.trace(P @ X) + np.trace(Q @ Xi)
        dX = P - Xi @ Q @ Xi  # d f / d X (symmetric)
        return f, (2 * dX @ L)[il]

    x0 = np.linalg.cholesky(np.sqrt(scale) * np.eye(5))[il]
    sol = optimize.minimize(fg, x0, jac=True, method="BFGS", options={"gtol": 1e-13, "maxiter": 20000})
    L = np.zeros((5, 5))
    L[il] = sol.x
    return L @ L.T


@pytest.mark.parametrize("seed", range(5))
def test_closed_form_solves_xpx_q_and_equals_the_numeric_minimum(seed):
    A, B, K = _data(seed)
    sol = chen_mcinroy(A, B)
    # spec check 3: residual < 1e-10, symmetric, smallest eigenvalue > 0, equal to a numeric
    # minimisation of (16) within 1e-6 (relative Frobenius)
    assert sol.residual < 1e-10
    assert_allclose(sol.K, sol.K.T, atol=0)
    assert sol.eigenvalues.min() > 0
    X = _numeric_minimum(A, B)
    assert np.linalg.norm(X - sol.K) / np.linalg.norm(sol.K) < 1e-6
    # the area criterion (16) itself is no smaller anywhere near the solution
    Y = np.linalg.cholesky(sol.K)
    f0 = area_criterion(Y, A, B)
    rng = np.random.default_rng(seed)
    for _ in range(20):
        assert area_criterion(Y + 1e-4 * np.tril(rng.normal(size=(5, 5))), A, B) >= f0
    # noise-free data: the true K back exactly
    exact = chen_mcinroy(A, A @ K.T)
    assert_allclose(exact.K, K, rtol=1e-9, atol=1e-9 * np.abs(K).max())


def test_spd_even_when_least_squares_is_not():
    A, B, K = _data(7, n=12, noise=3.0)  # few, very noisy disturbances
    ls = np.linalg.lstsq(A, B, rcond=None)[0].T
    sol = chen_mcinroy(A, B)
    assert sol.eigenvalues.min() > 0
    # the plain least-squares solution is indefinite: its symmetric part has a negative eigenvalue
    assert np.linalg.eigvalsh(symmetric_part(ls)).min() < 0


def test_bad_input_is_refused():
    A, B, _ = _data(0)
    with pytest.raises(DataError, match="same shape"):
        chen_mcinroy(A, B[:, :4])
    with pytest.raises(EstimationError, match="at least"):
        chen_mcinroy(A[:3], B[:3])
    with pytest.raises(EstimationError, match="P = A\\^T A is singular"):
        chen_mcinroy(np.c_[A[:, :4], np.zeros(len(A))], B)
    with pytest.raises(DataError, match="NaN"):
        chen_mcinroy(A * np.nan, B)

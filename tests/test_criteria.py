"""Checks of the confidence criteria of Sec. III-C and IV-D."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ConfigError, DataError
from armlab.estimation import (
    CriteriaConfig,
    asymmetry,
    condition_number,
    eig_symmetric_part,
    first_satisfied,
    is_positive_definite,
    quasi_constant_flags,
    relative_error,
    symmetric_part,
)

K = np.array([[15.0, 6.0], [6.0, 16.0]])


def test_condition_number_matches_singular_values():
    rng = np.random.default_rng(0)
    # a matrix with prescribed singular values 1e3 ... 1: cond = 1e3 exactly
    U, _ = np.linalg.qr(rng.normal(size=(40, 4)))
    V, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    W = U @ np.diag([1e3, 10.0, 2.0, 1.0]) @ V.T
    assert condition_number(W) == pytest.approx(1e3, rel=1e-10)
    batch = np.stack([W, np.eye(40, 4)])
    assert_allclose(condition_number(batch), [1e3, 1.0], rtol=1e-10)
    assert condition_number(np.array([[1.0, 2.0], [2.0, 4.0]])) >= 1e15  # rank 1: inf or round-off
    assert np.isinf(condition_number(np.zeros((3, 2))))


def test_symmetric_part_and_eigenvalues():
    A = np.array([[2.0, 3.0], [1.0, 2.0]])
    assert_allclose(symmetric_part(A), [[2.0, 2.0], [2.0, 2.0]])
    assert_allclose(eig_symmetric_part(A), [0.0, 4.0], atol=1e-14)  # ascending
    lam = eig_symmetric_part(np.stack([K, -K]))
    assert lam.shape == (2, 2) and np.all(np.diff(lam, axis=-1) >= 0)
    assert_allclose(lam[0], np.linalg.eigvalsh(K))


def test_positive_definiteness_uses_the_symmetric_part():
    assert is_positive_definite(K) is True
    # a large skew part does not matter: dq^T A dq = dq^T A_s dq (Eq. (20))
    assert is_positive_definite(np.array([[1.0, 5.0], [-5.0, 1.0]])) is True
    assert is_positive_definite(np.array([[1.0, 3.0], [3.0, 1.0]])) is False  # eigenvalues -2, 4
    assert is_positive_definite(np.zeros((2, 2))) is False
    assert is_positive_definite(np.stack([K, -K])).tolist() == [True, False]


def test_asymmetry():
    assert asymmetry(K) == 0.0
    assert asymmetry(np.zeros((2, 2))) == 0.0
    assert np.isinf(asymmetry(np.array([[0.0, 1.0], [-1.0, 0.0]])))
    A = np.array([[10.0, 2.0], [0.0, 10.0]])
    # |A - A^T|_F = sqrt(8), |A + A^T|_F = sqrt(400 + 400 + 8)
    assert asymmetry(A) == pytest.approx(np.sqrt(8) / np.sqrt(808))
    with pytest.raises(DataError, match=r"square matrices \(\.\.\., n, n\)"):
        asymmetry(np.zeros((2, 3)))


def test_first_satisfied():
    t = np.array([0.12, 0.13, 0.14, 0.15, 0.16])
    assert first_satisfied(t, np.array([False, True, False, True, True])) == pytest.approx(0.15)
    assert first_satisfied(t, np.ones(5, dtype=bool)) == pytest.approx(0.12)
    assert first_satisfied(t, np.array([True, True, True, True, False])) is None
    with pytest.raises(DataError, match="strictly increasing"):
        first_satisfied(t[::-1], np.ones(5, dtype=bool))
    with pytest.raises(DataError, match="bool flags"):
        first_satisfied(t, np.ones(5))


def test_quasi_constant_flags_converging_sequence():
    # parameters converge: the change to the next window halves each time (0.64, ..., 0.005)
    n = 9
    base = np.concatenate([[0.391, 0.155, 0.149], [2.3, 0.9, 0.9, 2.4], K.ravel()])
    drift = 0.64 * 0.5 ** np.arange(n)
    params = base + np.cumsum(drift)[:, None] * np.ones(11)
    flags = quasi_constant_flags(params, tol=0.05)
    # the xi block is the tightest: the change to the next window |dp| = drift[k + 1] against
    # 0.05 |xi_k| (by hand): k = 0: 0.32 > 0.05 * 1.52; k = 1: 0.16 > 0.05 * 2.07; k = 2: 0.08 <
    # 0.05 * 2.35, and the drift keeps halving while |xi_k| grows; the last window repeats the
    # previous change
    expected = np.array([False, False, True, True, True, True, True, True, True])
    assert flags.tolist() == expected.tolist()
    assert not flags[0] and flags[-1]
    t = np.arange(n) * 0.01 + 0.12
    assert first_satisfied(t, flags) == pytest.approx(t[np.argmax(expected)])


def test_quasi_constant_flags_block_scaling():
    # an off-diagonal stiffness near 0 may change by 0.3 N·m/rad: small against |K|_F ~ 31
    p = np.tile(np.concatenate([[2.3, 0.9, 0.9, 2.4], [15.0, 0.01, 0.01, 16.0]]), (3, 1))
    p[1, 5] = 0.31
    assert quasi_constant_flags(p, tol=0.05).all()
    p[1, 4] = 17.0  # K11 changes by 2, more than 5 % of |K| ~ 22
    assert quasi_constant_flags(p, tol=0.05).tolist() == [False, False, False]
    with pytest.raises(ConfigError, match="partition the 8 parameters"):
        quasi_constant_flags(p, tol=0.05, blocks=[slice(0, 4)])
    with pytest.raises(DataError, match=r"n_windows >= 1"):
        quasi_constant_flags(p[:0], tol=0.05)
    assert quasi_constant_flags(p[:1], tol=0.05).tolist() == [False]  # nothing to compare with


def test_relative_error():
    assert relative_error(K * 1.01, K) == pytest.approx(0.01)
    with pytest.raises(DataError, match="all-zero ground truth"):
        relative_error(K, np.zeros((2, 2)))
    with pytest.raises(DataError, match="same shape"):
        relative_error(K, K[0])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(symmetry_tol=0.0), r"symmetry_tol must lie in \(0, 1\]"),
        (dict(symmetry_tol=1.5), r"symmetry_tol must lie in \(0, 1\]"),
        (dict(constancy_tol=-0.1), "constancy_tol must be a positive"),
    ],
)
def test_criteria_config_validation(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        CriteriaConfig(**kwargs)
    assert CriteriaConfig() == CriteriaConfig(symmetry_tol=0.1, constancy_tol=0.05)


def test_public_api_resolves():
    import importlib
    import pkgutil

    import armlab.estimation as est
    import armlab.estimation.processing as proc
    import armlab.estimation.smoothing as sm

    # every module of the package (some share their names with the functions it exports)
    modules = [
        importlib.import_module(f"armlab.estimation.{info.name}")
        for info in pkgutil.iter_modules(est.__path__)
    ]
    for module in (est, *modules):
        assert all(hasattr(module, name) for name in module.__all__), module.__name__
    # smoothing.differentiate is exported as sg_differentiate (processing.differentiate keeps the name)
    assert set().union(*(m.__all__ for m in modules)) | {"sg_differentiate"} == set(est.__all__)
    assert est.sg_differentiate is sm.differentiate and est.differentiate is proc.differentiate


def test_quasi_constant_flags_per_second_of_window():
    # windows 10 ms apart, then a 50 ms extension step; every step changes the parameter by 4 %
    # of its norm. Per step (tol 0.05) all pass; per second (tol 5/s: 5 % per 10 ms, 25 % per
    # 50 ms) the 10 ms steps pass too; at 2/s (2 % per 10 ms) only the 50 ms step (allowed 10 %)
    # passes, i.e. a step is judged by its change per unit of T_obs, not per window
    t = np.array([0.35, 0.36, 0.37, 0.42])
    p = np.array([[1.0], [1.04], [1.0816], [1.124864]])
    assert quasi_constant_flags(p, tol=0.05).all()
    assert quasi_constant_flags(p, tol=5.0, t_obs=t).all()
    assert quasi_constant_flags(p, tol=2.0, t_obs=t).tolist() == [False, False, True, True]
    with pytest.raises(DataError, match="strictly increasing"):
        quasi_constant_flags(p, tol=5.0, t_obs=t[::-1])

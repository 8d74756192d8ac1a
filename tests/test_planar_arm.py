"""Ground-truth checks of the analytic planar two-link arm."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import DataError
from armlab.estimation.joint_ls import regressor
from armlab.models.planar_arm import (
    coriolis_matrix,
    coriolis_torque,
    forward,
    inverse,
    inverse_dynamics,
    jacobian,
    mass_matrix,
    xi_from_segments,
)

L1, L2 = 0.31, 0.34  # m, adult upper arm and forearm+hand
# Segment properties (kg, m, kg·m²) of a plausible adult arm; only used as consistent ground truth.
SEG = dict(m1=1.9, lc1=0.14, I1=0.013, m2=1.5, lc2=0.18, I2=0.020, l1=L1)


def _random_q(rng: np.random.Generator, n: int) -> np.ndarray:
    # q2 kept away from 0 and pi, where the elbow is singular and IK loses digits
    return np.stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(0.1, np.pi - 0.1, n)], axis=-1)


def test_forward_known_postures():
    assert_allclose(forward(np.array([0.0, 0.0]), L1, L2), [L1 + L2, 0.0], atol=1e-15)
    assert_allclose(forward(np.array([np.pi / 2, np.pi / 2]), L1, L2), [-L2, L1], atol=1e-15)


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(0)
    q = _random_q(rng, 50)
    h = 1e-6
    fd = np.stack(
        [(forward(q + h * e, L1, L2) - forward(q - h * e, L1, L2)) / (2 * h) for e in np.eye(2)], axis=-1
    )
    # central differences: truncation h²/6·|x'''| <= 1e-12 m/rad, round-off eps·|x|/h ~ 1e-10
    assert_allclose(jacobian(q, L1, L2), fd, atol=1e-8)


def test_inverse_round_trip_and_broadcasting():
    rng = np.random.default_rng(1)
    q = _random_q(rng, 200).reshape(10, 20, 2)
    q_back = inverse(forward(q, L1, L2), L1, L2)
    assert q_back.shape == q.shape
    # exact analytic inverse; round-off amplified by 1/sin(q2) <= 10
    assert_allclose(q_back, q, atol=1e-10)


def test_inverse_extended_branch():
    rng = np.random.default_rng(2)
    x = forward(_random_q(rng, 30), L1, L2)
    q = inverse(x, L1, L2, elbow="extended")
    assert np.all(q[:, 1] < 0)
    assert_allclose(forward(q, L1, L2), x, atol=1e-12)


def test_inverse_rejects_unreachable_points_and_bad_branch():
    with pytest.raises(DataError, match=r"unreachable.*valid range \[0.03, 0.65\] m"):
        inverse(np.array([[0.2, 0.1], [0.7, 0.0]]), L1, L2)
    with pytest.raises(DataError, match="unreachable"):
        inverse(np.array([0.0, 0.01]), L1, L2)
    with pytest.raises(DataError, match=r"elbow must be one of \('flexed', 'extended'\)"):
        inverse(np.array([0.3, 0.3]), L1, L2, elbow="up")


def _kinetic_energy_from_segments(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Kinetic energy from centre-of-mass velocities (independent of the xi parametrisation)."""
    q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
    w1, w12 = qd[..., 0], qd[..., 0] + qd[..., 1]
    v1 = SEG["lc1"] * w1  # upper-arm COM moves on a circle
    v_elbow = (L1 * w1)[..., None] * np.stack([-np.sin(q1), np.cos(q1)], -1)
    v2 = v_elbow + SEG["lc2"] * w12[..., None] * np.stack([-np.sin(q12), np.cos(q12)], -1)
    return 0.5 * (SEG["m1"] * v1**2 + SEG["I1"] * w1**2 + SEG["m2"] * np.sum(v2**2, -1) + SEG["I2"] * w12**2)


def test_mass_matrix_matches_segment_kinetic_energy():
    rng = np.random.default_rng(3)
    q, qd = _random_q(rng, 100), rng.normal(size=(100, 2))
    xi = xi_from_segments(**SEG)
    M = mass_matrix(q, xi)
    energy = 0.5 * np.einsum("ni,nij,nj->n", qd, M, qd)
    assert_allclose(energy, _kinetic_energy_from_segments(q, qd), rtol=1e-12)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    assert_allclose(M, np.swapaxes(M, -1, -2))


def test_coriolis_passivity_and_power_balance():
    xi = xi_from_segments(**SEG)
    rng = np.random.default_rng(4)
    q, qd = _random_q(rng, 20), rng.normal(size=(20, 2))
    # dM/dt - 2C is skew-symmetric; dM/dt = dM/dq2 * qd2 by central differences (exact for cos to 1e-10)
    h = 1e-6
    dM = (mass_matrix(q + [0, h], xi) - mass_matrix(q - [0, h], xi)) / (2 * h) * qd[:, 1, None, None]
    N = dM - 2 * coriolis_matrix(q, qd, xi)
    assert_allclose(N, -np.swapaxes(N, -1, -2), atol=1e-8)
    assert_allclose(coriolis_torque(q, qd, xi), np.einsum("nij,nj->ni", coriolis_matrix(q, qd, xi), qd))

    # along a smooth trajectory the power qd·tau equals dT/dt (no gravity in the transversal plane)
    t = np.linspace(0.0, 1.0, 4001)
    dt = t[1] - t[0]
    w = 2 * np.pi * 1.3
    q = np.stack([0.1 + 0.4 * np.sin(w * t), 1.2 + 0.5 * np.cos(w * t)], -1)
    qd = np.stack([0.4 * w * np.cos(w * t), -0.5 * w * np.sin(w * t)], -1)
    qdd = np.stack([-0.4 * w**2 * np.sin(w * t), -0.5 * w**2 * np.cos(w * t)], -1)
    power = np.sum(qd * inverse_dynamics(q, qd, qdd, xi), -1)
    dT = np.gradient(_kinetic_energy_from_segments(q, qd), dt, edge_order=2)
    # second-order differences with dt = 0.25 ms: error ~dt²·|T'''| ~ 1e-6 of the peak power
    assert_allclose(dT[5:-5], power[5:-5], atol=1e-5 * np.max(np.abs(power)))


def test_regressor_times_parameters_is_inverse_dynamics():
    rng = np.random.default_rng(5)
    q = _random_q(rng, 64).reshape(8, 8, 2)
    qd, qdd, dq = (rng.normal(size=(8, 8, 2)) for _ in range(3))
    xi = np.array([0.391, 0.155, 0.149])
    K = np.array([[15.0, 6.0], [6.5, 16.0]])
    D = np.array([[2.3, 0.9], [0.8, 2.4]])
    zeta = np.concatenate([xi, D.ravel(), K.ravel()])
    X = regressor(q, qd, qdd, dq)
    assert X.shape == (8, 8, 2, 11)
    expected = inverse_dynamics(q, qd, qdd, xi) + qd @ D.T + dq @ K.T
    assert_allclose(X @ zeta, expected, rtol=1e-12, atol=1e-12)


def test_public_api_resolves():
    import armlab.models.planar_arm as arm

    assert all(callable(getattr(arm, name)) for name in arm.__all__)

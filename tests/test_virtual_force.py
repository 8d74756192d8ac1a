"""Ground-truth recovery of the virtual force sensor, Eq. (2), and the fits of Eqs. (5)-(9) and the Appendix.

Synthetic data are sums of sinusoids with analytic derivatives, so every signal is exact to round-off;
Cartesian signals of the robot come from ``CapstanDynamics.fk/jacobian/jacobian_dot`` themselves, which
keeps the tests independent of the base-frame convention.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ConfigError, DataError, EstimationError
from armlab.estimation.virtual_force import (
    fit_arm,
    fit_fixture,
    identify_robot,
    table_vi,
    vaf,
    virtual_force,
)
from armlab.models.capstan_robot import HANDLE_MASS_KG, TABLE_VI_ALPHA, CapstanDynamics

FS = 1000.0  # Hz, the paper's loop rate
DYN = CapstanDynamics()
HOME = np.array([np.pi / 4, np.pi / 4])  # rad, the symmetric home pose
# Table I, K1 / M1 (X0 taken as a point in the workspace, the numbers as in the table).
FIX = dict(m=0.539, k_xx=421.57, k_yy=213.35, k_s=-18.87, x0=np.array([0.364, -0.009]))
# Table V-like arm impedance: full, non-symmetric matrices.
ARM_M = np.array([[1.4, 0.7], [0.7, 1.0]])  # kg
ARM_B = np.array([[11.0, 3.0], [3.0, 4.0]])  # N·s/m
ARM_K = np.array([[72.0, 6.0], [16.0, 13.0]])  # N/m
ARM_XV = np.array([0.38, 0.02])  # m
# Exact data: LS on ~1e5 rows with a scaled condition number below 1e3 is accurate to ~1e-13
# relative; 1e-8 leaves ample margin while catching any modelling error (e.g. a forgotten term).
EXACT = dict(rtol=1e-8)


def _multisine(t, amp, seed, f_max=2.0):
    """Sum of ten sinusoids per column in (0, f_max] Hz, peak |value| <= amp; (pos, vel, acc), each (n, 2)."""
    rng = np.random.default_rng(seed)
    f = rng.uniform(0.05, f_max, size=(2, 10))
    w, a = 2 * np.pi * f, np.full((2, 10), amp / 10)
    ph = rng.uniform(0, 2 * np.pi, size=(2, 10))
    arg = w * t[:, None, None] + ph
    return (
        np.sum(a * np.sin(arg), -1),
        np.sum(a * w * np.cos(arg), -1),
        np.sum(-a * w**2 * np.sin(arg), -1),
    )


def _robot_motion(duration_s, amp_rad, seed):
    """Joint multisine about HOME: theta, theta_dot, theta_ddot, each (n, 2)."""
    pos, vel, acc = _multisine(np.arange(round(duration_s * FS)) / FS, amp_rad, seed)
    return HOME + pos, vel, acc


def _cartesian(theta, theta_dot, theta_ddot):
    """X, X_d, X_dd through the model's own kinematics (frame-agnostic)."""
    J = DYN.jacobian(theta)
    x_dot = np.einsum("...ij,...j->...i", J, theta_dot)
    x_ddot = np.einsum("...ij,...j->...i", J, theta_ddot) + np.einsum(
        "...ij,...j->...i", DYN.jacobian_dot(theta, theta_dot), theta_dot
    )
    return DYN.fk(theta), x_dot, x_ddot


def _fixture_force(x, x_ddot):
    K = np.array([[FIX["k_xx"], FIX["k_s"]], [FIX["k_s"], FIX["k_yy"]]])
    return -(FIX["m"] * x_ddot + (x - FIX["x0"]) @ K.T)


def _fixture_data(seed=0):
    """50 s of Cartesian multisine (±2.5 cm, 0-2 Hz) near X0 and the exact Eq. (5) force."""
    x, _, x_ddot = _multisine(np.arange(round(50 * FS)) / FS, 0.025, seed)
    x = x + FIX["x0"] + np.array([0.004, -0.003])
    return x, x_ddot, _fixture_force(x, x_ddot)


def _arm_data(seed=1):
    x, x_dot, x_ddot = _multisine(np.arange(round(50 * FS)) / FS, 0.025, seed)
    x = x + ARM_XV + np.array([-0.005, 0.003])
    f = -((ARM_M + HANDLE_MASS_KG * np.eye(2)) @ x_ddot.T + ARM_B @ x_dot.T + ARM_K @ (x - ARM_XV).T).T
    return x, x_dot, x_ddot, f


def test_virtual_force_recovers_known_force():
    theta, theta_dot, theta_ddot = _robot_motion(5.0, np.deg2rad(5), seed=3)
    t = np.arange(len(theta)) / FS
    f_ext = np.column_stack([3 * np.sin(2 * np.pi * 0.7 * t) + 1, -2 * np.cos(2 * np.pi * 1.3 * t)])  # N
    J = DYN.jacobian(theta)
    tau = DYN.inverse_dynamics(theta, theta_dot, theta_ddot) - np.einsum("...ji,...j->...i", J, f_ext)
    # Eq. (1) inverted exactly: only round-off of a well-conditioned 2 x 2 solve (|det J| ~ l1 l2).
    assert_allclose(virtual_force(DYN, theta, theta_dot, theta_ddot, tau), f_ext, atol=1e-10)
    # Eq. (7) inverts X_dd = J Theta_dd + J_dot Theta_d.
    _, _, x_ddot = _cartesian(theta, theta_dot, theta_ddot)
    assert_allclose(DYN.joint_acceleration(theta, theta_dot, x_ddot), theta_ddot, atol=1e-10)
    # Broadcasts over trials.
    two = virtual_force(DYN, *(np.stack([a, a]) for a in (theta, theta_dot, theta_ddot, tau)))
    assert two.shape == (2, len(t), 2)


def test_virtual_force_rejects_singular_pose_and_bad_shapes():
    theta = np.array([[np.pi / 2, 0.0]])  # t1 - t2 = 90°: the arm is stretched out
    zero = np.zeros_like(theta)
    with pytest.raises(DataError, match="singularity"):
        virtual_force(DYN, theta, zero, zero, zero)
    with pytest.raises(DataError, match="shape"):
        virtual_force(DYN, HOME[None], zero, zero, np.zeros((1, 3)))


def test_fit_fixture_exact():
    fit = fit_fixture(*_fixture_data(), FS)
    for name in ("m", "k_xx", "k_yy", "k_s"):
        assert_allclose(getattr(fit, name), FIX[name], **EXACT)
    assert_allclose(fit.x0, FIX["x0"], **EXACT)
    assert_allclose(fit.K, fit.K.T)
    assert_allclose(fit.vaf_pct, 100.0, atol=1e-8)
    json.dumps(fit.as_dict())


def test_fit_fixture_noise_within_standard_errors():
    x, x_ddot, f = _fixture_data()
    sigma = 0.5  # N, white force noise
    f_noisy = f + np.random.default_rng(7).normal(0.0, sigma, f.shape)
    fit = fit_fixture(x, x_ddot, f_noisy, FS)
    # The noise is white, so the LS standard errors are the true spread (a 200-seed Monte Carlo gives
    # z-scores with SD 0.93-1.05): each estimate lies within 4 SE (two-sided p ~ 6e-5 per parameter).
    for name in ("m", "k_xx", "k_yy", "k_s"):
        se = getattr(fit, f"{name}_se")
        assert 0 < se < 0.05 * abs(FIX[name])
        assert abs(getattr(fit, name) - FIX[name]) < 4 * se
    assert np.all(np.abs(fit.x0 - FIX["x0"]) < 4 * fit.x0_se)
    # VAF lost to the noise on the validation window: 100 sigma² / (var(f) + sigma²). The sample
    # variance of 1e4 noise samples scatters by sqrt(2 / 1e4) = 1.4 % (1 SD), so rtol 6 % is ~4 SD.
    expected_loss = 100 * sigma**2 / (np.var(f[-10000:], axis=0) + sigma**2)
    assert np.all(fit.vaf_pct < 100)
    assert_allclose(100 - fit.vaf_pct, expected_loss, rtol=0.06)


def test_fit_fixture_through_virtual_sensor():
    """Method 1 end to end: robot motion, fixture force on the robot, Eq. (2), Eq. (5)."""
    theta, theta_dot, theta_ddot = _robot_motion(50.0, np.deg2rad(5), seed=5)
    x, _, x_ddot = _cartesian(theta, theta_dot, theta_ddot)
    x0 = DYN.fk(HOME) + np.array([0.003, -0.009])  # equilibrium near the perturbed pose, any frame
    K = np.array([[FIX["k_xx"], FIX["k_s"]], [FIX["k_s"], FIX["k_yy"]]])
    f_ext = -(FIX["m"] * x_ddot + (x - x0) @ K.T)
    tau = DYN.inverse_dynamics(theta, theta_dot, theta_ddot) - np.einsum(
        "...ji,...j->...i", DYN.jacobian(theta), f_ext
    )
    theta_ddot_7 = DYN.joint_acceleration(theta, theta_dot, x_ddot)  # Eq. (7), as in Table II
    fit = fit_fixture(x, x_ddot, virtual_force(DYN, theta, theta_dot, theta_ddot_7, tau), FS)
    for name in ("m", "k_xx", "k_yy", "k_s"):
        assert_allclose(getattr(fit, name), FIX[name], **EXACT)
    assert_allclose(fit.x0, x0, **EXACT)


def test_fit_arm_exact_with_handle_removed():
    x, x_dot, x_ddot, f = _arm_data()
    fit = fit_arm(x, x_dot, x_ddot, f, FS)
    assert_allclose(fit.M, ARM_M, **EXACT)
    assert_allclose(fit.B, ARM_B, **EXACT)
    assert_allclose(fit.K, ARM_K, **EXACT)
    assert_allclose(fit.xv, ARM_XV, **EXACT)
    assert_allclose(fit.vaf_pct, 100.0, atol=1e-8)
    # Forgetting Lambda lumps the handle into M's diagonal: off by exactly 0.135 kg.
    lumped = fit_arm(x, x_dot, x_ddot, f, FS, handle_mass_kg=0.0)
    assert_allclose(np.diag(lumped.M), np.diag(ARM_M) + HANDLE_MASS_KG, **EXACT)
    assert_allclose(np.diag(fit.M), np.diag(ARM_M), **EXACT)
    json.dumps(fit.as_dict())


def test_fit_arm_noise_within_standard_errors():
    x, x_dot, x_ddot, f = _arm_data()
    f_noisy = f + np.random.default_rng(11).normal(0.0, 0.5, f.shape)  # N, white
    fit = fit_arm(x, x_dot, x_ddot, f_noisy, FS)
    # White noise: every entry within 4 of its standard errors (see the fixture test).
    for est, se, true in ((fit.M, fit.M_se, ARM_M), (fit.B, fit.B_se, ARM_B), (fit.K, fit.K_se, ARM_K)):
        assert np.all(se > 0)
        assert np.all(np.abs(est - true) < 4 * se)
    assert np.all(np.abs(fit.xv - ARM_XV) < 4 * fit.xv_se)
    assert np.all(fit.vaf_pct < 100)


def _robot_trial(seed, duration_s=50.0, noise=0.0):
    theta, theta_dot, theta_ddot = _robot_motion(duration_s, np.deg2rad(20), seed)  # ±20°: the 40° range
    tau = DYN.inverse_dynamics(theta, theta_dot, theta_ddot)
    tau = tau + np.random.default_rng(seed + 100).normal(0.0, noise, tau.shape)
    return theta, theta_dot, theta_ddot, tau


def test_identify_robot_recovers_table_vi():
    ident = identify_robot([_robot_trial(1), _robot_trial(2)], FS)
    truth = TABLE_VI_ALPHA.as_array()
    assert_allclose(ident.alphas, np.stack([truth, truth]), **EXACT)
    assert_allclose(ident.params.as_array(), truth, **EXACT)
    # Two exact trials agree to round-off: the across-trial std is ~1e-15 kg·m².
    assert ident.params.std is not None and max(ident.params.std) < 1e-10
    assert_allclose(ident.vaf_pct, 100.0, atol=1e-8)
    rows = table_vi(ident)
    assert [r[0] for r in rows] == ["alpha1", "alpha2", "alpha3", "alpha4", "alpha5"]
    assert_allclose([r[5] for r in rows], 0.0, atol=1e-8)
    assert_allclose([r[4] for r in rows], TABLE_VI_ALPHA.std)
    json.dumps(ident.as_dict())


def test_identify_robot_single_noisy_trial():
    ident = identify_robot([_robot_trial(3, noise=0.01)], FS)  # 0.01 N·m white torque noise
    assert ident.params.std is None
    assert np.isnan(table_vi(ident)[0][2])
    # White noise: within 4 standard errors of the truth.
    assert np.all(np.abs(ident.alphas[0] - TABLE_VI_ALPHA.as_array()) < 4 * ident.alpha_se[0])
    assert np.all(ident.vaf_pct < 100) and np.all(ident.vaf_pct > 90)


def test_identify_robot_zero_motion_raises():
    n = round(50 * FS)
    still = (np.tile(HOME, (n, 1)), np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2)))
    with pytest.raises(EstimationError, match="do not excite"):
        identify_robot([_robot_trial(1, duration_s=50.0), still], FS)


def test_rank_deficient_regressor_raises():
    # x and y move in lock-step: the fixture's k_xx, k_yy, k_s (and the constant) are not separable.
    t = np.arange(round(50 * FS)) / FS
    pos, _, acc = _multisine(t, 0.02, seed=4)
    x, x_ddot = np.column_stack([pos[:, 0], pos[:, 0]]), np.column_stack([acc[:, 0], acc[:, 0]])
    with pytest.raises(EstimationError, match="rank deficient"):
        fit_fixture(x, x_ddot, _fixture_force(x, x_ddot), FS)


def test_bad_input():
    x, x_ddot, f = _fixture_data()
    nan = f.copy()
    nan[123, 1] = np.nan
    with pytest.raises(DataError, match=r"f_ext must be finite; NaN or inf at index \(123, 1\)"):
        fit_fixture(x, x_ddot, nan, FS)
    with pytest.raises(DataError, match=r"x_ddot must have shape \(n_samples, 2\)"):
        fit_fixture(x, x_ddot[:, :1], f, FS)
    with pytest.raises(DataError, match="n_samples=50000"):
        fit_fixture(x, x_ddot[:-1], f, FS)
    with pytest.raises(DataError, match=r"lasts 30\.000 s .*id_s=40\.0 s"):
        fit_fixture(x[:30000], x_ddot[:30000], f[:30000], FS)
    with pytest.raises(ConfigError, match="fs_hz must be a finite number > 0"):
        fit_fixture(x, x_ddot, f, 0.0)
    with pytest.raises(ConfigError, match="handle_mass_kg"):
        fit_arm(x, x, x_ddot, f, FS, handle_mass_kg=-1.0)
    with pytest.raises(DataError, match="trial 0 tau must be finite"):
        bad = _robot_trial(1, duration_s=1.0)
        identify_robot([(*bad[:3], np.full_like(bad[3], np.nan))], FS, id_s=0.8, val_s=0.2)
    with pytest.raises(DataError, match="trials is empty"):
        identify_robot([], FS)


def test_vaf():
    f = np.sin(np.linspace(0, 10, 1000))
    assert vaf(f, f) == 100.0
    assert_allclose(vaf(f, np.zeros_like(f)), 0.0, atol=1e-12)  # predicting nothing: var(f)/var(f)
    assert_allclose(vaf(f, f + 1.0), 100.0)  # Eq. (8) ignores a constant offset
    assert_allclose(vaf(np.column_stack([f, f]), np.column_stack([f, 0.5 * f])), [100.0, 75.0])
    with pytest.raises(DataError, match="zero variance"):
        vaf(np.ones(10), np.ones(10))

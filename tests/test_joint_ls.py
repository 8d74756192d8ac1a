"""Ground-truth recovery of the joint least squares, Eqs. (9)-(14) and (23)-(25)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import EstimationError
from armlab.estimation import (
    PARAM_NAMES,
    REDUCED_PARAM_NAMES,
    JointSignals,
    estimate,
    estimate_windows,
    regressor,
    relative_error,
    validate,
)
from armlab.models.planar_arm import inverse_dynamics
from armlab.perturbations import PAPER_DIRECTIONS, QuinticPerturbation, window_durations

FS = 1000.0  # Hz
Q0 = np.array([0.08, 1.00])  # rad, Sec. IV-B
XI = np.array([0.391, 0.155, 0.149])  # kg·m², Sec. IV-D
K = np.array([[15.0, 6.0], [6.0, 16.0]])  # N·m/rad
D = np.array([[2.3, 0.9], [0.9, 2.4]])  # N·m·s/rad
ZETA = np.concatenate([XI, D.ravel(), K.ravel()])
NOISE = 0.05  # N·m, torque noise standard deviation


def _simulate(durations, reps=1, noise=0.0, seed=0):
    """Trials of Eq. (9) under prescribed quintic joint trajectories, ``dtau`` computed exactly.

    Group k has ``reps`` trials per paper direction with interpolation time ``durations[k]``; the
    onsets vary from trial to trial. Returns the signals, each trial's group and the windows
    ``T_obs = T_k + 70 ms`` in samples.
    """
    durations = np.atleast_1d(durations)
    n_obs = np.round((durations + 0.07) * FS).astype(int)
    groups = np.repeat(np.arange(durations.size), 6 * reps)
    direction = np.tile(np.arange(6), durations.size * reps)
    onset = 60 + np.arange(groups.size) % 7
    t = np.arange(onset.max() + n_obs.max() + 3) / FS
    pos, vel, acc = (
        np.array(a)
        for a in zip(
            *(
                QuinticPerturbation(
                    amplitude=PAPER_DIRECTIONS[d], duration_s=durations[g], onset_s=o / FS
                ).sample(t)
                for g, d, o in zip(groups, direction, onset, strict=True)
            ),
            strict=True,
        )
    )
    q = Q0 + pos
    dtau = inverse_dynamics(q, vel, acc, XI) + vel @ D.T + pos @ K.T
    dtau = dtau + noise * np.random.default_rng(seed).normal(size=dtau.shape)
    signals = JointSignals(
        q=q, qd=vel, qdd=acc, dq=pos, tau_ext=dtau + 0.4, dtau=dtau, fs_hz=FS, onset_index=onset
    )
    return signals, groups, n_obs


WINDOWS = window_durations()[[0, 5, 12, 19, 25]]  # T_k = 50, 100, 170, 240, 300 ms


def test_regressor_columns_are_partial_derivatives():
    rng = np.random.default_rng(0)
    q, qd, qdd, dq = (rng.normal(size=(5, 2)) for _ in range(4))

    def psi(z):  # Eq. (9) with parameters z
        return inverse_dynamics(q, qd, qdd, z[:3]) + qd @ z[3:7].reshape(2, 2).T + dq @ z[7:].reshape(2, 2).T

    h = 1e-3  # Psi is linear in zeta, so central differences are exact up to round-off
    fd = np.stack([(psi(ZETA + h * e) - psi(ZETA - h * e)) / (2 * h) for e in np.eye(11)], axis=-1)
    assert_allclose(regressor(q, qd, qdd, dq), fd, atol=1e-10)


@pytest.mark.parametrize("k", [0, 2, 4])
def test_exact_data_recover_full_model(k):
    signals, groups, n_obs = _simulate(WINDOWS)
    est = estimate(signals, groups == k, n_obs[k])
    # Exact data: the error is round-off amplified by cond(W) <= 3e3, i.e. <~ 1e-12 relative.
    assert_allclose(est.zeta, ZETA, rtol=1e-9)
    assert_allclose(est.K, K, rtol=1e-9)
    assert_allclose(est.D, D, rtol=1e-9)
    assert_allclose(est.xi, XI, rtol=1e-9)
    assert est.names == PARAM_NAMES and not est.reduced
    assert est.n_rows == 2 * 6 * n_obs[k] and est.rms_residual < 1e-10
    assert 10 < est.cond < 1e4  # the windows of the protocol are moderately conditioned (Fig. 4)


def test_exact_data_recover_reduced_model():
    signals, groups, n_obs = _simulate(WINDOWS)
    est = estimate(signals, groups == 0, n_obs[0], xi_known=XI)
    # same argument as above; the reduced problem is better conditioned (cond ~ 30)
    assert_allclose(est.zeta, ZETA[3:], rtol=1e-10)
    assert_allclose(est.K, K, rtol=1e-10)
    assert_allclose(est.xi, XI)
    assert est.names == REDUCED_PARAM_NAMES and est.reduced and est.cov.shape == (8, 8)
    full = estimate(signals, groups == 0, n_obs[0])
    assert est.cond < full.cond  # known inertia removes the worst-scaled columns (Fig. 5 vs Fig. 4)


@pytest.mark.parametrize("xi_known", [None, XI])
def test_noisy_data_errors_are_bracketed_by_the_covariance(xi_known):
    signals, groups, n_obs = _simulate(WINDOWS, reps=2, noise=NOISE, seed=3)
    truth = ZETA if xi_known is None else ZETA[3:]
    for k in range(WINDOWS.size):
        est = estimate(signals, groups == k, n_obs[k], xi_known=xi_known)
        # The noise is white, Gaussian and on the output only, so the LS covariance is exact: each
        # error is N(0, std²); 4 std bounds all 5 x 11 errors with probability > 0.99.
        assert np.all(np.abs(est.zeta - truth) < 4 * est.std), (k, (est.zeta - truth) / est.std)
        assert relative_error(est.zeta, truth) > 1e-6  # noise does cost accuracy ...
        assert relative_error(est.K, K) < 0.05  # ... but stiffness stays within 5 % at this noise level
        # the residual estimates the noise level: relative sd of the estimate sqrt(1/(2 r)) < 1 %
        assert est.rms_residual == pytest.approx(NOISE, rel=0.05)


@pytest.mark.parametrize("xi_known", [None, XI])
@pytest.mark.parametrize("nested", [False, True])
def test_estimate_windows_equals_looped_estimate(xi_known, nested):
    signals, groups, n_obs = _simulate(WINDOWS, reps=2, noise=NOISE, seed=4)
    masks = groups[None, :] == np.arange(WINDOWS.size)[:, None]
    if nested:
        masks = np.ones_like(masks)
    many = estimate_windows(signals, masks, n_obs, xi_known=xi_known)
    assert len(many) == WINDOWS.size
    for k, est in enumerate(many):
        one = estimate(signals, masks[k], n_obs[k], xi_known=xi_known)
        # Normal equations square the scaled condition number (<~ 1e2 here): parameter error
        # <~ 1e4 · eps. The residual y'y - g'zeta cancels (|y|/|r|)² ~ 1e3 of the digits.
        assert_allclose(est.zeta, one.zeta, rtol=1e-9)
        assert_allclose(est.cov, one.cov, rtol=1e-7, atol=1e-7 * np.abs(one.cov).max())
        assert_allclose(est.cond, one.cond, rtol=1e-8)
        assert_allclose(est.rms_residual, one.rms_residual, rtol=1e-8)
        assert est.n_rows == one.n_rows and est.names == one.names


def _best_time(fn, repeats=3):
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


@pytest.mark.slow  # a wall-clock comparison: flaky under load; `make bench` reports the same ratios
def test_estimate_windows_cost():
    signals, groups, n_obs = _simulate(window_durations(), reps=1, noise=NOISE)
    n_win = n_obs.size
    # nested windows (all trials in every window): one pass over the longest window's data
    nested = np.ones((n_win, signals.n_trials), dtype=bool)
    t_all = _best_time(lambda: estimate_windows(signals, nested, n_obs))
    t_longest = _best_time(lambda: estimate(signals, None, n_obs[-1]))
    assert t_all < 2 * t_longest, (t_all, t_longest)  # measured ~0.3x
    # disjoint groups (the protocol): cheaper than looping over the windows (measured ~3x)
    masks = groups[None, :] == np.arange(n_win)[:, None]
    t_groups = _best_time(lambda: estimate_windows(signals, masks, n_obs))
    t_loop = _best_time(lambda: [estimate(signals, masks[k], n_obs[k]) for k in range(n_win)])
    assert t_groups < t_loop, (t_groups, t_loop)


def test_predict_and_validate_on_held_out_trial():
    signals, groups, n_obs = _simulate(WINDOWS, reps=2, noise=NOISE, seed=5)
    held_out = 59  # last trial of group 4
    train = (groups == 4) & (np.arange(groups.size) != held_out)
    est = estimate(signals, train, n_obs[4])
    fit = validate(est, signals, held_out, n_obs[4])
    assert fit.dtau.shape == fit.dtau_hat.shape == (n_obs[4], 2) and fit.t[1] == pytest.approx(1 / FS)
    # the prediction error is the noise (0.05 N·m) plus a small parameter error
    assert np.all(fit.rmse < 1.2 * NOISE) and np.all(fit.rmse > 0.8 * NOISE)
    assert np.all(fit.vaf > 90.0)
    exact, groups, n_obs = _simulate(WINDOWS)
    est = estimate(exact, groups == 2, n_obs[2])
    assert_allclose(validate(est, exact, 3, n_obs[2]).vaf, 100.0, atol=1e-8)
    idx = np.flatnonzero(groups == 2)
    measured = np.stack([exact.dtau[i, exact.onset_index[i] : exact.onset_index[i] + n_obs[2]] for i in idx])
    assert_allclose(est.predict(exact, n_obs[2], groups == 2), measured, atol=1e-10)


def test_estimation_errors():
    signals, groups, n_obs = _simulate(WINDOWS)
    with pytest.raises(EstimationError, match="at least 12 rows"):
        estimate(signals, np.array([0]), 5)
    with pytest.raises(
        EstimationError, match=r"runs past the end of a trial; the maximum allowed .* is \d+ samples"
    ):
        estimate(signals, groups == 0, signals.n_samples)
    with pytest.raises(EstimationError, match="no trial selected"):
        estimate(signals, np.zeros(groups.size, dtype=bool), 100)
    with pytest.raises(EstimationError, match=r"boolean trial mask must have shape \(30,\)"):
        estimate(signals, np.ones(3, dtype=bool), 100)
    with pytest.raises(EstimationError, match="window_samples must be a positive integer"):
        estimate(signals, groups == 0, 0)
    with pytest.raises(EstimationError, match=r"do not excite parameter\(s\) \['D12', 'D22', 'K12', 'K22'\]"):
        estimate(signals, np.array([0, 1]), 100)  # shoulder-only perturbations never move the elbow
    with pytest.raises(EstimationError, match="rank deficient"):
        estimate(signals, np.array([4, 5]), 100)  # dq1 = -dq2 throughout: collinear K columns
    with pytest.raises(EstimationError, match="xi_known must be 3 finite values"):
        estimate(signals, groups == 0, 100, xi_known=[0.3, 0.1])
    masks = groups[None, :] == np.arange(WINDOWS.size)[:, None]
    with pytest.raises(EstimationError, match=r"trial_masks must be a bool array \(n_windows, 30\)"):
        estimate_windows(signals, masks[:, :3], n_obs)
    with pytest.raises(EstimationError, match=r"window\(s\) \[2\] select no trial"):
        estimate_windows(signals, masks & (groups != 2), n_obs)
    with pytest.raises(EstimationError, match=r"window_samples must have shape \(5,\)"):
        estimate_windows(signals, masks, n_obs[:2])
    bad = masks.copy()
    bad[1] = bad[1] & np.isin(np.arange(groups.size), [10, 11])  # directions 4 and 5 only
    with pytest.raises(EstimationError, match=r"window\(s\) \[1\]: the regressor is rank deficient"):
        estimate_windows(signals, bad, n_obs)

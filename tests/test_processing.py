"""Checks of the measurement processing of Sec. IV-C (IK, zero-phase filter, differences, J^T F)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ConfigError, DataError
from armlab.estimation import JointSignals, ProcessingConfig, differentiate, joint_signals, lowpass_zero_phase
from armlab.models.planar_arm import forward, inverse, jacobian
from armlab.perturbations import QuinticPerturbation

FS = 1000.0  # Hz, the paper's sample rate
L1, L2 = 0.31, 0.34  # m
Q0 = np.array([0.08, 1.00])  # rad, initial posture of Sec. IV-B
K = np.array([[15.0, 6.0], [6.0, 16.0]])  # N·m/rad
TAU0 = np.array([0.3, -0.2])  # N·m, pre-load (the subject pushes 5 N distally)
T_K = 0.2  # s, interpolation time
AMPS = [(0.05, -0.05), (0.0, 0.05), (-0.05, 0.0)]


def _truth():
    """Known smooth joint trajectories of three trials with different onsets, and their hand data."""
    n = 800
    onset = np.array([300, 400, 250])
    t = np.arange(n) / FS
    pos, vel, acc = zip(
        *(
            QuinticPerturbation(amplitude=a, duration_s=T_K, onset_s=o / FS).sample(t)
            for a, o in zip(AMPS, onset, strict=True)
        ),
        strict=True,
    )
    q, qd, qdd = Q0 + np.array(pos), np.array(vel), np.array(acc)
    tau = TAU0 + (q - Q0) @ K.T  # a static spring load: the torque is known exactly
    force = np.linalg.solve(np.swapaxes(jacobian(q, L1, L2), -1, -2), tau[..., None])[..., 0]  # F = J^-T tau
    return dict(q=q, qd=qd, qdd=qdd, tau=tau, hand_pos=forward(q, L1, L2), force=force, onset=onset)


def test_unfiltered_signals_match_truth_to_difference_truncation():
    tr = _truth()
    s = joint_signals(tr["hand_pos"], tr["force"], FS, tr["onset"], L1, L2, ProcessingConfig(lowpass_hz=None))
    dt, jerk_jump = 1 / FS, 60 * 0.05 / T_K**3  # quintic jerk jumps by 60 A / T³ at both ends
    assert_allclose(s.q, tr["q"], atol=1e-12)  # exact IK
    assert_allclose(s.dq, tr["q"] - Q0, atol=1e-12)  # baseline = true q0 (steady before onset)
    assert_allclose(s.tau_ext, tr["tau"], atol=1e-12)  # exact J^T F
    assert_allclose(s.dtau, tr["tau"] - TAU0, atol=1e-12)
    # central difference of a C² quintic: |error| <= dt²/6·max|q'''| (= jerk at the ends)
    assert np.max(np.abs(s.qd - tr["qd"])) <= dt**2 / 6 * jerk_jump * 1.01
    # the doubled stencil straddling a jerk jump J errs by at most J·dt/3
    assert np.max(np.abs(s.qdd - tr["qdd"])) <= jerk_jump * dt / 3 * 1.01


@pytest.mark.parametrize("cutoff", [20.0, 40.0])
def test_filtered_signals_match_truth_within_filter_bias(cutoff):
    tr = _truth()
    s = joint_signals(
        tr["hand_pos"], tr["force"], FS, tr["onset"], L1, L2, ProcessingConfig(lowpass_hz=cutoff)
    )
    # The only content the low-pass removes comes from the jerk jumps J = 60 A/T³ at both ends of the
    # quintic; their spectrum above f_c bounds the k-th derivative's error by ~J / (2 pi f_c)^(3 - k).
    jerk_jump, w = 60 * 0.05 / T_K**3, 2 * np.pi * cutoff
    assert np.max(np.abs(s.q - tr["q"])) < jerk_jump / w**3
    assert np.max(np.abs(s.dq - (tr["q"] - Q0))) < jerk_jump / w**3
    assert np.max(np.abs(s.qd - tr["qd"])) < jerk_jump / w**2
    assert np.max(np.abs(s.qdd - tr["qdd"])) < jerk_jump / w
    # torque follows q through the spring: error <= |K|·(q error bound)
    assert np.max(np.abs(s.dtau - (tr["tau"] - TAU0))) < np.linalg.norm(K, 2) * jerk_jump / w**3
    assert s.onset_index.tolist() == tr["onset"].tolist() and s.fs_hz == FS


def test_baseline_is_the_mean_over_the_pre_onset_window():
    tr = _truth()
    n = tr["hand_pos"].shape[1]
    # a slow drift of the hand up to onset (1 mm per 100 ms), then held: the baseline is a mean
    ramp = np.minimum(np.arange(n)[None, :], tr["onset"][:, None]) * 1e-5
    pos = tr["hand_pos"] + np.stack([np.zeros_like(ramp), ramp], -1)
    s = joint_signals(
        pos, tr["force"], FS, tr["onset"], L1, L2, ProcessingConfig(lowpass_hz=None, baseline_s=0.2)
    )
    q = inverse(pos, L1, L2)
    for i, o in enumerate(tr["onset"]):  # samples [onset - 200, onset) at 1 kHz
        assert_allclose(s.dq[i], q[i] - q[i, o - 200 : o].mean(axis=0), atol=1e-12)


def test_lowpass_is_zero_phase_and_attenuates():
    t = np.arange(2000) / FS
    slow = np.sin(2 * np.pi * 5 * t)[None, :, None]
    fast = np.sin(2 * np.pi * 200 * t)[None, :, None]
    y = lowpass_zero_phase(slow + fast, FS, 40.0)
    # forward-backward gain at 5 Hz: 1 / (1 + (5/40)^8) ≈ 1 - 6e-8, no lag; at 200 Hz (5/40)^8-small
    assert_allclose(y[:, 200:-200], slow[:, 200:-200], atol=1e-4)
    assert_allclose(lowpass_zero_phase(slow, FS, None), slow)


def test_lowpass_and_differentiate_errors():
    x = np.zeros((1, 100, 2))
    with pytest.raises(ConfigError, match=r"cutoff_hz must lie in \(0, 500\) Hz"):
        lowpass_zero_phase(x, FS, 500.0)
    with pytest.raises(DataError, match="too short"):
        lowpass_zero_phase(np.zeros((1, 10, 2)), FS, 40.0, order=4)
    with pytest.raises(DataError, match="at least 5 samples"):
        differentiate(np.zeros((1, 4, 2)), FS)


def test_differentiate_is_fourth_order_inside():
    # five-point stencils are exact for quartics (first derivative) and quintics (second), so on
    # interior samples only round-off and the first derivative's dt^4 term remain
    t = np.arange(60) / FS
    x = (1.0 + 2.0 * t - 3.0 * t**2 + 4.0 * t**3 - 5.0 * t**4 + 6.0 * t**5)[:, None]
    xd, xdd = differentiate(x, FS, axis=0)
    d1 = 2.0 - 6.0 * t + 12.0 * t**2 - 20.0 * t**3 + 30.0 * t**4
    d2 = -6.0 + 24.0 * t - 60.0 * t**2 + 120.0 * t**3
    # round-off: ~1e-15 * 30 / dt^2 ~ 3e-8
    assert_allclose(xdd[2:-2, 0], d2[2:-2], atol=1e-6)
    # the t^5 term leaves dt^4 / 30 * (d^5 x / dt^5 = 720) ~ 2.4e-11 in the first derivative
    assert_allclose(xd[2:-2, 0], d1[2:-2], atol=1e-9)


def test_differentiate_is_exact_for_quadratics():
    t = np.arange(50) / FS
    x = np.stack([3 * t**2 - t, 0.5 * t**2], -1)
    xd, xdd = differentiate(x, FS, axis=0)
    assert_allclose(xd, np.stack([6 * t - 1, t], -1), atol=1e-9)
    assert_allclose(xdd, np.broadcast_to([6.0, 1.0], x.shape), atol=1e-6)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(lowpass_hz=-1.0), "lowpass_hz must be None"),
        (dict(filter_order=0), r"filter_order must be an integer in 1..10"),
        (dict(filter_order=2.5), r"filter_order must be an integer in 1..10"),
        (dict(baseline_s=0.0), "baseline_s must be a positive"),
    ],
)
def test_processing_config_validation(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        ProcessingConfig(**kwargs)


def test_joint_signals_input_errors():
    tr = _truth()
    with pytest.raises(DataError, match=r"\(n_trials, n_samples, 2\)"):
        joint_signals(tr["hand_pos"][0], tr["force"][0], FS, tr["onset"], L1, L2)
    bad = tr["hand_pos"].copy()
    bad[0, 5, 0] = np.nan
    with pytest.raises(DataError, match="hand_pos contains 1 non-finite"):
        joint_signals(bad, tr["force"], FS, tr["onset"], L1, L2)
    with pytest.raises(DataError, match=r"onset_index must lie in \[1, 799\]"):
        joint_signals(tr["hand_pos"], tr["force"], FS, np.array([0, 10, 20]), L1, L2)
    z = np.zeros((2, 10, 2))
    with pytest.raises(DataError, match="joint signals must all be"):
        JointSignals(q=z, qd=z, qdd=z, dq=z, tau_ext=z, dtau=z[:, :5], fs_hz=FS, onset_index=np.array([1, 2]))

"""Tests for armlab.estimation.static_inertial (seed paper 001, Eqs. (11)-(13), (22)): the spec's
acceptance check 4 on base-wrench data generated with MuJoCo from models/arm_5dof (the arm held
still in 40 configurations), ideal and through a realistic base F/T channel and IK of noisy markers."""

from __future__ import annotations

import numpy as np
import pytest
from arm5_data import MARKER_RATE_HZ, add_marker_noise, held_wrench, postures, wrist_frames
from numpy.testing import assert_allclose

from armlab.errors import DataError, EstimationError
from armlab.estimation import (
    gravity_stiffness_from_fit,
    gravity_torque_from_fit,
    inverse_kinematics,
    static_inertial_regression,
)
from armlab.models import gravity_stiffness, gravity_torque, inertial_truth, limb_kinematics, load_arm_5dof
from armlab.sensors import JR3_BASE_FORCE, JR3_BASE_TORQUE, apply_channel

ARM = load_arm_5dof()


KIN = limb_kinematics(ARM)
TRUTH = inertial_truth(ARM)
FT_RATE_HZ = 2000.0  # paper Sec. 3: base JR3 at 2 kHz
HOLD_S = 1.0  # spec design: hold each configuration 1 s


def _configurations(n: int, seed: int) -> np.ndarray:
    """(n, 5) rad: q0 +- 0.7 rad (the paper's 40 predefined configurations, Sec. 3)."""
    return postures(ARM, n, seed, 0.7)


def _held_wrench(q: np.ndarray) -> np.ndarray:
    return held_wrench(ARM, q)


def test_ideal_data_recover_xi_red():
    q = _configurations(40, 31)
    fit = static_inertial_regression(KIN, q, _held_wrench(q))
    # spec check 4 allows every identifiable combination 1 % (entries that are zero in the model: 1 %
    # of the largest first moment); ideal static data make it exact to rounding, far inside that
    assert_allclose(fit.xi_red, TRUTH.xi_red, atol=1e-9)
    held_out = _configurations(10, 32)
    g_fit = gravity_torque_from_fit(KIN, fit.xi_red, held_out)
    assert_allclose(g_fit, gravity_torque(ARM, held_out), atol=1e-9)
    # dG/dq from the fit equals MuJoCo's (finite differences of both: 1e-6 N m/rad)
    dg_fit = gravity_stiffness_from_fit(KIN, fit.xi_red, ARM.q0)
    assert_allclose(dg_fit, gravity_stiffness(ARM, ARM.q0), atol=1e-6)


def test_realistic_base_sensor_and_markers_predict_gravity_within_0_1_nm():
    rng = np.random.default_rng(33)
    q = _configurations(50, 34)
    fit_q, held_q = q[:40], q[40:]
    n_ft = round(HOLD_S * FT_RATE_HZ)
    # the whole session is one record of the base sensor (one untared offset for all 40 holds,
    # which the intercept absorbs): apply_channel draws its bias once per trial, so the 40 holds
    # go in as one trial of 40 x 2000 samples
    clean = np.repeat(_held_wrench(fit_q)[:, None, :], n_ft, axis=1).reshape(1, -1, 6)
    wrench = (
        np.concatenate(
            [
                apply_channel(clean[..., :3], FT_RATE_HZ, JR3_BASE_FORCE, rng),
                apply_channel(clean[..., 3:], FT_RATE_HZ, JR3_BASE_TORQUE, rng),
            ],
            axis=-1,
        )
        .reshape(40, n_ft, 6)
        .mean(axis=1)
    )
    # joint angles: IK of the noisy wrist frame over the 1 s hold, averaged (paper Sec. 4.1); the
    # solver starts at the predefined configuration missed by 0.1 rad (the subject's imprecision)
    n_mk = round(HOLD_S * MARKER_RATE_HZ)
    q_rep = np.repeat(fit_q, n_mk, axis=0)
    pos, rot = wrist_frames(ARM, q_rep)
    pos, rot = add_marker_noise(pos, rot, rng)
    start = np.repeat(fit_q + rng.normal(0.0, 0.1, fit_q.shape), n_mk, axis=0)
    q_ik = inverse_kinematics(KIN, rot, pos, start).q.reshape(40, n_mk, 5).mean(axis=1)
    fit = static_inertial_regression(KIN, q_ik, wrench)
    err = gravity_torque_from_fit(KIN, fit.xi_red, held_q) - gravity_torque(ARM, held_q)
    rms = float(np.sqrt(np.mean(err**2)))
    assert rms < 0.1, rms  # spec check 4: 10 held-out configurations, realistic base sensor


def test_bad_input_is_refused():
    q = _configurations(5, 35)
    with pytest.raises(DataError, match="wrench"):
        static_inertial_regression(KIN, q, np.zeros((5, 3)))
    with pytest.raises(EstimationError, match="at least 3"):
        static_inertial_regression(KIN, q[:2], np.zeros((2, 6)))
    still = np.repeat(q[:1], 20, axis=0)  # one configuration repeated: nothing to regress
    with pytest.raises(EstimationError, match="rank"):
        static_inertial_regression(KIN, still, _held_wrench(still))
    with pytest.raises(DataError, match="xi_red"):
        gravity_torque_from_fit(KIN, np.zeros(8), q)

"""Tests for armlab.estimation.inverse_kinematics (seed paper 001, Eq. (10)): the spec's acceptance
check 2 on wrist frames generated with MuJoCo from models/arm_5dof, the calibrated chain from the
joint-centre estimates of check 1, and the batched solver against SciPy's least squares."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from arm5_data import add_marker_noise, markers, random_motion, wrist_frames
from numpy.testing import assert_allclose
from scipy import optimize

from armlab.errors import DataError
from armlab.estimation import frobenius_residual, inverse_kinematics, joint_centre
from armlab.models import axis_rotation, limb_kinematics, load_arm_5dof

ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)
Q = random_motion(ARM, np.random.default_rng(21))  # 30 s at 500 Hz
WRIST_POS, WRIST_ROT = wrist_frames(ARM, Q)
POS, ROT = markers(ARM, Q)
TORSO, UPPER, FOREARM = 0, 1, 2


def _site_in_body(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A site's position (3,) m and orientation (3, 3) in its body frame (the cluster placement)."""
    s = ARM.sites[name]
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, ARM.model.site_quat[s])
    return ARM.model.site_pos[s].copy(), rot.reshape(3, 3)


def _rms_deg(q: np.ndarray) -> float:
    return float(np.degrees(np.sqrt(np.mean((q - Q) ** 2))))


def test_ideal_wrist_frames_give_the_true_angles():
    res = inverse_kinematics(KIN, WRIST_ROT, WRIST_POS, ARM.q0)
    # consistent data: Eq. (10) has a zero minimum at the true q; 1e-9 rad is rounding, the spec's
    # check 2 allows 0.2 deg RMS
    assert_allclose(res.q, Q, atol=1e-9)  # hence far inside check 2's 0.2 deg RMS
    assert res.cost.max() < 1e-12
    assert_allclose(res.J_limb, KIN.jacobian(Q), atol=1e-8)  # J at q within 1e-9 rad of Q


def test_noisy_markers_and_calibrated_chain_within_1_deg():
    rng = np.random.default_rng(22)
    pos, rot = add_marker_noise(POS, ROT, rng)
    sh = joint_centre(pos[:, TORSO], rot[:, TORSO], pos[:, UPPER], rot[:, UPPER])
    el = joint_centre(pos[:, UPPER], rot[:, UPPER], pos[:, FOREARM], rot[:, FOREARM])
    # the chain from the estimated centres: the clusters' placement on their segments is known
    # (the lab measures it once), the centres come from check 1
    up_pos, up_rot = _site_in_body("upper_arm_marker")
    fa_pos, fa_rot = _site_in_body("forearm_marker")
    wrist_in_marker = fa_rot.T @ (ARM.model.site_pos[ARM.sites["wrist"]] - fa_pos)
    calibrated = KIN.with_centres(
        shoulder=sh.centre.mean(axis=0),
        elbow_offset=up_rot @ (el.d1 - sh.d2),
        wrist_offset=fa_rot @ (wrist_in_marker - el.d2),
    )
    # T_d: the wrist frame carried by the noisy forearm cluster (wrist frame = forearm frame here)
    rot_d = rot[:, FOREARM] @ fa_rot.T
    pos_d = pos[:, FOREARM] + rot[:, FOREARM] @ wrist_in_marker
    res = inverse_kinematics(calibrated, rot_d, pos_d, ARM.q0)
    assert _rms_deg(res.q) < 1.0, _rms_deg(res.q)  # spec check 2, noisy markers


def test_batched_solver_equals_scipy_least_squares_per_sample():
    rng = np.random.default_rng(23)
    idx = rng.choice(len(Q), 5, replace=False)
    rot_d, pos_d = WRIST_ROT[idx], WRIST_POS[idx]
    # perturb the targets so that the minimum is not zero (a real least-squares problem)
    axes = rng.normal(size=(5, 3))
    tilt = np.stack([axis_rotation(a / np.linalg.norm(a), 0.03) for a in axes])  # 0.03 rad
    rot_d = rot_d @ tilt
    pos_d = pos_d + 0.01 * rng.normal(size=(5, 3))
    res = inverse_kinematics(KIN, rot_d, pos_d, ARM.q0)
    for i in range(5):
        ref = optimize.least_squares(
            lambda q, i=i: frobenius_residual(KIN, q, rot_d[i], pos_d[i]),
            ARM.q0,
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        assert_allclose(res.q[i], ref.x, atol=1e-7)  # two solvers to their tolerances
        assert res.cost[i] == pytest.approx(np.linalg.norm(ref.fun), rel=1e-9)


def test_bad_input_is_refused():
    with pytest.raises(DataError, match="rot_d must be"):
        inverse_kinematics(KIN, WRIST_ROT[:3], WRIST_POS[:4], ARM.q0)
    with pytest.raises(DataError, match="q_init"):
        inverse_kinematics(KIN, WRIST_ROT[:3], WRIST_POS[:3], np.zeros(4))
    with pytest.raises(DataError, match="NaN"):
        inverse_kinematics(KIN, WRIST_ROT[:3], WRIST_POS[:3] * np.nan, ARM.q0)

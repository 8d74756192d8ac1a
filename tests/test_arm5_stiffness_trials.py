"""The stiffness trials of seed paper 001 simulated in the composed lab and estimated: the spec's
acceptance checks 5 (K_q relative Frobenius error < 5 % ideal, < 12 % realistic; SPD in every
condition), 6 (ignoring G shifts K by dG/dq within 10 %) and 9 (ellipsoid major axis within 10 deg
of the truth in every condition).

Reduced trial count: 20 disturbances per condition (2 per direction) instead of the paper's 50, to
keep the suite fast (~4 s of stepping instead of ~9 s). With ideal sensors the error is a
deterministic settling bias (the same at 20 and 50 trials: 0.1-0.3 %, measured); with realistic
sensors the noise part grows as 1/sqrt(N), so 20 trials test the tolerances more severely than 50.
(Check 7, the reflex bias: tests/test_stiffness5_protocol.py; here the activations are frozen.)"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from arm5_data import held_wrench, postures

from armlab.errors import ConfigError, DataError
from armlab.estimation import (
    WristSensorGeometry,
    axis_angle_deg,
    chordal_mean_rotation,
    condition_stiffness,
    interval_mean,
    quat_to_rot,
    relative_error,
    static_inertial_regression,
    stiffness_ellipsoid,
)
from armlab.models import (
    analytic_stiffness,
    build_arm5_scene,
    gravity_stiffness,
    limb_kinematics,
    load_arm_5dof,
)
from armlab.sensors import Arm5SensorSuite
from armlab.sim import (
    AMPLITUDE_RAD,
    TrialTiming,
    force_task_activations,
    measure_stiffness_record,
    plan_stiffness_trials,
    preload_conditions,
    simulate_stiffness_trials,
)

N_PER_CONDITION = 20  # reduced from the paper's 50 (module docstring)
ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)
SCENE = build_arm5_scene()
NAMES, FORCES = preload_conditions()
ACTS = np.array([force_task_activations(ARM, ARM.q0, f).activation for f in FORCES])
PLAN = plan_stiffness_trials(len(FORCES), N_PER_CONDITION, np.random.default_rng(19))
RECORD = simulate_stiffness_trials(SCENE, KIN, ARM.q0, ACTS, PLAN)
# xi_red from 40 held configurations through the base F/T (paper Sec. 3; ideal base sensor)
_Q40 = postures(ARM, 40, 40, 0.7)
XI = static_inertial_regression(KIN, _Q40, held_wrench(ARM, _Q40)).xi_red


def _estimates(preset: str) -> list:
    suite = Arm5SensorSuite.ideal() if preset == "ideal" else Arm5SensorSuite.realistic()
    meas = measure_stiffness_record(RECORD, suite, np.random.default_rng(7), t0_s=PLAN.wait_s)
    geo = WristSensorGeometry.from_scene(SCENE)
    out = []
    for c in range(len(FORCES)):
        i = PLAN.condition == c
        out.append(
            condition_stiffness(
                KIN,
                XI,
                meas.marker_pos[i],
                meas.marker_quat[i],
                meas.marker_t,
                meas.ft["wrist_force"][i],
                meas.ft["wrist_torque"][i],
                meas.ft_t,
                SCENE.marker_to_wrist,
                geo,
                np.tile(ARM.q0, (int(i.sum()), 1)),
                ARM.q0 + RECORD.commanded_dq[i],
            )
        )
    return out


EST = {p: _estimates(p) for p in ("ideal", "realistic")}


def test_plan_draws_balanced_random_directions_and_holds():
    assert PLAN.n_trials == 8 * N_PER_CONDITION
    for c in range(8):
        d = PLAN.direction[PLAN.condition == c]
        assert np.bincount(d, minlength=10).tolist() == [N_PER_CONDITION // 10] * 10
    assert 1.5 <= PLAN.wait_s.min() and PLAN.wait_s.max() <= 2.5  # paper Sec. 3: 1.5-2.5 s
    again = plan_stiffness_trials(8, N_PER_CONDITION, np.random.default_rng(19))
    assert np.array_equal(again.direction, PLAN.direction) and np.array_equal(again.wait_s, PLAN.wait_s)
    assert not np.array_equal(PLAN.direction[:20], PLAN.direction[20:40])  # random order per condition


def test_the_arm_follows_the_planned_displacement():
    q = RECORD.channels["true_q"]
    post = (np.arange(q.shape[1]) - RECORD.onset_index) / RECORD.fs_hz
    moved = q[:, (post >= 0.2) & (post < 0.4)].mean(axis=1) - q[:, post < 0].mean(axis=1)
    # the robot places the wrist at T(q0 + dq) and the weld carries the arm with it: within
    # 0.005 rad (the servos' static error under the arm's changed load; 6 % of 0.08 rad)
    assert np.abs(moved - RECORD.commanded_dq).max() < 0.005
    assert np.abs(RECORD.commanded_dq).max() == AMPLITUDE_RAD


# spec 001 check 5 allows 5 % (ideal) and 12 % (realistic). The ideal-sensor error is only the
# residual motion in the post-interval (measured 0.1-0.3 %): 1 % is a guard far inside 5 % that
# fails on any systematic mapping error
@pytest.mark.parametrize(("preset", "tolerance"), [("ideal", 0.01), ("realistic", 0.12)])
def test_check_5_joint_stiffness_per_condition(preset, tolerance):
    for c, est in enumerate(EST[preset]):
        K_true = analytic_stiffness(ARM, ACTS[c])  # linear muscles: the intrinsic truth, exact
        err = relative_error(est.estimate.K, K_true)
        assert err < tolerance, (NAMES[c], err)
        assert est.estimate.spd.eigenvalues.min() > 0  # SPD in every condition


def test_check_6_gravity_ablation():
    for c, est in enumerate(EST["ideal"]):
        dG = gravity_stiffness(ARM, est.q_work)
        shift = est.uncompensated.K_ls - est.estimate.K_ls
        assert relative_error(shift, dG) < 0.10, NAMES[c]  # spec 001 check 6


@pytest.mark.parametrize("preset", ["ideal", "realistic"])
def test_check_9_ellipsoid_major_axis(preset):
    for c, est in enumerate(EST[preset]):
        truth = stiffness_ellipsoid(analytic_stiffness(ARM, ACTS[c]), KIN.jacobian(ARM.q0))
        ell = stiffness_ellipsoid(est.estimate.K, est.J_work, centre=FORCES[c])  # at the displayed force
        assert axis_angle_deg(ell.major_axis, truth.major_axis) < 10.0, NAMES[c]  # spec 001 check 9


def test_the_held_torque_is_the_displayed_force():
    """Before the onsets the JR3's tau_ext = J^T w equals J^T (-F, 0) of the displayed force F.
    (The wrench itself does not: a 6-D cuff on a 5-DoF arm carries a wrench in the null space of
    J^T that the limb neither feels nor controls, set by the robot servo's static deflection; up to
    3 N at the wrist here, measured; the ellipsoids are drawn at the displayed force.)"""
    J = KIN.jacobian(ARM.q0)
    for c, est in enumerate(EST["realistic"]):
        # the servos' static error moves the working point <= 0.002 rad from q0 (measured), so
        # (K_q + dG/dq) dq <= ~0.04 N m; sensor noise on the mean is ~1e-3 N m
        assert np.abs(est.tau_pre.mean(axis=0) - J.T @ np.r_[-FORCES[c], 0.0, 0.0, 0.0]).max() < 0.05


def test_timing_outside_the_record_is_refused():
    with pytest.raises(ConfigError, match="post_interval"):
        TrialTiming(post_interval=(0.2, 0.6))
    with pytest.raises(ConfigError, match="pre_interval"):
        TrialTiming(pre_interval=(-0.3, 0.0))
    with pytest.raises(ConfigError, match="at least 10 trials"):
        plan_stiffness_trials(8, 5, np.random.default_rng(0))


def test_quaternion_and_mean_rotation_helpers():
    rng = np.random.default_rng(3)
    quat = rng.normal(size=(6, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    for qu, rot in zip(quat, quat_to_rot(quat), strict=True):
        expected = np.zeros(9)
        mujoco.mju_quat2Mat(expected, qu)
        np.testing.assert_allclose(rot, expected.reshape(3, 3), atol=1e-15)  # MuJoCo's convention
    # rotations +-theta about one axis around a centre: the chordal mean is the centre (exact by
    # symmetry), and a rotation (det +1)
    centre = quat_to_rot(quat[0])
    turns = [
        quat_to_rot(np.r_[np.cos(a / 2), np.sin(a / 2) * np.array([0.6, 0.0, 0.8])]) for a in (0.01, -0.01)
    ]
    mean = chordal_mean_rotation(np.stack([centre @ t for t in turns])[None])[0]
    np.testing.assert_allclose(mean, centre, atol=1e-14)
    assert np.linalg.det(mean) == pytest.approx(1.0)


def test_interval_mean_refuses_an_empty_interval():
    x = np.zeros((2, 5, 3))
    t = np.arange(5) * 0.1 - 0.2
    np.testing.assert_allclose(interval_mean(x + np.arange(5)[None, :, None], t, (-0.2, 0.0)), 0.5)
    with pytest.raises(DataError, match="no sample in the interval"):
        interval_mean(x, t, (1.0, 2.0))

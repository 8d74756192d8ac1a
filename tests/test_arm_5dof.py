"""Tests for the seated 5-DoF arm (models/arm_5dof, armlab.models.arm_5dof / limb_kinematics /
arm5_truth): indices, kinematics against MuJoCo, the finite-difference truth against the analytic
impedance of the linear muscles, gravity and xi_red against MuJoCo's own forces and sensors.
(The standalone file's compile-and-step check with zero warnings is
tests/test_scene.py::test_standalone_model_steps_one_second_without_warnings[arm_5dof/arm_5dof.xml].)"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from arm5_data import base_wrench, held_still, postures
from numpy.testing import assert_allclose

from armlab.errors import DataError
from armlab.models import (
    ARM5_JOINTS,
    ARM5_MUSCLES,
    ELECTRODE_MUSCLES,
    analytic_damping,
    analytic_stiffness,
    gravity_stiffness,
    gravity_torque,
    inertial_truth,
    joint_centre_truth,
    limb_kinematics,
    load_arm_5dof,
    stiffness_fd,
)

ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)


def _postures(n: int, seed: int) -> np.ndarray:
    """(n, 5) rad: the default posture +-0.5 rad (inside every joint range)."""
    return postures(ARM, n, seed, 0.5)


def test_model_indices_and_constants():
    m = ARM.model
    assert [m.joint(int(j)).name for j in m.dof_jntid[ARM.dof]] == list(ARM5_JOINTS)
    assert [m.actuator(int(a)).name for a in ARM.muscle_act] == list(ARM5_MUSCLES)
    assert len(ELECTRODE_MUSCLES) == 8 and len(ARM5_MUSCLES) == 12  # paper Fig. 1b + 4 silent ones
    assert_allclose(ARM.q0, [0.6, 0.3, 0.0, 1.4, 0.0])  # keyframe q0 of arm_5dof.xml
    assert_allclose(m.opt.gravity, [0, 0, -9.81])  # gravity on (spec: no support beam)
    # the muscles alone span all five joints, the electrode ones too (rank 5 of K_q's muscle part)
    assert np.linalg.matrix_rank(ARM.moment_arms) == 5
    # segment numbers of models/arm_5dof/README.md (Winter 2009 Table 4.1)
    upper, forearm = (m.body(n) for n in ("upper_arm", "forearm"))
    assert upper.mass[0] == pytest.approx(2.10) and forearm.mass[0] == pytest.approx(1.65)
    assert np.linalg.norm(KIN.elbow_offset) == pytest.approx(0.326)
    assert np.linalg.norm(KIN.wrist_offset) == pytest.approx(0.30)


def test_activated_arm_steps_one_second_without_warnings():
    data = ARM.data_at(ARM.q0, np.full(12, 0.15))
    data.ctrl[ARM.muscle_act] = 0.15  # co-contraction; gravity pulls the arm to a new equilibrium
    for _ in range(round(1.0 / ARM.model.opt.timestep)):
        mujoco.mj_step(ARM.model, data)
    assert [int(w.number) for w in data.warning] == [0] * len(data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.sensordata))
    assert np.all(ARM.model.jnt_range[:, 0] < data.qpos) and np.all(data.qpos < ARM.model.jnt_range[:, 1])


def test_forward_kinematics_and_jacobian_equal_mujoco():
    q = _postures(5, 0)
    rot, pos = KIN.forward(q)
    jac = KIN.jacobian(q)
    w = ARM.sites["wrist"]
    for i, qi in enumerate(q):
        data = ARM.data_at(qi)
        jp, jr = np.zeros((3, ARM.model.nv)), np.zeros((3, ARM.model.nv))
        mujoco.mj_jacSite(ARM.model, data, jp, jr, w)
        # same rigid-body arithmetic in another order: equal to rounding
        assert_allclose(pos[i], data.site_xpos[w], atol=1e-12)
        assert_allclose(rot[i], data.site_xmat[w].reshape(3, 3), atol=1e-12)
        assert_allclose(jac[i], np.vstack([jp[:, ARM.dof], jr[:, ARM.dof]]), atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_finite_difference_stiffness_equals_analytic_sum(seed):
    rng = np.random.default_rng(seed)
    act = rng.uniform(0.02, 0.4, len(ARM5_MUSCLES))
    q = _postures(1, seed)[0]
    K, D = stiffness_fd(ARM, q, act)
    K_a = analytic_stiffness(ARM, act)
    # linear muscles on fixed tendons: K is exactly sum a k r r^T + K_passive, so the only error is
    # the central difference's rounding, ~ 1e-16 * 300 N / 1e-6 rad * 0.05 m ~ 1e-8 N m/rad
    assert_allclose(K, K_a, atol=1e-7)
    assert_allclose(D, analytic_damping(ARM, act), atol=1e-7)
    assert np.linalg.eigvalsh(K_a).min() > 0
    # independent of posture (constant moment arms): the same K at the default posture
    assert_allclose(stiffness_fd(ARM, ARM.q0, act)[0], K_a, atol=1e-7)


def test_every_muscle_pulls_over_the_papers_perturbations():
    """T0 = 300 N per unit activation keeps every tension positive over +-0.08 rad (paper Sec. 3)
    along each of the 10 directions from q0 (models/arm_5dof/README.md)."""
    act = np.full(len(ARM5_MUSCLES), 0.2)
    for dq in np.vstack([np.eye(5), -np.eye(5)]) * 0.08:
        data = ARM.data_at(ARM.q0 + dq, act)
        # a pulling muscle has a negative actuator force; the largest tension loss over 0.08 rad is
        # k_i |r_i| 0.08 rad = 80 N per unit activation (README), so at least 0.2 * (300 - 80) N
        # here (1e-9 N: rounding)
        assert np.all(data.actuator_force[ARM.muscle_act] <= -0.2 * (300.0 - 80.0) + 1e-9)


def test_truth_refuses_wrong_activation_shape():
    with pytest.raises(DataError, match="one activation per muscle"):
        analytic_stiffness(ARM, np.ones(8))


def test_gravity_torque_balances_the_static_arm_and_its_stiffness_is_symmetric():
    q = _postures(4, 3)
    G = gravity_torque(ARM, q)
    for qi, gi in zip(q, G, strict=True):
        data = held_still(ARM, qi)
        # passive springs are zero at qpos = springref only; the joint torque that holds the arm
        # still with no muscle force is G - passive
        assert_allclose(data.qfrc_inverse[ARM.dof], gi - data.qfrc_passive[ARM.dof], atol=1e-12)
    dG = gravity_stiffness(ARM, ARM.q0)
    assert_allclose(dG, dG.T, atol=1e-7)  # the Hessian of the potential energy
    # order of the spec's "about 0.9 N m over 0.08 rad at the shoulder": several N m/rad
    assert 3.0 < np.abs(dG[:2, :2]).max() < 20.0


def test_xi_red_predicts_mujocos_base_sensor():
    truth = inertial_truth(ARM)
    assert truth.xi_red[0] == pytest.approx(
        ARM.model.body_subtreemass[ARM.model.site_bodyid[ARM.sites["base_ft"]]]
    )
    assert truth.masses[1:] == pytest.approx([2.10, 1.65])
    g = 9.81  # m/s², the MJCF's gravity
    for qi in _postures(6, 4):
        f, n = np.split(base_wrench(ARM, held_still(ARM, qi)), 2)
        pose = KIN.pose(qi)
        s = (
            np.r_[truth.xi_red[1:3], 0.0]
            + pose.upper_rot @ truth.xi_red[3:6]
            + pose.forearm_rot @ truth.xi_red[6:9]
        )
        assert_allclose(f, [0.0, 0.0, g * truth.xi_red[0]], atol=1e-9)
        assert_allclose(n, [g * s[1], -g * s[0], 0.0], atol=1e-9)


def test_joint_centre_truth_is_fixed_in_both_marker_frames():
    q = _postures(5, 5)
    truth = joint_centre_truth(ARM, q)
    for qi, elbow in zip(q, truth.elbow, strict=True):
        data = ARM.data_at(qi)

        def world(site: str, d: np.ndarray, data=data) -> np.ndarray:
            s = ARM.sites[site]
            return data.site_xpos[s] + data.site_xmat[s].reshape(3, 3) @ d

        assert_allclose(world("torso_marker", truth.d_shoulder[0]), truth.shoulder, atol=1e-12)
        assert_allclose(world("upper_arm_marker", truth.d_shoulder[1]), truth.shoulder, atol=1e-12)
        assert_allclose(world("upper_arm_marker", truth.d_elbow[0]), elbow, atol=1e-12)
        assert_allclose(world("forearm_marker", truth.d_elbow[1]), elbow, atol=1e-12)
        assert_allclose(data.site_xpos[ARM.sites["elbow_centre"]], elbow, atol=1e-12)

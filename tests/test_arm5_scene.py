"""Tests for the stiffness lab of seed paper 001 (armlab.models.arm5_scene, models/arm_5dof/
cuff_6d.xml): the composed arm + LWR + 6-D cuff compiles and holds the arm for a second with zero
MuJoCo warnings, and the cuff transmits the moment about the forearm axis (a robot rotation of the
wrist turns the forearm's pronation joint, and the wrist JR3 reads the restoring moment)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ModelError
from armlab.estimation import WristSensorGeometry, external_joint_torque, wrench_on_limb
from armlab.models import (
    ARM5_LAB_TIMESTEP_S,
    analytic_stiffness,
    build_arm5_scene,
    gravity_torque,
    limb_kinematics,
    load_arm_5dof,
)
from armlab.sim import force_task_activations, preload_conditions, solve_ik
from armlab.sim.robot_ik import nominal_robot_posture

ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)
SCENE = build_arm5_scene()
ACT = force_task_activations(ARM, ARM.q0, preload_conditions()[1][7]).activation  # Z+10 N


def _held(q_target: np.ndarray, seconds: float) -> mujoco.MjData:
    """The arm with ACT, the robot's servos commanded to the wrist frame T(q_target), stepped
    ``seconds`` from q0 (Python loop: a single trial)."""
    m = SCENE.model
    rot, pos = KIN.forward(ARM.q0)
    q_hold = solve_ik(SCENE, pos[None], nominal_robot_posture(SCENE, pos), rotation=rot[None])[0]
    rot_t, pos_t = KIN.forward(q_target)
    q_rob = solve_ik(SCENE, pos_t[None], q_hold, rotation=rot_t[None])[0]
    data = mujoco.MjData(m)
    data.qpos[SCENE.arm_qpos] = ARM.q0
    data.qpos[SCENE.robot_qpos] = q_hold
    data.act[SCENE.muscle_actadr] = ACT
    data.ctrl[SCENE.muscle_act] = ACT
    data.ctrl[SCENE.robot_act] = q_rob
    for _ in range(round(seconds / m.opt.timestep)):
        mujoco.mj_step(m, data)
    return data


def _tau_ext(data: mujoco.MjData) -> np.ndarray:
    """tau_ext = J_limb^T w (5,) N m from the wrist JR3, the tool's weight compensated."""
    geo = WristSensorGeometry.from_scene(SCENE)
    q = data.qpos[SCENE.arm_qpos]
    rot, _ = KIN.forward(q)
    f, n = SCENE.sensor(data.sensordata, "wrist_force"), SCENE.sensor(data.sensordata, "wrist_torque")
    return external_joint_torque(KIN.jacobian(q), wrench_on_limb(f, n, rot, geo))


def test_lab_compiles_and_holds_the_arm_one_second_without_warnings():
    m = SCENE.model
    assert m.opt.timestep == ARM5_LAB_TIMESTEP_S == 0.0005  # 2 kHz F/T (paper Sec. 3)
    assert_allclose(m.opt.gravity, [0.0, 0.0, -9.81])  # gravity on (spec 001: no support)
    assert m.eq_type.tolist() == [mujoco.mjtEq.mjEQ_WELD]  # the 6-D cuff: a weld, not a connect
    data = _held(ARM.q0, 1.0)
    assert [int(w.number) for w in data.warning] == [0] * len(data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.sensordata))
    # the weld holds: cuff centre on the wrist to 0.01 mm (the solver's softness at 10 N)
    gap = data.site_xpos[SCENE.contact_site] - data.site_xpos[SCENE.wrist_site]
    assert np.linalg.norm(gap) < 1e-5
    # the arm stays at q0 within the robot servo's static error under the load (< 0.01 rad)
    assert np.abs(data.qpos[SCENE.arm_qpos] - ARM.q0).max() < 0.01
    # every sensor the trials record is there (wrist JR3, base JR3, forearm marker)
    for name in ("wrist_force", "wrist_torque", "base_force", "base_torque", "forearm_marker_quat"):
        assert name in SCENE.sensors


def test_cuff_transmits_the_moment_about_the_forearm_axis():
    """The robot turns the wrist frame by 0.05 rad of pronation: the forearm follows (a cuff
    passing forces only would leave pronation to the muscles and gravity), and the change of the
    JR3's tau_ext = J^T w equals K_q dq + dG (Eq. (14) at rest) on every joint."""
    before = _held(ARM.q0, 0.5)
    q_target = ARM.q0 + np.r_[0.0, 0.0, 0.0, 0.0, 0.05]
    after = _held(q_target, 0.5)
    q0, q1 = before.qpos[SCENE.arm_qpos], after.qpos[SCENE.arm_qpos]
    dq = q1 - q0
    # the forearm rotates with the cuff: 0.05 rad to 2 % (servo error under the changed load)
    assert dq[4] == pytest.approx(0.05, rel=0.02)
    d_tau = _tau_ext(after) - _tau_ext(before)
    expected = analytic_stiffness(ARM, ACT) @ dq + gravity_torque(ARM, q1) - gravity_torque(ARM, q0)
    # static balance with linear muscles: exact up to the residual motion after 0.5 s (< 1e-4 N m)
    assert_allclose(d_tau, expected, atol=1e-3)
    # the pronation moment itself (K_55 ~ 2.7 N m/rad here: ~0.13 N m) is 100x that tolerance
    assert abs(d_tau[4]) > 0.1


def test_bad_robot_base_is_refused():
    with pytest.raises(ModelError, match="three finite numbers"):
        build_arm5_scene((0.3, 0.9))

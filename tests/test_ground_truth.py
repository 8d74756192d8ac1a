"""Tests for armlab.models.ground_truth: K and D against the linear muscles' analytic impedance,
against the human figures the models are tuned to, and xi against an independently built model."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from conftest import make_lab
from numpy.testing import assert_allclose

from armlab.config.schema import ArmConfig
from armlab.models.ground_truth import base_inertial_parameters, ground_truth, joint_impedance
from armlab.sim.hold import settle

FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


def _moment_arms(scene) -> np.ndarray:
    """(6, 2) m, fixed-tendon coefficients of each muscle on (shoulder, elbow), read from the wraps."""
    model = scene.model
    arm_joints = list(model.dof_jntid[scene.arm_dof])
    r = np.zeros((len(scene.muscle_act), 2))
    for i, a in enumerate(scene.muscle_act):
        assert model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON
        t = model.actuator_trnid[a, 0]
        for w in range(model.tendon_adr[t], model.tendon_adr[t] + model.tendon_num[t]):
            assert model.wrap_type[w] == mujoco.mjtWrap.mjWRAP_JOINT
            r[i, arm_joints.index(model.wrap_objid[w])] = model.wrap_prm[w]
    return r


def _act(scene, state) -> np.ndarray:
    data = mujoco.MjData(scene.model)
    mujoco.mj_setState(scene.model, data, state, FULL)
    return data.act[scene.muscle_act].copy()


@pytest.mark.parametrize("rigid", [True, False])
def test_linear_impedance_equals_analytic_sum(rigid):
    lab = make_lab("linear", rigid)
    scene, state = lab.scene, lab.hold.state
    gain = scene.model.actuator_gainprm[scene.muscle_act]
    k, b = -gain[:, 1], -gain[:, 2]  # N/m, N s/m (gainprm = [-F0', -k, -b])
    r = _moment_arms(scene)
    act = _act(scene, state)
    K_ref = np.einsum("i,ij,ik->jk", act * k, r, r)
    D_ref = np.einsum("i,ij,ik->jk", act * b, r, r)
    K, D = joint_impedance(scene, state)
    # The affine muscle force is exactly linear in q and qdot, so central differences are exact up
    # to rounding: ~1e-13 N*m torque noise / 1e-6 step ~ 1e-7 N*m/rad on entries of order 1-15.
    assert_allclose(K, K_ref, rtol=1e-6)
    assert_allclose(D, D_ref, rtol=1e-6)


def test_ground_truth_bundles_impedance_inertia_and_operating_point():
    lab = make_lab("linear", False)
    gt = ground_truth(lab.scene, lab.hold.state, rigid_cuff=False)
    K, D = joint_impedance(lab.scene, lab.hold.state)
    assert_allclose(gt.K, K, rtol=0, atol=0)
    assert_allclose(gt.D, D, rtol=0, atol=0)
    assert_allclose(gt.xi, base_inertial_parameters(lab.scene, False), rtol=0, atol=0)
    assert_allclose(gt.q_op, lab.hold.q_arm, rtol=0, atol=0)


def test_impedance_positive_definite_and_in_published_range(lab):
    K, D = joint_impedance(lab.scene, lab.hold.state)
    assert np.all(np.linalg.eigvalsh(0.5 * (K + K.T)) > 0), K
    assert np.all(np.linalg.eigvalsh(0.5 * (D + D.T)) > 0), D
    # Shadmehr & Mussa-Ivaldi 1994: K ~ [[15, 6], [6, 16]] N m/rad, D ~ [[2.3, 0.9], [0.9, 2.4]]
    # N m s/rad; the bands span the inter-subject spread reported there (about +-35 %).
    assert 10 <= K[0, 0] <= 20 and 10 <= K[1, 1] <= 22, K
    assert 3 <= K[0, 1] <= 9 and 3 <= K[1, 0] <= 9, K
    assert 1.5 <= D[0, 0] <= 3.2 and 1.5 <= D[1, 1] <= 3.3, D
    assert 0.5 <= D[0, 1] <= 1.3 and 0.5 <= D[1, 0] <= 1.3, D


def test_linear_impedance_scales_with_cocontraction():
    lab = make_lab("linear", False)
    out = []
    for c in (0.2, 0.4):
        arm = ArmConfig(muscle="linear", cocontraction=c, preload_N=0.0)
        hold = settle(lab.scene, arm, 0.2)
        assert_allclose(hold.activation, c, rtol=1e-12)  # no pre-load: every muscle at the co-contraction
        out.append(joint_impedance(lab.scene, hold.state))
    (K1, D1), (K2, D2) = out
    # K = sum act k r r^T with constant moment arms: exactly linear in act; tolerance as above.
    assert_allclose(K2, 2 * K1, rtol=1e-6)
    assert_allclose(D2, 2 * D1, rtol=1e-6)


def _body_xml(model, b: int, name: str, pos, quat, children: str = "", joint: str = "") -> str:
    ipos = " ".join(repr(float(x)) for x in model.body_ipos[b])
    iquat = " ".join(repr(float(x)) for x in model.body_iquat[b])
    inertia = " ".join(repr(float(x)) for x in model.body_inertia[b])
    mass = float(model.body_mass[b])
    return (
        f'<body name="{name}" pos="{" ".join(map(repr, map(float, pos)))}" '
        f'quat="{" ".join(map(repr, map(float, quat)))}">{joint}'
        f'<inertial pos="{ipos}" quat="{iquat}" mass="{mass!r}" diaginertia="{inertia}"/>'
        f"{children}</body>"
    )


def _independent_xi(scene, rigid: bool) -> np.ndarray:
    """xi from the joint-space inertia of a standalone 2-link model built from the scene's numbers."""
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    upper = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "arm_planar/upper_arm")
    forearm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "arm_planar/forearm")
    shell = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "arm_planar/cuff_shell/shell")
    assert min(upper, forearm, shell) >= 0
    # the shell's pose in the forearm frame at qpos0 (it is welded there through the attachment frame)
    r_f = data.xmat[forearm].reshape(3, 3)
    shell_pos = r_f.T @ (data.xpos[shell] - data.xpos[forearm])
    shell_mat = r_f.T @ data.xmat[shell].reshape(3, 3)
    shell_quat = np.empty(4)
    mujoco.mju_mat2Quat(shell_quat, shell_mat.ravel())
    shell_xml = _body_xml(model, shell, "shell", shell_pos, shell_quat)
    if rigid:
        # the robot-side cuff bodies beyond the sensor count as point masses at the hand
        m_tool = sum(
            float(model.body_mass[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"lwr/cuff/{n}")])
            for n in ("ft_sensor", "mount")
        )
        hand = model.site_pos[scene.hand_site]
        shell_xml += (
            f'<body name="tool" pos="{" ".join(map(repr, map(float, hand)))}">'
            f'<inertial pos="0 0 0" mass="{m_tool!r}" diaginertia="0 0 0"/></body>'
        )
    forearm_xml = _body_xml(
        model,
        forearm,
        "forearm",
        model.body_pos[forearm],
        model.body_quat[forearm],
        shell_xml,
        '<joint name="q2" type="hinge" axis="0 0 1"/>',
    )
    upper_xml = _body_xml(
        model,
        upper,
        "upper",
        [0, 0, 0],
        [1, 0, 0, 0],
        forearm_xml,
        '<joint name="q1" type="hinge" axis="0 0 1"/>',
    )
    xml = f'<mujoco><option gravity="0 0 0"/><worldbody>{upper_xml}</worldbody></mujoco>'
    m2 = mujoco.MjModel.from_xml_string(xml)
    d2 = mujoco.MjData(m2)
    M = np.zeros((2, 2))

    def mass_matrix(q2: float) -> np.ndarray:
        d2.qpos[:] = (0.0, q2)
        mujoco.mj_forward(m2, d2)
        mujoco.mj_fullM(m2, d2, M)
        return M.copy()

    # eq. (13): M11 = xi1 + 2 xi2 cos q2, M12 = xi3 + xi2 cos q2, M22 = xi3
    m_90, m_0 = mass_matrix(np.pi / 2), mass_matrix(0.0)
    xi1, xi3 = m_90[0, 0], m_90[1, 1]
    return np.array([xi1, m_0[0, 1] - xi3, xi3])


@pytest.mark.parametrize("rigid", [True, False])
def test_base_inertial_parameters_match_independent_model(rigid):
    scene = make_lab("hill", rigid).scene
    xi = base_inertial_parameters(scene, rigid)
    # Same inertias summed by MuJoCo's composite-rigid-body algorithm instead of by hand: agreement
    # to rounding of a few products of O(1) numbers (cos(pi/2) ~ 6e-17 leaves M11 exact to 1e-16).
    assert_allclose(xi, _independent_xi(scene, rigid), rtol=1e-9)


def test_rigid_cuff_adds_tool_masses_at_the_hand():
    xi_r = base_inertial_parameters(make_lab("hill", True).scene, True)
    scene = make_lab("hill", False).scene
    xi_c = base_inertial_parameters(scene, False)
    m_tool = 0.02 + 0.02  # kg, ft_sensor + mount of models/common/cuff.xml
    l1, l2 = scene.l1, scene.l2
    assert_allclose(xi_r - xi_c, m_tool * np.array([l1**2 + l2**2, l1 * l2, l2**2]), rtol=1e-9)

"""The relaxed arm on the capstan handle: activations that hold it and the endpoint M, B, K truth."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from armlab.config.capstan import CapstanConfig
from armlab.config.schema import ArmConfig
from armlab.errors import ConfigError, ModelError
from armlab.models import planar_arm
from armlab.models.arm_endpoint import endpoint_truth, relaxed_activation
from armlab.models.capstan_scene import CapstanScene, build_capstan_scene

# the protocol's arm trials (armlab/protocols/virtual_force_sensor/experiment.py, VfsConfig, SimConfig)
SIM = dict(timestep_s=0.00025, integrator="Euler")
HANDLE_XY = np.array([0.383, 0.015])  # m, Table V's equilibrium
LEVEL = 0.04  # the relaxed subject's co-contraction
# planar_arm's frame (x lateral, y anterior) turned by +90 deg into the robot frame
ROT90 = np.array([[0.0, -1.0], [1.0, 0.0]])
# models/arm_planar/skeleton.xml: upper arm m1 2.10 kg, COM 0.142 m, Izz 0.0232 kg·m², l1 0.326 m;
# forearm + hand m2 1.65 kg, COM 0.174 m, Izz 0.0235 kg·m²
XI = planar_arm.xi_from_segments(2.10, 0.142, 0.0232, 1.65, 0.174, 0.0235, 0.326)


@pytest.fixture(scope="module")
def scene() -> CapstanScene:
    return build_capstan_scene(
        CapstanConfig(),
        "arm",
        arm=ArmConfig(muscle="linear", cocontraction=LEVEL),
        handle_xy=tuple(HANDLE_XY),
        reach_m=0.5,
        **SIM,
    )


def _pose(scene: CapstanScene, dq=(0.0, 0.0)):
    return scene.dynamics.ik(HANDLE_XY), scene.arm_posture(HANDLE_XY) + np.asarray(dq)


def _net_arm_torque(scene: CapstanScene, state: np.ndarray) -> np.ndarray:
    data = mujoco.MjData(scene.model)
    mujoco.mj_setState(scene.model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_forward(scene.model, data)
    return (data.qfrc_actuator + data.qfrc_passive)[scene.arm_dof]


def _muscle_terms(scene: CapstanScene, state: np.ndarray):
    """Per-muscle k, b (N/m, N·s/m per unit activation) and moment arms r (6, 2) m from the model."""
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_forward(model, data)
    moment = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(
        moment, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
    )
    # affine gain: force = act (g0 + g1 L + g2 L_dot), g1 = -k, g2 = -b (arm_planar_linear.xml)
    gain = model.actuator_gainprm[scene.muscle_act]
    return -gain[:, 1], -gain[:, 2], moment[np.ix_(scene.muscle_act, scene.arm_dof)]


def test_relaxed_activation_at_the_protocol_posture(scene):
    theta0, arm_q = _pose(scene)
    act = relaxed_activation(scene, scene.initial_state(theta0, arm_q), LEVEL)
    assert act.shape == (6,) and np.all((act >= 0) & (act <= 1))
    # the scene re-centres the linear muscles on this posture, so uniform activation balances:
    # the least squares returns the level itself (seen: exact to 1e-16)
    np.testing.assert_allclose(act, LEVEL, atol=1e-9)
    # net arm torque with those activations (module tolerance 1e-6 N·m; seen 7e-15 N·m)
    net = _net_arm_torque(scene, scene.initial_state(theta0, arm_q, act))
    assert np.max(np.abs(net)) < 1e-9


@pytest.mark.parametrize("dq", [(0.05, -0.05), (-0.1, 0.08)])
def test_relaxed_activation_away_from_the_design_posture(scene, dq):
    # off the re-centred posture uniform activation no longer balances (linear muscles: the
    # tensions change by act k dL, e.g. 0.04 * 14000 N/m * 0.04 m * 0.05 rad ~ 1 N; seen 0.09 to
    # 0.2 N·m net); the bounded least squares must find other activations with zero net torque
    theta0, arm_q = _pose(scene, dq)
    uniform = _net_arm_torque(scene, scene.initial_state(theta0, arm_q, LEVEL))
    assert np.max(np.abs(uniform)) > 1e-3
    act = relaxed_activation(scene, scene.initial_state(theta0, arm_q), LEVEL)
    assert np.all((act >= 0) & (act <= 1))
    assert np.max(np.abs(act - LEVEL)) > 1e-4  # not the trivial answer
    net = _net_arm_torque(scene, scene.initial_state(theta0, arm_q, act))
    assert np.max(np.abs(net)) < 1e-6  # the module's own tolerance (seen 8e-15 N·m)


def test_relaxed_activation_ignores_velocities(scene):
    theta0, arm_q = _pose(scene, (0.05, -0.05))
    state = scene.initial_state(theta0, arm_q)
    data = mujoco.MjData(scene.model)
    mujoco.mj_setState(scene.model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    data.qvel[scene.arm_dof] = (0.5, -0.3)  # rad/s: the muscles' damping would add torque
    moving = np.empty_like(state)
    mujoco.mj_getState(scene.model, data, moving, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    np.testing.assert_allclose(
        relaxed_activation(scene, moving, LEVEL), relaxed_activation(scene, state, LEVEL), atol=1e-12
    )


@pytest.fixture(scope="module")
def truth(scene):
    theta0, arm_q = _pose(scene)
    act = relaxed_activation(scene, scene.initial_state(theta0, arm_q), LEVEL)
    state = scene.initial_state(theta0, arm_q, act)
    return state, act, endpoint_truth(scene, state)


def test_endpoint_matrices_are_physical(truth):
    _, act, tr = truth
    for name, mat in (("M", tr.M), ("B", tr.B), ("K", tr.K)):
        assert mat.shape == (2, 2)
        # K and B come from central differences (eps 1e-6): symmetric to round-off (seen 4e-11
        # relative); M from mj_fullM exactly
        np.testing.assert_allclose(mat, mat.T, rtol=0, atol=1e-7 * np.abs(mat).max(), err_msg=name)
        assert np.all(np.linalg.eigvalsh(mat) > 0), name
    np.testing.assert_allclose(tr.xv, HANDLE_XY, atol=1e-12)  # the relaxed hand rests on the grip
    np.testing.assert_array_equal(tr.activation, act)
    assert set(tr.as_dict()) == {"M_kg", "B_Ns_per_m", "K_N_per_m", "xv_m", "activation"}


def test_endpoint_k_and_b_are_the_muscle_springs_through_the_jacobian(scene, truth):
    state, act, tr = truth
    k, b, r = _muscle_terms(scene, state)
    # moment arms of models/arm_planar/skeleton.xml: 4 cm shoulder, 3 cm elbow, 3 cm bi-articular
    np.testing.assert_allclose(
        np.abs(r), [[0.04, 0], [0.04, 0], [0, 0.03], [0, 0.03], [0.03, 0.03], [0.03, 0.03]]
    )
    # linear muscles: K_q = sum act k r r^T, D_q = sum act b r r^T (arm_planar_linear.xml header)
    k_q = (r.T * (act * k)) @ r
    d_q = (r.T * (act * b)) @ r
    # the hand's Jacobian from the analytic planar arm, turned into the robot frame
    jac = ROT90 @ planar_arm.jacobian(scene.arm_posture(HANDLE_XY), scene.arm_l1, scene.arm_l2)
    jinv = np.linalg.inv(jac)
    # the finite differences of linear torques are exact up to round-off: seen 3e-9 N/m on
    # K ~ 12..78 N/m and B ~ 2..12 N·s/m
    np.testing.assert_allclose(tr.K, jinv.T @ k_q @ jinv, rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(tr.B, jinv.T @ d_q @ jinv, rtol=1e-7, atol=1e-6)


def test_endpoint_k_is_minus_the_hand_force_gradient(scene, truth):
    # Cartesian finite differences: move the hand by +-1e-5 m along x and y (arm joints through
    # the inverse kinematics, robot held at its own pose), F = J^-T tau, K = -dF/dX
    state, act, tr = truth
    theta0 = scene.dynamics.ik(HANDLE_XY)
    d = HANDLE_XY - scene.shoulder_pos

    def hand_force(x: np.ndarray) -> np.ndarray:
        p = x - scene.shoulder_pos
        q = planar_arm.inverse(ROT90.T @ p, scene.arm_l1, scene.arm_l2, "flexed")
        tau = _net_arm_torque(scene, scene.initial_state(theta0, q, act))
        jac = ROT90 @ planar_arm.jacobian(q, scene.arm_l1, scene.arm_l2)
        return np.linalg.solve(jac.T, tau)

    assert np.linalg.norm(ROT90.T @ d) == pytest.approx(0.5)  # 50 cm reach
    assert np.linalg.norm(hand_force(HANDLE_XY)) < 1e-9  # relaxed: no static hand force
    eps = 1e-5
    k = -np.column_stack(
        [(hand_force(HANDLE_XY + e) - hand_force(HANDLE_XY - e)) / (2 * eps) for e in eps * np.eye(2)]
    )
    # truncation (eps / 0.3 m)^2 ~ 1e-9 relative; round-off of the inverse kinematics and the
    # torques over 2 eps: seen 2.8e-7 N/m on K ~ 12..78 N/m
    np.testing.assert_allclose(k, tr.K, rtol=1e-6, atol=1e-5)


def test_endpoint_mass_is_the_arm_inertia_through_the_jacobian(scene, truth):
    _, _, tr = truth
    q = scene.arm_posture(HANDLE_XY)
    jac = ROT90 @ planar_arm.jacobian(q, scene.arm_l1, scene.arm_l2)
    jinv = np.linalg.inv(jac)
    # the arm alone (Eq. (9) keeps the 135 g handle apart): exact up to round-off (seen 1e-15 kg)
    np.testing.assert_allclose(tr.M, jinv.T @ planar_arm.mass_matrix(q, XI) @ jinv, rtol=1e-9, atol=1e-12)


def test_doubling_the_activation_doubles_k_and_b(scene, truth):
    _, _, low = truth
    theta0, arm_q = _pose(scene)
    act = relaxed_activation(scene, scene.initial_state(theta0, arm_q), 2 * LEVEL)
    np.testing.assert_allclose(act, 2 * LEVEL, atol=1e-9)
    high = endpoint_truth(scene, scene.initial_state(theta0, arm_q, act))
    # linear muscles: K, B proportional to activation (round-off of the differences: 1e-9 rel.)
    np.testing.assert_allclose(high.K, 2 * low.K, rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(high.B, 2 * low.B, rtol=1e-7, atol=1e-6)
    np.testing.assert_array_equal(high.M, low.M)


@pytest.mark.parametrize("level", [-0.01, 1.01, float("nan")])
def test_level_outside_unit_interval_rejected(scene, level):
    theta0, arm_q = _pose(scene)
    with pytest.raises(ConfigError, match=r"\[0, 1\]"):
        relaxed_activation(scene, scene.initial_state(theta0, arm_q), level)


def test_scene_without_arm_rejected():
    none = build_capstan_scene(CapstanConfig(), "none", **SIM)
    state = none.initial_state(np.array([np.pi / 4, np.pi / 4]))
    with pytest.raises(ModelError, match="load='arm'"):
        endpoint_truth(none, state)
    with pytest.raises(ModelError, match="load='arm'"):
        relaxed_activation(none, state, LEVEL)

"""The composed capstan lab (seeds/003): loads, cable modes, PD servos, friction, springs, drag, arm."""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from armlab.config.capstan import CapstanConfig
from armlab.config.schema import ArmConfig
from armlab.errors import ConfigError, ModelError
from armlab.models.capstan_robot import CAPSTAN_RATIO
from armlab.models.capstan_scene import LOADS, CapstanScene, build_capstan_scene
from armlab.models.spring_array import TABLE_I_PAYLOADS_KG, TABLE_I_STIFFNESS, table_i_array

# the protocol's physics (armlab/protocols/virtual_force_sensor/experiment.py with configs/sim defaults)
SIM = dict(timestep_s=0.00025, integrator="Euler")
HANDLE_XY = np.array([0.383, 0.015])  # m, Table V's equilibrium (VfsConfig.arm_handle_m)
REACH_M = 0.5  # m, hand 50 cm anterior to the shoulder (Sec. II-C-2)
HOME = np.array([np.pi / 4, np.pi / 4])  # rad, end effector at (0.495, 0) m
ARM = ArmConfig(muscle="linear", cocontraction=0.04)
SPRINGS = ("K1", "K5")  # Table I fields with coupling of either sign (k_s = -18.87, +73.16 N/m)


def _scene(load: str, cfg: CapstanConfig | None = None, k_label: str = "K1", **kw) -> CapstanScene:
    cfg = CapstanConfig() if cfg is None else cfg
    if load == "fixture":
        kw = dict(array=table_i_array(k_label), payload_kg=TABLE_I_PAYLOADS_KG["M3"]) | kw
    elif load == "arm":
        kw = dict(arm=ARM, handle_xy=tuple(HANDLE_XY), reach_m=REACH_M) | kw
    return build_capstan_scene(cfg, load, **SIM, **kw)


def _pose(scene: CapstanScene, k_label: str = "K1") -> tuple[np.ndarray, np.ndarray | None]:
    """The protocol's robot pose (and arm posture) for each load."""
    if scene.load == "fixture":
        return scene.dynamics.ik(TABLE_I_STIFFNESS[k_label].X0), None
    if scene.load == "arm":
        return scene.dynamics.ik(HANDLE_XY), scene.arm_posture(HANDLE_XY)
    return HOME.copy(), None


def _data(scene: CapstanScene, theta, arm_q=None, act: float = 0.0) -> mujoco.MjData:
    data = mujoco.MjData(scene.model)
    state = scene.initial_state(theta, arm_q, act)
    mujoco.mj_setState(scene.model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    data.ctrl[scene.motor_act] = theta  # PD servos holding the pose
    mujoco.mj_forward(scene.model, data)
    return data


def _id(scene: CapstanScene, obj: mujoco.mjtObj, name: str) -> int:
    i = mujoco.mj_name2id(scene.model, obj, name)
    assert i >= 0, name
    return i


def _link_torque(scene: CapstanScene, qfrc: np.ndarray) -> np.ndarray:
    """(2,) N·m: generalised forces on (rotor1, rotor2, shoulder, elbow) as torques on Theta.

    qdot = T Theta_dot with shoulder = t1, elbow = t2 - t1, rotor_i = N t_i, so tau = T^T qfrc.
    """
    r1, r2, sh, el = qfrc[scene.robot_dof]
    return np.array([sh - el + CAPSTAN_RATIO * r1, el + CAPSTAN_RATIO * r2])


def _ee_force(scene: CapstanScene, data: mujoco.MjData, theta) -> np.ndarray:
    """(2,) N: the Cartesian force at the end effector equivalent to ``qfrc_passive`` (tau = J^T F)."""
    jac = scene.dynamics.jacobian(np.asarray(theta, float))
    return np.linalg.solve(jac.T, _link_torque(scene, data.qfrc_passive))


def _sensor2(scene: CapstanScene, data: mujoco.MjData, a: str, b: str) -> np.ndarray:
    return np.concatenate([scene.sensor(data.sensordata, a), scene.sensor(data.sensordata, b)])


# --- every scene compiles and steps ---------------------------------------------------------


@pytest.mark.parametrize("effects", [True, False], ids=["drag+coulomb", "bare"])
@pytest.mark.parametrize("cable", ["rigid", "compliant"])
@pytest.mark.parametrize("load", LOADS)
def test_every_load_steps_half_a_second_without_warnings(load, cable, effects):
    cfg = CapstanConfig(cable=cable, drag=effects, coulomb_Nm=0.05 if effects else 0.0)
    scene = _scene(load, cfg)
    theta, arm_q = _pose(scene)
    data = _data(scene, theta, arm_q)
    x0 = scene.sensor(data.sensordata, "p_ee")[:2].copy()
    for _ in range(2000):  # 0.5 s
        mujoco.mj_step(scene.model, data)
    assert [w.number for w in data.warning] == [0] * len(data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert np.all(np.isfinite(data.sensordata))
    moved = np.linalg.norm(scene.sensor(data.sensordata, "p_ee")[:2] - x0)
    if effects:  # the drag pulls the held robot towards its neutral point X_n = (0.371, 0.002) m:
        # 5.4 N at home (load none) moves it mm; the fixture and the arm rest within 12 mm of X_n
        assert moved < 2e-2
        if load == "none":
            assert moved > 1e-3
    else:
        # without drag or friction and with the servos holding theta0 every load starts in
        # equilibrium (the fixture's springs balance at X0, the limp arm's hand is on the grip):
        # seen 0 to 3e-16 m of drift; a misplaced spring or hand would move it by millimetres
        assert moved < 1e-9


def test_initial_state_places_the_robot():
    scene = _scene("none")
    theta = np.array([0.7, 1.1])
    data = _data(scene, theta)
    np.testing.assert_allclose(_sensor2(scene, data, "theta1", "theta2"), theta, atol=1e-12)
    np.testing.assert_allclose(_sensor2(scene, data, "link_theta1", "link_theta2"), theta, atol=1e-12)
    np.testing.assert_allclose(_sensor2(scene, data, "psi1", "psi2"), 0.0, atol=1e-12)
    np.testing.assert_allclose(
        scene.sensor(data.sensordata, "p_ee")[:2], scene.dynamics.fk(theta), atol=1e-12
    )
    assert np.all(data.qvel == 0.0)


# --- cables --------------------------------------------------------------------------------


@pytest.mark.parametrize("cable", ["rigid", "compliant"])
def test_cable_mode_sets_the_equalities(cable):
    scene = _scene("none", CapstanConfig(cable=cable))
    for i in (1, 2):
        eq = _id(scene, mujoco.mjtObj.mjOBJ_EQUALITY, f"capstan_planar/rigid{i}")
        assert bool(scene.model.eq_active0[eq]) is (cable == "rigid")


@pytest.mark.parametrize("stiffness", [500.0, 2000.0])
def test_cable_stiffness_and_damping_reach_the_tendons(stiffness):
    cfg = CapstanConfig(
        cable="compliant", cable_stiffness_Nm_per_rad=stiffness, cable_damping_Nms_per_rad=0.2
    )
    scene = _scene("none", cfg)
    for i in (1, 2):
        tendon = _id(scene, mujoco.mjtObj.mjOBJ_TENDON, f"capstan_planar/cable{i}")
        assert scene.model.tendon_stiffness[tendon] == stiffness
        assert scene.model.tendon_damping[tendon] == 0.2


@pytest.mark.parametrize("stiffness", [500.0, 2000.0])
def test_compliant_cable_stretches_by_torque_over_stiffness(stiffness):
    # The drag pulls the held robot (5.4 N along -x at home); at rest each cable carries the
    # servo torque: k psi = tau (link side). 0.5 s of settling leaves seen 8e-6 (500 N·m/rad) and
    # 7e-7 (2000 N·m/rad) relative; allow 1e-3.
    cfg = CapstanConfig(cable="compliant", cable_stiffness_Nm_per_rad=stiffness, coulomb_Nm=0.0)
    scene = _scene("none", cfg)
    data = _data(scene, HOME)
    for _ in range(2000):
        mujoco.mj_step(scene.model, data)
    tau = _sensor2(scene, data, "tau1", "tau2")
    psi = _sensor2(scene, data, "psi1", "psi2")
    assert np.all(np.abs(tau) > 1.0)  # seen 2.4 N·m on each joint
    np.testing.assert_allclose(stiffness * psi, tau, rtol=1e-3)


def test_rigid_cable_does_not_stretch():
    # Same load as above; the rigid equality (soft constraint, README: ~3e-7 rad per N·m) holds
    # psi at seen 7e-7 rad under 2.4 N·m, where the softest compliant cable (200 N·m/rad) would
    # stretch 1.2e-2 rad and the default one 1.2e-3 rad.
    scene = _scene("none", CapstanConfig(cable="rigid"))
    data = _data(scene, HOME)
    for _ in range(2000):
        mujoco.mj_step(scene.model, data)
    assert np.all(np.abs(_sensor2(scene, data, "tau1", "tau2")) > 1.0)
    assert np.max(np.abs(_sensor2(scene, data, "psi1", "psi2"))) < 1e-5


# --- PD servos and friction ----------------------------------------------------------------


@pytest.mark.parametrize("cable", ["rigid", "compliant"])
def test_servo_torque_is_kp_times_the_position_error(cable):
    cfg = CapstanConfig(cable=cable, kp_Nm_per_rad=120.0, kd_Nms_per_rad=2.5)
    scene = _scene("none", cfg)
    theta = np.array([0.7, 1.1])
    data = _data(scene, theta)
    d = np.array([0.01, -0.03])  # rad: 1.2 and -3.6 N·m, inside the 25 N·m clamp
    data.ctrl[scene.motor_act] = theta + d
    mujoco.mj_forward(scene.model, data)
    tau = _sensor2(scene, data, "tau1", "tau2")
    np.testing.assert_allclose(tau, 120.0 * d, rtol=1e-9)
    # the torque acts on the link side: on the rotor through the 1/N gear
    np.testing.assert_allclose(data.qfrc_actuator[scene.robot_dof[:2]], tau / CAPSTAN_RATIO, rtol=1e-9)
    np.testing.assert_allclose(_link_torque(scene, data.qfrc_actuator), tau, rtol=1e-9)


def test_servo_damping_is_kd_times_the_encoder_velocity():
    cfg = CapstanConfig(kp_Nm_per_rad=120.0, kd_Nms_per_rad=2.5)
    scene = _scene("none", cfg)
    theta = np.array([0.7, 1.1])
    data = _data(scene, theta)
    w = np.array([0.4, -0.2])  # rad/s, link side
    data.qvel[scene.robot_dof[:2]] = CAPSTAN_RATIO * w
    mujoco.mj_forward(scene.model, data)
    np.testing.assert_allclose(_sensor2(scene, data, "theta1_dot", "theta2_dot"), w, rtol=1e-12)
    np.testing.assert_allclose(_sensor2(scene, data, "tau1", "tau2"), -2.5 * w, rtol=1e-9)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_servo_torque_clamps_at_25_Nm(sign):
    scene = _scene("none")
    data = _data(scene, HOME)
    data.ctrl[scene.motor_act] = HOME + sign * np.array([1.0, 0.5])  # kp d = 150, 75 N·m
    mujoco.mj_forward(scene.model, data)
    np.testing.assert_array_equal(_sensor2(scene, data, "tau1", "tau2"), [sign * 25.0, sign * 25.0])


@pytest.mark.parametrize("coulomb", [0.0, 0.05, 0.3])
def test_coulomb_friction_is_rotor_frictionloss(coulomb):
    scene = _scene("none", CapstanConfig(coulomb_Nm=coulomb))
    loss = scene.model.dof_frictionloss
    # link-side coulomb torque reflected to the rotor through the drum ratio
    np.testing.assert_allclose(loss[scene.robot_dof[:2]], coulomb / CAPSTAN_RATIO, rtol=1e-12)
    np.testing.assert_array_equal(loss[scene.robot_dof[2:]], 0.0)


# --- mass-spring fixture -------------------------------------------------------------------


@pytest.mark.parametrize("m_label", ["M1", "M5"])
def test_fixture_payload_replaces_the_handle(m_label):
    mass = TABLE_I_PAYLOADS_KG[m_label]
    scene = _scene("fixture", payload_kg=mass)
    handle = _id(scene, mujoco.mjtObj.mjOBJ_BODY, "capstan_planar/handle")
    assert scene.model.body_mass[handle] == pytest.approx(mass, rel=1e-12)
    assert scene.payload_kg == pytest.approx(mass, rel=1e-12)
    # a point mass on the grip (Eq. (5): M = m I): centred, spin inertia negligible against m l^2
    np.testing.assert_allclose(scene.model.body_ipos[handle], 0.0, atol=1e-12)
    assert np.all(scene.model.body_inertia[handle] <= 1e-5)


def test_handle_mass_per_load():
    none, arm = (
        _scene("none", CapstanConfig(id_ee_mass_kg=0.0)),
        _scene("arm", CapstanConfig(handle_mass_kg=0.2)),
    )
    h_none = _id(none, mujoco.mjtObj.mjOBJ_BODY, "capstan_planar/handle")
    h_arm = _id(arm, mujoco.mjtObj.mjOBJ_BODY, "capstan_planar/handle")
    assert none.model.body_mass[h_none] == 0.0 and np.all(none.model.body_inertia[h_none] == 0.0)
    assert none.payload_kg == 0.0
    # the identification's robot carries the model's inertia error on its handle (CapstanConfig)
    ident = _scene("none", CapstanConfig(id_ee_mass_kg=0.1))
    assert ident.model.body_mass[h_none] == pytest.approx(0.1) and ident.payload_kg == 0.0
    assert arm.model.body_mass[h_arm] == pytest.approx(0.2) and arm.payload_kg == pytest.approx(0.2)


@pytest.mark.parametrize("k_label", SPRINGS)
def test_fixture_springs_balance_at_x0_with_table_i_stiffness(k_label):
    field = TABLE_I_STIFFNESS[k_label]
    scene = _scene("fixture", CapstanConfig(drag=False), k_label=k_label)
    names = [scene.model.tendon(i).name for i in range(scene.model.ntendon)]
    assert sum(n.startswith("spring_") for n in names) == len(table_i_array(k_label).springs)

    def force(x: np.ndarray) -> np.ndarray:
        theta = scene.dynamics.ik(x)
        data = _data(scene, theta)
        np.testing.assert_allclose(scene.sensor(data.sensordata, "p_ee")[:2], x, atol=1e-12)
        return _ee_force(scene, data, theta)

    # the array is balanced to ~1e-13 N (spring_array); in the scene seen 5e-14 N: the springs
    # run in the plane of the grip, anchored where the array puts them
    assert np.linalg.norm(force(field.X0)) < 1e-9
    # K by central differences of the spring force at the end effector (eps 1e-5 m: the spring
    # force is smooth on the 0.2 m scale, truncation ~ (eps / 0.2 m)^2 ~ 3e-9; seen 5e-10 rel.)
    eps = 1e-5
    k = -np.column_stack([(force(field.X0 + e) - force(field.X0 - e)) / (2 * eps) for e in eps * np.eye(2)])
    np.testing.assert_allclose(k, field.K, rtol=1e-6, atol=1e-6 * np.abs(field.K).max())


# --- cabling drag --------------------------------------------------------------------------


def test_drag_off_means_no_drag_tendon():
    scene = _scene("none", CapstanConfig(drag=False))
    for axis in ("x", "y"):
        assert mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_TENDON, f"drag_{axis}") == -1
    data = _data(scene, HOME)
    np.testing.assert_allclose(data.qfrc_passive, 0.0, atol=1e-12)


@pytest.mark.parametrize("neutral", [(0.371, 0.002), (0.45, -0.05)])
def test_drag_is_a_force_field_about_its_neutral_point(neutral):
    cfg = CapstanConfig(
        drag=True,
        drag_neutral_m=neutral,
        drag_stiffness_N_per_m=40.0,
        drag_stiffness_y_N_per_m=15.0,
        drag_hysteresis_m=0.0,
        coulomb_Nm=0.0,
    )
    scene = _scene("none", cfg)
    for axis, k in (("x", 40.0), ("y", 15.0)):
        tendon = _id(scene, mujoco.mjtObj.mjOBJ_TENDON, f"drag_{axis}")
        assert scene.model.tendon_stiffness[tendon] == k
    # F = -diag(k_x, k_y) (X - X_n) up to the tension across each 1 m spring: at home, 0.05-0.12 m
    # from X_n, the transverse pull is k d_x d_y / 1 m < 0.3 N; allow 0.35 N
    theta = HOME
    data = _data(scene, theta)
    d = scene.dynamics.fk(theta) - np.asarray(neutral)
    want = -np.array([40.0, 15.0]) * d
    np.testing.assert_allclose(_ee_force(scene, data, theta), want, atol=0.35)
    # at the neutral point the cables pull nothing
    data = _data(scene, scene.dynamics.ik(np.asarray(neutral)))
    np.testing.assert_allclose(data.qfrc_passive, 0.0, atol=1e-9)


def test_drag_hysteresis_is_dry_friction_proportional_to_each_springs_stiffness():
    cfg = CapstanConfig(drag_stiffness_N_per_m=40.0, drag_stiffness_y_N_per_m=10.0, drag_hysteresis_m=0.02)
    scene = _scene("fixture", cfg)
    for axis, k in (("x", 40.0), ("y", 10.0)):
        tendon = _id(scene, mujoco.mjtObj.mjOBJ_TENDON, f"drag_{axis}")
        assert scene.model.tendon_frictionloss[tendon] == pytest.approx(0.02 * k)  # N


def _link_inertia(scene: CapstanScene, theta) -> np.ndarray:
    """(2, 2) joint-space inertia of the shoulder and elbow dofs (rotors excluded), kg·m²."""
    data = _data(scene, theta)
    nv, dof = scene.model.nv, scene.robot_dof[2:]
    M = np.zeros((nv, nv))
    for j in range(nv):
        column = np.zeros(nv)
        mujoco.mj_mulM(scene.model, data, column, np.eye(nv)[j])
        M[:, j] = column
    return M[np.ix_(dof, dof)]


def test_identification_mass_is_on_the_identified_robot_only():
    # The robot as identified (load none: the point mass on the handle) is the MJCF's, i.e. Table
    # VI; the robot of the impedance trials lacks a point mass m_e at the end effector, so its
    # inertia is lower by m_e J^T J (J: d X / d (shoulder, elbow)); seen to 1e-16 kg·m²
    m_e = 0.195  # kg, the default capstan.id_ee_mass_kg
    plain = CapstanConfig(drag=False, id_ee_mass_kg=0.0)
    with_err = CapstanConfig(drag=False, id_ee_mass_kg=m_e)
    for theta in (HOME, np.array([0.5, 1.2])):
        np.testing.assert_allclose(
            _link_inertia(_scene("none", with_err), theta),
            _link_inertia(_scene("none", plain), theta),
            atol=2e-6,  # the point mass's own spin inertia, 1e-6 kg·m² (0.002 % of alpha3)
        )
        J = _scene("none", plain).dynamics.jacobian(theta) @ np.array([[1.0, 0.0], [1.0, 1.0]])
        lost = _link_inertia(_scene("fixture", plain), theta) - _link_inertia(
            _scene("fixture", with_err), theta
        )
        np.testing.assert_allclose(lost, m_e * J.T @ J, atol=1e-12)
    with pytest.raises(ConfigError, match="id_ee_mass_kg"):
        _scene("fixture", CapstanConfig(id_ee_mass_kg=5.0))


# --- arm -----------------------------------------------------------------------------------


def test_arm_posture_puts_the_hand_on_the_grip():
    scene = _scene("arm")
    theta, arm_q = _pose(scene)
    data = _data(scene, theta, arm_q)
    sd = data.sensordata
    np.testing.assert_allclose(scene.sensor(sd, "p_ee")[:2], HANDLE_XY, atol=1e-12)
    np.testing.assert_allclose(scene.sensor(sd, "p_hand")[:2], scene.sensor(sd, "p_ee")[:2], atol=1e-6)
    # the grip and the hand are at the same height: the connect equality is satisfied at t = 0
    hand_grip = _id(scene, mujoco.mjtObj.mjOBJ_EQUALITY, "hand_grip")
    assert scene.model.eq_active0[hand_grip]
    assert np.max(np.abs(data.efc_pos[: data.nefc])) < 1e-9
    # the shoulder 0.5 m behind the handle along +x (the subject faces the robot)
    np.testing.assert_allclose(scene.shoulder_pos, HANDLE_XY + [REACH_M, 0.0], atol=1e-15)
    np.testing.assert_allclose(scene.sensor(sd, "p_shoulder_site")[:2], scene.shoulder_pos, atol=1e-12)
    # a human elbow: flexed, inside the skeleton's 0..2.6 rad
    assert 0.0 < arm_q[1] < 2.6
    # upper arm 0.326 m, forearm to the cuff 0.30 m (models/arm_planar/skeleton.xml)
    assert (scene.arm_l1, scene.arm_l2) == pytest.approx((0.326, 0.30), rel=1e-12)
    elbow = scene.sensor(sd, "p_elbow_site")[:2]
    assert np.linalg.norm(elbow - scene.shoulder_pos) == pytest.approx(0.326, rel=1e-9)
    assert np.linalg.norm(HANDLE_XY - elbow) == pytest.approx(0.30, rel=1e-9)


def test_arm_scene_addresses_its_muscles():
    scene = _scene("arm")
    assert scene.arm_qpos.shape == (2,) and scene.arm_dof.shape == (2,)
    assert scene.muscle_act.shape == (6,) and scene.motor_act.shape == (2,)
    data = _data(scene, *_pose(scene), act=0.3)
    np.testing.assert_array_equal(data.act[scene.model.actuator_actadr[scene.muscle_act]], 0.3)
    none = _scene("none")
    assert none.arm_qpos.size == 0 and none.muscle_act.size == 0 and np.all(np.isnan(none.shoulder_pos))


# --- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize("payload", [0.0, -1.0, None, math.nan, math.inf])
def test_fixture_rejects_a_bad_payload(payload):
    with pytest.raises(ConfigError, match="payload"):
        _scene("fixture", payload_kg=payload)


def test_fixture_needs_an_array():
    with pytest.raises(ConfigError, match="SpringArray"):
        _scene("fixture", array=None)
    with pytest.raises(ConfigError, match="SpringArray"):
        _scene("fixture", array=TABLE_I_STIFFNESS["K1"])  # a Table I row is not an array


def test_unknown_load_rejected():
    with pytest.raises(ConfigError, match=r"load='table'.*'none', 'fixture', 'arm'"):
        build_capstan_scene(CapstanConfig(), "table", **SIM)


def test_arm_load_needs_linear_muscles_and_a_handle_position():
    with pytest.raises(ConfigError, match="linear"):
        _scene("arm", arm=replace(ARM, muscle="hill"))
    with pytest.raises(ConfigError, match="handle_xy"):
        _scene("arm", handle_xy=None)
    with pytest.raises(ConfigError, match="ArmConfig"):
        _scene("arm", arm=None)


def test_arm_only_calls_raise_model_error():
    none = _scene("none")
    with pytest.raises(ModelError, match="load='arm'"):
        none.arm_posture(HANDLE_XY)
    arm = _scene("arm")
    with pytest.raises(ModelError, match="arm_q"):
        arm.initial_state(arm.dynamics.ik(HANDLE_XY))
    with pytest.raises(ModelError, match="p_hand"):
        none.sensor(np.zeros(none.model.nsensordata), "p_hand")


def test_fixture_rejects_a_non_numeric_payload():
    with pytest.raises(ConfigError, match="payload"):
        _scene("fixture", payload_kg="heavy")

"""The capstan robot: the MJCF realises Eqs. (11)-(13) with Table VI, and the analytic model agrees."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from armlab.errors import ConfigError, DataError
from armlab.models.capstan_robot import (
    CABLE_DAMPING_NMS_PER_RAD,
    CABLE_STIFFNESS_NM_PER_RAD,
    CAPSTAN_RATIO,
    HANDLE_MASS_KG,
    LINK1_LENGTH_M,
    LINK2_LENGTH_M,
    ROTOR_INERTIA_KGM2,
    TABLE_VI_ALPHA,
    CapstanDynamics,
    CapstanParameters,
)
from armlab.models.scene import model_file

DYN = CapstanDynamics()
ALPHA = TABLE_VI_ALPHA.as_array()
# The MJCF's mass properties are decimal numbers with 15 significant digits: exact to ~1e-15.
EXACT = dict(rtol=1e-9, atol=1e-12)


def _model(*, rigid: bool, handle: bool = True) -> mujoco.MjModel:
    model = mujoco.MjModel.from_xml_path(str(model_file("capstan_planar", "capstan_planar.xml")))
    model.opt.timestep = 0.001  # the paper's 1 kHz loop
    model.eq_active0[:] = rigid
    if not handle:  # the robot as identified in the Appendix: Table VI excludes the handle
        hid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "handle")
        model.body_mass[hid] = 0.0
        model.body_inertia[hid] = 0.0
    return model


def _addr(model: mujoco.MjModel) -> dict[str, int]:
    return {
        name: int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)])
        for name in ("shoulder", "elbow", "rotor1", "rotor2")
    }


def _rigid_map(model: mujoco.MjModel) -> np.ndarray:
    """(nv, 2): qvel = T Theta_dot for a rigid capstan (q1 = t1, q2 = t2 - t1, rotor_i = N t_i)."""
    a = _addr(model)
    t = np.zeros((model.nv, 2))
    t[a["shoulder"]] = (1.0, 0.0)
    t[a["elbow"]] = (-1.0, 1.0)
    t[a["rotor1"], 0] = t[a["rotor2"], 1] = CAPSTAN_RATIO
    return t


def _set_state(model, data, theta, theta_dot, theta_ddot=(0.0, 0.0)) -> None:
    t = _rigid_map(model)  # all joints are hinges with qpos0 = 0: qpos = T Theta as well
    data.qpos[:] = t @ np.asarray(theta)
    data.qvel[:] = t @ np.asarray(theta_dot)
    data.qacc[:] = t @ np.asarray(theta_ddot)


def _random_states(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t1 = rng.uniform(-1.2, 1.2, n)
    theta = np.stack([t1, t1 + rng.uniform(-1.0, 1.0, n)], axis=-1)  # inside the joint ranges
    return theta, rng.uniform(-3.0, 3.0, (n, 2)), rng.uniform(-20.0, 20.0, (n, 2))


def _full_inertia(model, data) -> np.ndarray:
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)  # mujoco >= 3.11: data.qM is gone, mj_fullM(m, d, dst)
    return full


@pytest.mark.parametrize("rigid", [True, False], ids=["rigid", "compliant"])
def test_compiles_and_steps_two_seconds_without_warnings(rigid):
    model = _model(rigid=rigid)
    data = mujoco.MjData(model)
    _set_state(model, data, (np.pi / 4, np.pi / 4), (0.0, 0.0))
    a = _addr(model)
    t = np.arange(2000) * model.opt.timestep
    psi = np.zeros((t.size, 2))
    for k, tk in enumerate(t):  # a 1.5 N m, 3 Hz torque on both axes: excites the cable a little
        data.ctrl[:] = 1.5 * np.sin(2 * np.pi * 3.0 * tk) * np.array([1.0, -1.0])
        mujoco.mj_step(model, data)
        psi[k] = data.qpos[[a["rotor1"], a["rotor2"]]] / CAPSTAN_RATIO - (
            data.qpos[a["shoulder"]],
            data.qpos[a["shoulder"]] + data.qpos[a["elbow"]],
        )
    assert all(w.number == 0 for w in data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.sensordata))
    stretch = np.max(np.abs(psi))
    # compliant: 1.5 N m over 200 N m/rad is ~7.5 mrad plus the dynamic part; the rigid
    # equality holds the cable to a tiny fraction of that (soft constraint, 2 ms time constant)
    if rigid:  # seen: 4.5e-7 rad
        assert stretch < 1e-5
    else:
        assert 1e-3 < stretch < 3e-2
    assert np.all(np.abs(data.qpos[[a["shoulder"], a["elbow"]]]) < 1.3)


def test_constants_mirror_the_mjcf():
    model = _model(rigid=False)

    def idx(obj, name):
        return mujoco.mj_name2id(model, obj, name)

    assert model.body_pos[idx(mujoco.mjtObj.mjOBJ_BODY, "link2")][:2] == pytest.approx([LINK1_LENGTH_M, 0])
    assert model.site_pos[idx(mujoco.mjtObj.mjOBJ_SITE, "ee")][:2] == pytest.approx([0, -LINK2_LENGTH_M])
    for i in (1, 2):
        act, rotor = (
            idx(mujoco.mjtObj.mjOBJ_ACTUATOR, f"motor{i}"),
            idx(mujoco.mjtObj.mjOBJ_BODY, f"rotor{i}"),
        )
        cable = idx(mujoco.mjtObj.mjOBJ_TENDON, f"cable{i}")
        assert model.actuator_gear[act, 0] == pytest.approx(1 / CAPSTAN_RATIO)
        assert model.body_inertia[rotor, 2] == pytest.approx(ROTOR_INERTIA_KGM2)
        assert model.tendon_stiffness[cable] == pytest.approx(CABLE_STIFFNESS_NM_PER_RAD)
        assert model.tendon_damping[cable] == pytest.approx(CABLE_DAMPING_NMS_PER_RAD)
        theta = idx(mujoco.mjtObj.mjOBJ_TENDON, f"theta{i}")
        assert model.tendon_damping[theta] == pytest.approx(TABLE_VI_ALPHA.alpha[2 + i])
    assert model.body_mass[idx(mujoco.mjtObj.mjOBJ_BODY, "handle")] == pytest.approx(HANDLE_MASS_KG)
    assert not model.eq_active0.any()  # compliant by default


@pytest.mark.parametrize("handle", [False, True], ids=["bare", "with_handle"])
def test_mujoco_inertia_in_absolute_angles_is_eq11_with_table_vi(handle):
    model = _model(rigid=True, handle=handle)
    data = mujoco.MjData(model)
    t = _rigid_map(model)
    hid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "handle")
    for theta in _random_states(20, seed=1)[0]:
        _set_state(model, data, theta, (0.0, 0.0))
        mujoco.mj_forward(model, data)
        expected = DYN.inertia(theta)
        if handle:  # Eq. (9)'s point mass Lambda at the end effector, plus its own spin inertia
            jac = DYN.jacobian(theta)
            expected = expected + HANDLE_MASS_KG * jac.T @ jac + np.diag([0.0, model.body_inertia[hid, 2]])
        np.testing.assert_allclose(t.T @ _full_inertia(model, data) @ t, expected, **EXACT)


@pytest.mark.parametrize("rigid", [True, False], ids=["rigid", "compliant"])
def test_mujoco_inverse_dynamics_matches_the_analytic_model(rigid):
    # Constraint forces of the rigid cable are orthogonal to T (J_eq T = 0) and a cable at
    # psi = psi_dot = 0 carries no force, so T^T qfrc_inverse is the torque of Eq. (1) either way.
    model = _model(rigid=rigid, handle=False)
    data = mujoco.MjData(model)
    t = _rigid_map(model)
    for theta, theta_dot, theta_ddot in zip(*_random_states(20, seed=2), strict=True):
        _set_state(model, data, theta, theta_dot, theta_ddot)
        mujoco.mj_inverse(model, data)
        np.testing.assert_allclose(
            t.T @ data.qfrc_inverse, DYN.inverse_dynamics(theta, theta_dot, theta_ddot), **EXACT
        )


def test_actuator_ctrl_is_the_link_side_joint_torque():
    model = _model(rigid=False)
    data = mujoco.MjData(model)
    data.ctrl[:] = (2.0, -3.0)
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(_rigid_map(model).T @ data.qfrc_actuator, [2.0, -3.0], **EXACT)
    names = [model.sensor(i).name for i in range(model.nsensor)]
    adr = dict(zip(names, model.sensor_adr, strict=True))
    assert data.sensordata[adr["tau1"]] == 2.0 and data.sensordata[adr["tau2"]] == -3.0


def test_rigid_forward_dynamics_matches_within_the_constraint_softness():
    model = _model(rigid=True, handle=False)
    data = mujoco.MjData(model)
    a = _addr(model)
    rng = np.random.default_rng(3)
    theta, theta_dot, _ = _random_states(10, seed=3)
    for th, thd in zip(theta, theta_dot, strict=True):
        tau = rng.uniform(-5.0, 5.0, 2)
        _set_state(model, data, th, thd)
        data.ctrl[:] = tau
        mujoco.mj_forward(model, data)
        qacc = data.qacc
        got = np.array([qacc[a["shoulder"]], qacc[a["shoulder"]] + qacc[a["elbow"]]])
        # solimp 0.9999: the soft equality lets ~1e-4 of the rotor-link acceleration mismatch
        # through (seen: 1.05e-4 relative); allow 5e-4 of the largest acceleration
        want = DYN.forward_dynamics(th, thd, tau)
        np.testing.assert_allclose(got, want, atol=5e-4 * np.abs(want).max())


def test_regressor_reproduces_inverse_dynamics_and_coriolis_is_consistent():
    theta, theta_dot, theta_ddot = _random_states(50, seed=4)
    y = DYN.regressor(theta, theta_dot, theta_ddot)
    assert y.shape == (50, 2, 5)
    np.testing.assert_allclose(y @ ALPHA, DYN.inverse_dynamics(theta, theta_dot, theta_ddot), **EXACT)
    # dI/dt - 2C is skew-symmetric (central differences along the motion, eps 1e-6: error ~1e-12)
    eps = 1e-6
    i_dot = (DYN.inertia(theta + eps * theta_dot) - DYN.inertia(theta - eps * theta_dot)) / (2 * eps)
    n = i_dot - 2 * DYN.coriolis(theta, theta_dot)
    np.testing.assert_allclose(n, -np.swapaxes(n, -1, -2), atol=1e-8)
    # forward dynamics inverts inverse dynamics
    tau = DYN.inverse_dynamics(theta, theta_dot, theta_ddot)
    np.testing.assert_allclose(DYN.forward_dynamics(theta, theta_dot, tau), theta_ddot, rtol=1e-10, atol=1e-9)


def test_least_squares_on_mujoco_torques_recovers_table_vi():
    # The Appendix experiment, noise free: each joint tracks ten sinusoids in 0.1..2 Hz over a
    # 40 degree range for 10 s at 1 kHz; torques from MuJoCo's inverse dynamics of the rigid robot.
    rng = np.random.default_rng(5)
    time = np.arange(0.0, 10.0, 1e-3)[:, None, None]
    freq = 2 * np.pi * np.linspace(0.1, 2.0, 10)
    amp = np.deg2rad(20.0) / 10
    phase = rng.uniform(0, 2 * np.pi, (2, 10))
    arg = freq * time + phase  # (n, 2, 10)
    theta = np.array([np.pi / 4, np.pi / 4]) + (amp * np.sin(arg)).sum(-1)
    theta_dot = (amp * freq * np.cos(arg)).sum(-1)
    theta_ddot = -(amp * freq**2 * np.sin(arg)).sum(-1)
    model = _model(rigid=True, handle=False)
    data = mujoco.MjData(model)
    t = _rigid_map(model)
    tau = np.empty_like(theta)
    for k in range(theta.shape[0]):
        _set_state(model, data, theta[k], theta_dot[k], theta_ddot[k])
        mujoco.mj_inverse(model, data)
        tau[k] = t.T @ data.qfrc_inverse
    y = DYN.regressor(theta, theta_dot, theta_ddot).reshape(-1, 5)
    alpha, *_ = np.linalg.lstsq(y, tau.reshape(-1), rcond=None)
    np.testing.assert_allclose(alpha, ALPHA, rtol=1e-6)


def test_fk_and_jacobians_match_the_ee_site():
    model = _model(rigid=False)
    data = mujoco.MjData(model)
    t = _rigid_map(model)
    sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "ee")
    jacp = np.zeros((3, model.nv))
    theta, theta_dot, _ = _random_states(20, seed=6)
    for th in theta:
        _set_state(model, data, th, (0.0, 0.0))
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.site_xpos[sid, :2], DYN.fk(th), **EXACT)
        mujoco.mj_jacSite(model, data, jacp, None, sid)
        np.testing.assert_allclose(jacp[:2] @ t, DYN.jacobian(th), **EXACT)
    # dJ/dt by central differences along the motion (error ~eps², ~1e-12)
    eps = 1e-6
    fd = (DYN.jacobian(theta + eps * theta_dot) - DYN.jacobian(theta - eps * theta_dot)) / (2 * eps)
    np.testing.assert_allclose(DYN.jacobian_dot(theta, theta_dot), fd, atol=1e-8)
    assert DYN.fk(np.array([np.pi / 4, np.pi / 4])) == pytest.approx([0.7 * np.sqrt(0.5), 0.0], abs=1e-15)


def test_eq7_from_the_ee_accelerometer_gives_the_link_accelerations():
    # compliant robot, cable at rest: the links' accelerations are whatever the cable and the
    # dynamics give; the accelerometer (ee site frame, link 2's body axes) rotated into the base frame
    # and Eq. (7) must return them
    model = _model(rigid=False)
    data = mujoco.MjData(model)
    a = _addr(model)
    sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "ee")
    adr = {model.sensor(i).name: int(model.sensor_adr[i]) for i in range(model.nsensor)}
    theta, theta_dot, _ = _random_states(10, seed=7)
    for k, (th, thd) in enumerate(zip(theta, theta_dot, strict=True)):
        _set_state(model, data, th, thd)
        data.qpos[a["rotor1"]] += 0.01 * CAPSTAN_RATIO * (-1) ** k  # a stretched cable pulls
        mujoco.mj_forward(model, data)
        acc_site = data.sensordata[adr["ee_acc"] : adr["ee_acc"] + 3]
        rot = data.site_xmat[sid].reshape(3, 3)
        c, s = np.cos(th[1]), np.sin(th[1])  # the site frame is turned by theta2 (README)
        np.testing.assert_allclose(rot, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-12)
        acc = rot @ acc_site
        assert acc[2] == pytest.approx(9.81)  # the default gravity, normal to the plane
        want = [data.qacc[a["shoulder"]], data.qacc[a["shoulder"]] + data.qacc[a["elbow"]]]
        np.testing.assert_allclose(DYN.joint_acceleration(th, thd, acc[:2]), want, rtol=1e-9, atol=1e-9)


def test_cable_spring_acts_on_the_absolute_angle():
    model = _model(rigid=False)
    data = mujoco.MjData(model)
    a = _addr(model)
    data.qpos[a["rotor2"]] = 0.01 * CAPSTAN_RATIO  # psi2 = +0.01 rad: link 2 pulled forward
    mujoco.mj_forward(model, data)
    qfp = data.qfrc_passive
    # link-side torques on the absolute angles: q = (t1, t2 - t1), so tau_t = (tau_q1 - tau_q2, tau_q2)
    link_torque = np.array([qfp[a["shoulder"]] - qfp[a["elbow"]], qfp[a["elbow"]]])
    # on the link side the cable pulls theta2 with k psi; on the rotor it holds back with k psi / N
    assert data.qfrc_passive[a["rotor2"]] == pytest.approx(-CABLE_STIFFNESS_NM_PER_RAD * 0.01 / CAPSTAN_RATIO)
    assert link_torque == pytest.approx([0.0, CABLE_STIFFNESS_NM_PER_RAD * 0.01])


def test_bad_inputs_are_rejected_with_the_valid_form():
    with pytest.raises(ConfigError, match="positive definite"):
        CapstanParameters(alpha=(0.01, 0.5, 0.01, 0.0, 0.0))
    with pytest.raises(ConfigError, match="5 finite"):
        CapstanParameters(alpha=(1.0, 0.0, 1.0))
    with pytest.raises(DataError, match=r"\(\.\.\., 2\)"):
        DYN.inertia(np.zeros(3))
    assert CapstanParameters.from_array(ALPHA) == CapstanParameters(alpha=TABLE_VI_ALPHA.alpha)

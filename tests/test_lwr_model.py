"""Tests for the LWR-III / LBR4+ class robot model, models/lwr/lwr.xml.

Numbers checked here are the published figures the model cites (models/lwr/README.md), not values
read back from the model.
"""

from pathlib import Path

import mujoco
import numpy as np
import pytest
from dm_control import mjcf

LWR_XML = Path(__file__).resolve().parents[1] / "models" / "lwr" / "lwr.xml"

JOINTS = [f"lwr_j{i}" for i in range(1, 8)]
LINKS = [f"lwr_link{i}" for i in range(1, 8)]
# Joint axes in the parent-link frame: z, -y, z, +y, z, -y, z (KUKA sign convention).
AXES = [(0, 0, 1), (0, -1, 0), (0, 0, 1), (0, 1, 0), (0, 0, 1), (0, -1, 0), (0, 0, 1)]
# LBR4+/LWR-III joint ranges, deg, and torque limits, N*m.
RANGE_DEG = [170, 120, 170, 120, 170, 120, 170]
TORQUE_LIMIT = [176, 176, 100, 100, 100, 38, 38]
# Base->shoulder, shoulder->elbow, elbow->wrist, wrist->flange, m. 0.3105 m is the figure of both open
# LBR4+ descriptions; the DH tables round it to 0.31 m (0.5 mm, inside the 1 mm tolerance either way).
LINK_LENGTHS = [0.3105, 0.40, 0.39, 0.078]
# Published totals: LWR-III 13.5 kg (Albu-Schaeffer et al. 2007), LBR4+ 16 kg (KUKA).
MASS_TOTAL_MIN, MASS_TOTAL_MAX = 13.5, 16.0


@pytest.fixture()
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(LWR_XML))


def _assert_no_warnings(data: mujoco.MjData) -> None:
    counts = {mujoco.mjtWarning(i).name: int(data.warning[i].number) for i in range(len(data.warning))}
    assert all(n == 0 for n in counts.values()), counts


def _simulate(model: mujoco.MjModel, qpos0, ctrl, duration: float) -> tuple[np.ndarray, mujoco.MjData]:
    """Steps from rest; returns qpos history (n_steps, 7) rad and the final data."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos0
    data.ctrl[:] = ctrl
    n_steps = round(duration / model.opt.timestep)
    history = np.empty((n_steps, model.nq))
    for k in range(n_steps):
        mujoco.mj_step(model, data)
        history[k] = data.qpos
    _assert_no_warnings(data)
    return history, data


def test_names_and_counts(model):
    assert model.nq == model.nv == model.nu == 7
    assert [model.body(i).name for i in range(1, model.nbody)] == ["lwr_base", *LINKS]
    assert [model.joint(i).name for i in range(model.njnt)] == JOINTS
    assert [model.actuator(i).name for i in range(model.nu)] == [f"lwr_a{i}" for i in range(1, 8)]
    names = [model.sensor(i).name for i in range(model.nsensor)]
    assert names == [f"lwr_q{i}" for i in range(1, 8)] + [f"lwr_tau{i}" for i in range(1, 8)]
    assert model.site("flange").bodyid[0] == model.body("lwr_link7").id


def test_joints_hinge_axes_and_limits(model):
    for i, name in enumerate(JOINTS):
        joint = model.joint(name)
        assert joint.type[0] == mujoco.mjtJoint.mjJNT_HINGE
        assert model.jnt_limited[joint.id]
        np.testing.assert_allclose(joint.axis, AXES[i])
        np.testing.assert_allclose(joint.range, np.deg2rad([-RANGE_DEG[i], RANGE_DEG[i]]), atol=1e-5)


def test_actuators_position_servos_with_lwr_torque_limits(model):
    for i in range(7):
        actuator = model.actuator(f"lwr_a{i + 1}")
        assert actuator.trnid[0] == model.joint(JOINTS[i]).id
        kp = actuator.gainprm[0]
        assert kp >= 1000.0  # a stiff position-controlled joint: thousands of N*m/rad
        np.testing.assert_allclose(actuator.biasprm[:2], [0.0, -kp])
        assert actuator.biasprm[2] < 0.0  # kv > 0
        assert actuator.forcelimited[0]
        np.testing.assert_allclose(actuator.forcerange, [-TORQUE_LIMIT[i], TORQUE_LIMIT[i]])


def test_every_link_gravity_compensated(model):
    for name in LINKS:
        assert model.body_gravcomp[model.body(name).id] == 1.0


def test_total_mass_within_published_totals(model):
    total = sum(model.body(name).mass[0] for name in ["lwr_base", *LINKS])
    assert MASS_TOTAL_MIN <= total <= MASS_TOTAL_MAX


def test_flange_at_sum_of_link_lengths_at_zero_posture(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(data.site("flange").xpos, [0.0, 0.0, sum(LINK_LENGTHS)], atol=1e-3)
    # The 0.31 m rounding used in DH tables is also within 1 mm.
    assert abs(data.site("flange").xpos[2] - (0.31 + 0.40 + 0.39 + 0.078)) < 1e-3
    # z-axis of the flange site points out of the flange: straight up at q = 0.
    np.testing.assert_allclose(data.site("flange").xmat.reshape(3, 3)[:, 2], [0.0, 0.0, 1.0], atol=1e-12)


@pytest.mark.parametrize(
    "integrator", [mujoco.mjtIntegrator.mjINT_EULER, mujoco.mjtIntegrator.mjINT_IMPLICITFAST]
)
def test_hundred_steps_no_warnings_and_finite(model, integrator):
    model.opt.integrator = integrator
    history, data = _simulate(model, np.zeros(7), np.zeros(7), duration=100 * model.opt.timestep)
    assert history.shape[0] == 100
    assert np.all(np.isfinite(history))
    assert np.all(np.isfinite(data.qvel))
    assert np.all(np.isfinite(data.sensordata))


def test_gravcomp_holds_zero_posture(model):
    history, _ = _simulate(model, np.zeros(7), np.zeros(7), duration=1.0)
    assert np.abs(history).max() < 1e-3


def test_gravcomp_holds_bent_posture_and_shows_in_joint_torque(model):
    # At q = 0 gravity torques vanish, so also hold a bent posture: with gravcomp the servo carries no
    # gravity error; without it the error is tau_g / kp, several mrad here.
    q0 = np.array([0.3, 0.6, -0.2, -1.2, 0.4, 0.8, 0.1])
    history, data = _simulate(model, q0, q0, duration=1.0)
    assert np.abs(history - q0).max() < 1e-3
    # Gravity compensation is delivered by the drives, so the joint torque sensors read g(q).
    np.testing.assert_allclose(data.sensordata[7:], data.qfrc_gravcomp, atol=1e-6)
    assert np.abs(data.sensordata[7:]).max() > 1.0

    model.body_gravcomp[:] = 0.0
    history_off, _ = _simulate(model, q0, q0, duration=1.0)
    assert np.abs(history_off[-1] - q0).max() > 1e-3


def test_step_on_joint_2_settles(model):
    # kp = 5000 N*m/rad, kv = 250 N*m*s/rad, M22(q=0) = 2.80 kg*m^2 (incl. armature): wn = 42 rad/s,
    # damping ratio 1.06, so the linear 2 % settling time is about 5.8 / wn = 0.14 s with no overshoot.
    # The 0.1 rad step asks kp * 0.1 = 500 N*m, above the 176 N*m limit, so the drive saturates first;
    # measured 2 % settling is 0.15-0.16 s (Euler or implicitfast, 1 or 2 ms). Bound: 0.25 s.
    target = np.zeros(7)
    target[1] = 0.1
    history, data = _simulate(model, np.zeros(7), target, duration=0.5)
    t = model.opt.timestep * np.arange(1, history.shape[0] + 1)
    q2 = history[:, 1]
    outside = np.flatnonzero(np.abs(q2 - 0.1) > 0.002)
    settling_time = t[outside[-1] + 1]
    assert settling_time < 0.25
    assert q2.max() < 0.1 + 1e-3  # overshoot below 1 %
    assert abs(q2[-1] - 0.1) < 1e-4
    np.testing.assert_allclose(np.delete(history[-1], 1), 0.0, atol=1e-3)  # other joints held
    assert abs(data.sensor("lwr_tau2").data[0]) <= TORQUE_LIMIT[1]


def test_loads_and_compiles_through_dm_control():
    mjcf_model = mjcf.from_path(str(LWR_XML))
    assert mjcf_model.model == "lwr"
    assert mjcf_model.find("site", "flange") is not None
    physics = mjcf.Physics.from_mjcf_model(mjcf_model)
    assert physics.model.nu == 7
    physics.step()
    assert np.all(np.isfinite(physics.data.qpos))


def test_attaches_into_a_scene_with_dm_control():
    scene = mjcf.RootElement(model="scene")
    mount = scene.worldbody.add("site", name="robot_mount", pos=[0.0, 0.0, 0.5])
    mount.attach(mjcf.from_path(str(LWR_XML)))
    physics = mjcf.Physics.from_mjcf_model(scene)
    physics.forward()
    flange = physics.named.data.site_xpos["lwr/flange"]
    np.testing.assert_allclose(flange, [0.0, 0.0, 0.5 + sum(LINK_LENGTHS)], atol=1e-3)

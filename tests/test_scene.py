"""Tests for armlab.models.scene and the MJCF files under models/ (STYLE.md 8: every scene compiles
and steps without a MuJoCo warning)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from contact_check import assert_contacts_off_changes_nothing
from numpy.testing import assert_array_equal

from armlab.config.schema import ArmConfig
from armlab.errors import ConfigError, ModelError
from armlab.models.scene import MODELS_DIR, MUSCLES, model_file

ALL_XML = sorted(MODELS_DIR.glob("**/*.xml"))
FULL_MODELS = [p for p in ALL_XML if ET.parse(p).getroot().tag == "mujoco"]  # skip <mujocoinclude>


def _warnings(data: mujoco.MjData) -> dict[str, int]:
    return {mujoco.mjtWarning(i).name: int(data.warning[i].number) for i in range(len(data.warning))}


def _step_seconds(model: mujoco.MjModel, data: mujoco.MjData, seconds: float) -> None:
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)


def test_model_discovery_finds_the_known_files():
    names = {p.name for p in FULL_MODELS}
    assert {"arm_planar_linear.xml", "arm_planar_hill.xml", "lwr.xml", "cuff.xml", "cuff_shell.xml"} <= names
    assert "skeleton.xml" not in names  # include-only


@pytest.mark.parametrize("path", FULL_MODELS, ids=lambda p: str(p.relative_to(MODELS_DIR)))
def test_standalone_model_steps_one_second_without_warnings(path):
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    # Position servos (joint transmission with a bias) hold their joint's current position; all
    # other actuators (muscles) get zero control.
    for i in range(model.nu):
        if model.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT and model.actuator_biastype[i] != 0:
            data.ctrl[i] = data.qpos[model.jnt_qposadr[model.actuator_trnid[i, 0]]]
    _step_seconds(model, data, 1.0)
    assert all(n == 0 for n in _warnings(data).values()), _warnings(data)
    assert np.all(np.isfinite(data.qpos))


def test_composed_scene_steps_one_second_without_warnings(lab):
    model, hold = lab.scene.model, lab.hold
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, hold.state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    data.ctrl[:] = hold.ctrl
    data.ctrl[lab.scene.robot_act] = data.qpos[lab.scene.robot_qpos]  # servos hold the settled posture
    _step_seconds(model, data, 1.0)
    assert all(n == 0 for n in _warnings(data).values()), _warnings(data)
    assert np.all(np.isfinite(data.qpos))
    assert np.all(np.isfinite(data.sensordata))


def test_scene_indices(lab):
    scene = lab.scene
    model = scene.model
    assert len(scene.arm_qpos) == len(scene.arm_dof) == 2
    assert len(scene.robot_qpos) == len(scene.robot_dof) == len(scene.robot_act) == 7
    assert len(scene.cuff_dof) == (0 if lab.rigid else 3)
    assert model.nv == 2 + 7 + len(scene.cuff_dof)
    assert len(scene.muscle_act) == 6
    names = [model.actuator(int(i)).name for i in scene.muscle_act]
    assert names == [f"arm_planar/{m}" for m in MUSCLES]
    arm_joints = [model.joint(int(j)).name for j in model.dof_jntid[scene.arm_dof]]
    assert arm_joints == ["arm_planar/shoulder", "arm_planar/elbow"]
    # segment lengths from models/arm_planar/skeleton.xml; read back through a norm, so exact to rounding
    assert scene.l1 == pytest.approx(0.326, abs=1e-12)
    assert scene.l2 == pytest.approx(0.30, abs=1e-12)
    for m in MUSCLES:
        assert scene.sensors[f"len_{m}"].stop - scene.sensors[f"len_{m}"].start == 1
    assert min(scene.contact_site, scene.hand_site, scene.flange_site) >= 0


def test_unknown_sensor_names_available_ones(lab):
    with pytest.raises(ModelError, match="len_elbow_flexor"):
        lab.scene.sensor(np.zeros(lab.scene.model.nsensordata), "nope")


def test_missing_model_file_names_available_files():
    with pytest.raises(ModelError) as info:
        model_file("arm_planar", "nope.xml")
    msg = str(info.value)
    assert "nope.xml" in msg
    for name in ("arm_planar_hill.xml", "arm_planar_linear.xml", "skeleton.xml"):
        assert name in msg


def test_unknown_muscle_variant_lists_valid_ones():
    with pytest.raises(ConfigError) as info:
        ArmConfig(muscle="nope")
    msg = str(info.value)
    assert "'nope'" in msg and "'hill'" in msg and "'linear'" in msg


@pytest.mark.parametrize("rigid", [True, False])
def test_lab_scene_skips_collision_detection_and_no_trajectory_changes(rigid):
    # the conditioning lab couples arm, cuff and robot by joints and tendons only: collision
    # detection is off (the speed), and with it switched back on a perturbed hold steps the same
    # bit for bit (activations, cuff slides, servos and muscles all moving)
    from armlab.config.schema import CuffConfig, RobotConfig, SimConfig
    from armlab.models.scene import build_scene

    scene = build_scene(ArmConfig(), CuffConfig(rigid=rigid), RobotConfig(), SimConfig())

    def perturbed_hold(data):
        data.qpos[scene.arm_qpos] = (0.6, 1.2)
        data.ctrl[scene.muscle_act] = (0.3, 0.1, 0.2, 0.4, 0.1, 0.3)
        data.ctrl[scene.robot_act] = 0.1

    assert_contacts_off_changes_nothing(scene, perturbed_hold, 1000)


def test_sensors_side_by_side_are_a_view_where_they_lie_in_order(lab):
    scene = lab.scene
    sd = np.arange(3 * scene.model.nsensordata, dtype=float).reshape(3, -1)
    names = [f"lwr_q{i}" for i in range(1, 8)]
    joined = np.concatenate([scene.sensor(sd, n) for n in names], axis=-1)
    view = scene.sensors_of(sd, names)
    assert_array_equal(view, joined)
    assert np.shares_memory(view, sd)  # no copy of a large record
    shuffled = ["lwr_q3", "lwr_q1", "ft_force"]  # not one after the other: a new array, same values
    copy = scene.sensors_of(sd, shuffled)
    assert_array_equal(copy, np.concatenate([scene.sensor(sd, n) for n in shuffled], axis=-1))
    assert not np.shares_memory(copy, sd)
    with pytest.raises(ModelError, match="no sensor 'lwr_q9'"):
        scene.sensors_of(sd, ["lwr_q1", "lwr_q9"])

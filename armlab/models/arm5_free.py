"""The seated 5-DoF arm moving on its own (seed paper 001, Sec. 3: calibration and inertial trials).

Before the robot is coupled, the subject "moves all joint axes of the limb randomly" (kinematic
calibration) and then reaches "different predefined kinematic limb configurations ... in free
movement" (inertial trials). Neither needs the robot: this scene is ``models/arm_5dof/arm_5dof.xml``
alone with one joint position servo per hinge standing for the subject's own motor control
(spec 001, design: "joint servos drive the arm to the 40 configurations"). A servo's torque acts
between two segments of the arm, so it is internal to what the base F/T sensor carries: at rest the
sensor reads the static weight (Eq. (22)) whatever the servos do. The muscles stay in the model
with zero activation (they pull only when active).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.arm5_scene import ARM5_LAB_TIMESTEP_S
from armlab.models.arm_5dof import ARM5_JOINTS, MARKERS
from armlab.models.scene import SensorReadout, compile_mjcf, mjcf, model_file, named_id, sensor_slices

__all__ = [
    "FREE_SERVO_KP",
    "FREE_SERVO_KV",
    "Arm5FreeScene",
    "build_arm5_free_scene",
]

# N·m/rad per joint (shoulder flexion, abduction, rotation, elbow flexion, pronation): the
# subject's postural control idealised as a position servo (assumption; the paper does not model
# it). 200 N·m/rad at the shoulder holds its ~10 N·m gravity load within ~0.05 rad (the sag is
# measured by the markers, not assumed away); the same order as the human arm's voluntary
# posture stiffness under load (tens to hundreds of N·m/rad, Shadmehr and Mussa-Ivaldi 1994 give
# joint stiffness of that order at the shoulder and elbow).
FREE_SERVO_KP = (200.0, 200.0, 100.0, 100.0, 20.0)
# N·m·s/rad: about critically damped or more with the segments' inertias about each axis
# (~0.1-0.2 kg m² at the shoulder, ~0.03 kg m² at the elbow, ~0.002 kg m² in pronation,
# models/arm_5dof README), integrated implicitly (implicitfast) at the 0.5 ms step
FREE_SERVO_KV = (20.0, 20.0, 10.0, 5.0, 1.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class Arm5FreeScene(SensorReadout):
    """The compiled free-moving arm and its addresses.

    Attributes:
        model: the compiled MjModel; ``xml``, ``assets`` its composed MJCF.
        arm_qpos, arm_dof: (5,) qpos / dof addresses in ``ARM5_JOINTS`` order.
        servo_act: (5,) the joint servos' actuator ids (same order); servo_kp, servo_kv: (5,).
        sensors: sensor name (namespace stripped) -> slice into ``sensordata`` (base F/T, the
            three marker clusters' ``*_pos`` m and ``*_quat`` (w, x, y, z), joint angles ``q_*``).
    """

    model: mujoco.MjModel
    xml: str
    assets: dict
    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    servo_act: np.ndarray
    servo_kp: np.ndarray
    servo_kv: np.ndarray
    sensors: dict[str, slice]


def _compose() -> mjcf.RootElement:
    root = mjcf.RootElement(model="arm5_free")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = ARM5_LAB_TIMESTEP_S  # s, one step per 2 kHz base F/T sample (Sec. 3)
    root.option.gravity = [0.0, 0.0, -9.81]  # m/s², standard gravity, as the arm file
    root.option.integrator = "implicitfast"  # the servos' velocity gains integrated implicitly
    arm = mjcf.from_path(str(model_file("arm_5dof", "arm_5dof.xml")))
    for key in arm.find_all("key"):  # the keyframe is the standalone model's
        key.remove()
    for name, kp, kv in zip(ARM5_JOINTS, FREE_SERVO_KP, FREE_SERVO_KV, strict=True):
        joint = arm.find("joint", name)
        if joint is None:
            raise ModelError(f"arm_5dof has no joint {name!r}")
        arm.actuator.add("position", name=f"servo_{name}", joint=joint, kp=kp, kv=kv)
    root.worldbody.add("site", name="arm_mount", pos=[0.0, 0.0, 0.0]).attach(arm)
    return root


def build_arm5_free_scene() -> Arm5FreeScene:
    """Compose, compile and index the free-moving arm (module docstring).

    Raises:
        ModelError: the composition does not compile or lacks an expected element.
    """
    model, xml, assets = compile_mjcf(_compose(), "arm5 free-movement scene", contacts=False)
    jnt, act = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR
    joints = [named_id(model, jnt, f"arm_5dof/{n}") for n in ARM5_JOINTS]
    servos = np.array([named_id(model, act, f"arm_5dof/servo_{n}") for n in ARM5_JOINTS])
    sensors = sensor_slices(model)
    missing = [f"{m}_{k}" for m in MARKERS for k in ("pos", "quat") if f"{m}_{k}" not in sensors]
    if missing:
        raise ModelError(f"arm_5dof lacks the marker sensors {missing}")
    return Arm5FreeScene(
        model=model,
        xml=xml,
        assets=assets,
        arm_qpos=model.jnt_qposadr[joints].copy(),
        arm_dof=model.jnt_dofadr[joints].copy(),
        servo_act=servos,
        servo_kp=model.actuator_gainprm[servos, 0].copy(),
        servo_kv=-model.actuator_biasprm[servos, 2].copy(),
        sensors=sensors,
    )

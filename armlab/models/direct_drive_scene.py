"""Compose the fractional-elbow lab: direct-drive motor, link and handle, and the grasping elbow.

The motor (models/direct_drive) and the elbow (models/elbow_1dof) turn about one vertical axis.
A fixed tendon ``grasp`` of length ``psi = phi - theta`` (elbow minus motor angle) carries the
grasp's spring and damper, ``k1 L²`` and ``d1 L²`` for the translational grasp values k1, d1 at
the handle radius L. The force the handle exerts on the hand along the link normal (the paper's
Y axis, positive towards increasing theta) is ``F = -(k1 L² psi + d1 L² psi_dot) / L``.

The elbow's impedance follows ``ElbowConfig.impedance``: the Hill pair of the model file
(``muscle``), a joint spring/damper (``five_element``), or a joint spring plus an actuator the
simulation drives with the fractional element's torque (``fractional``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.schema import ElbowConfig, SimConfig
from armlab.errors import ModelError
from armlab.models.scene import compile_mjcf, model_file, sensor_slices

os.environ.setdefault("MUJOCO_GL", "egl")
from dm_control import mjcf  # noqa: E402

__all__ = [
    "ELBOW_MUSCLES",
    "DirectDriveScene",
    "build_direct_drive_scene",
]

ELBOW_MUSCLES = ("elbow_flexor", "elbow_extensor")
# m, the elbow model sits above the motor on the same axis (drawing only: the axis is vertical)
_ELBOW_HEIGHT_M = 0.08


@dataclass(frozen=True, kw_only=True, eq=False)
class DirectDriveScene:
    """A compiled direct-drive + elbow scene and its addresses.

    Attributes:
        model: the compiled MjModel; ``xml`` its composed MJCF.
        impedance: the elbow's ground-truth option.
        motor_qpos, motor_dof, elbow_qpos, elbow_dof: addresses of the two hinges.
        motor_act: actuator id of the motor (ctrl in A); ``torque_constant`` N·m/A (its gear).
        muscle_act: (2,) actuator ids of the elbow muscles (empty unless ``muscle``).
        element_act: actuator id driving the fractional element (-1 unless ``fractional``).
        grasp_tendon: tendon id of the grasp; ``grasp_k``, ``grasp_d`` its rotational stiffness
            (N·m/rad) and damping (N·m·s/rad).
        link_length: m, motor axis to handle (L).
        link_inertia: kg·m², everything turning with the motor (rotor armature included).
        coulomb: N·m, the motor joint's dry friction; ``viscous`` N·m·s/rad its damping.
        elbow_inertia: kg·m², forearm and hand about the elbow axis.
        sensors: sensor name (no namespace) -> slice into ``sensordata``.
    """

    model: mujoco.MjModel
    xml: str
    impedance: str
    motor_qpos: int
    motor_dof: int
    elbow_qpos: int
    elbow_dof: int
    motor_act: int
    torque_constant: float
    muscle_act: np.ndarray
    element_act: int
    grasp_tendon: int
    grasp_k: float
    grasp_d: float
    link_length: float
    link_inertia: float
    coulomb: float
    viscous: float
    elbow_inertia: float
    sensors: dict[str, slice]

    def sensor(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """Slice one named sensor out of ``(..., nsensordata)`` sensor data."""
        try:
            return sensordata[..., self.sensors[name]]
        except KeyError:
            raise ModelError(f"scene has no sensor {name!r}; available: {sorted(self.sensors)}") from None


def _compose(elbow: ElbowConfig, sim: SimConfig) -> tuple[mjcf.RootElement, float]:
    root = mjcf.RootElement(model="armlab_direct_drive")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = sim.timestep_s
    root.option.integrator = sim.integrator
    root.option.gravity = [0, 0, 0]  # horizontal plane; the vertical load is borne by bearings/arm

    motor = mjcf.from_path(str(model_file("direct_drive", "direct_drive.xml")))
    arm = mjcf.from_path(str(model_file(elbow.model, f"{elbow.model}.xml")))
    root.worldbody.add("site", name="motor_mount", pos=[0, 0, 0]).attach(motor)
    root.worldbody.add("site", name="elbow_mount", pos=[0, 0, _ELBOW_HEIGHT_M]).attach(arm)
    motor_joint, elbow_joint = motor.find("joint", "motor"), arm.find("joint", "elbow")
    handle, grip = motor.find("site", "handle"), arm.find("site", "grip")
    if None in (motor_joint, elbow_joint, handle, grip):
        raise ModelError(
            "direct_drive needs joint 'motor' and site 'handle'; elbow_1dof joint 'elbow', site 'grip'"
        )
    length = float(np.linalg.norm(handle.parent.pos))
    grip_r = float(np.linalg.norm(grip.pos))
    if abs(grip_r - length) > 1e-9:
        raise ModelError(f"the grip ({grip_r} m from the elbow) must sit at the link length L = {length} m")

    if elbow.impedance != "muscle":
        for act in arm.find_all("actuator"):
            act.remove()
        for sensor in list(arm.sensor.all_children()):
            if sensor.tag in ("actuatorpos", "actuatorvel"):
                sensor.remove()
        elbow_joint.stiffness = elbow.arm_stiffness_Nm_per_rad
        elbow_joint.springref = 0.0
        if elbow.impedance == "five_element":
            elbow_joint.damping = elbow.arm_damping_Nms_per_rad
        else:  # the fractional element replaces the damper; driven by the simulation
            root.actuator.add(
                "motor", name="fractional_element", joint=elbow_joint, gear=[1.0], ctrllimited=False
            )

    tendon = root.tendon.add(
        "fixed",
        name="grasp",
        stiffness=elbow.grasp_stiffness_N_per_m * length**2,
        damping=elbow.grasp_damping_Ns_per_m * length**2,
        springlength=[0.0, 0.0],
    )
    tendon.add("joint", joint=elbow_joint, coef=1.0)
    tendon.add("joint", joint=motor_joint, coef=-1.0)
    root.sensor.add("tendonpos", name="grasp_psi", tendon=tendon)
    root.sensor.add("tendonvel", name="grasp_psi_dot", tendon=tendon)
    root.sensor.add("framepos", name="p_handle", objtype="site", objname=handle)
    root.sensor.add("framepos", name="p_grip", objtype="site", objname=grip)
    return root, length


def build_direct_drive_scene(elbow: ElbowConfig, sim: SimConfig) -> DirectDriveScene:
    """Compose, compile and index the direct-drive + elbow scene."""
    root, length = _compose(elbow, sim)
    model, xml, _ = compile_mjcf(root, "direct-drive scene", contacts=False)

    def jid(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    def aid(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)

    mj, ej = jid("direct_drive/motor"), jid(f"{elbow.model}/elbow")
    motor_act = aid("direct_drive/motor")
    muscles = [aid(f"{elbow.model}/{m}") for m in ELBOW_MUSCLES] if elbow.impedance == "muscle" else []
    if min([mj, ej, motor_act, *muscles]) < 0:
        raise ModelError(
            "direct-drive scene lacks joints motor/elbow, the motor actuator or the elbow muscles"
        )
    sensors = sensor_slices(model)
    # inertia about the motor axis of everything on the motor side, from the compiled model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    md, ed = int(model.jnt_dofadr[mj]), int(model.jnt_dofadr[ej])
    grasp = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, "grasp")
    return DirectDriveScene(
        model=model,
        xml=xml,
        impedance=elbow.impedance,
        motor_qpos=int(model.jnt_qposadr[mj]),
        motor_dof=md,
        elbow_qpos=int(model.jnt_qposadr[ej]),
        elbow_dof=ed,
        motor_act=motor_act,
        torque_constant=float(model.actuator_gear[motor_act, 0]),
        muscle_act=np.asarray(muscles, dtype=int),
        element_act=aid("fractional_element"),
        grasp_tendon=grasp,
        grasp_k=float(model.tendon_stiffness[grasp]),
        grasp_d=float(model.tendon_damping[grasp]),
        link_length=length,
        link_inertia=float(full[md, md]),
        coulomb=float(model.dof_frictionloss[md]),
        viscous=float(model.dof_damping[md]),
        elbow_inertia=float(full[ed, ed] - model.dof_armature[ed]),
        sensors=sensors,
    )

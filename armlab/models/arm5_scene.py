"""Compose the stiffness lab of seed paper 001: the seated 5-DoF arm, the LWR and the 6-D cuff.

The arm (``models/arm_5dof/arm_5dof.xml``, base F/T under the seat) stands at the world origin,
the LWR-class robot (``models/lwr/lwr.xml``) on its own base in front of the subject, the wrist
JR3 and cuff (``models/arm_5dof/cuff_6d.xml``) on its flange, and a ``weld`` equality joins the
cuff centre to the arm's wrist site: forces and moments, so the robot can turn the forearm about
its own axis (pronation). Gravity acts on everything; the LWR's drives compensate their own links
(``actuatorgravcomp``), as the real robot's controller does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.arm_5dof import ARM5_JOINTS, ARM5_MUSCLES
from armlab.models.scene import (
    CONNECT_SOLIMP,
    SensorReadout,
    compile_mjcf,
    mjcf,
    model_file,
    named_id,
    sensor_slices,
)

__all__ = [
    "ARM5_LAB_TIMESTEP_S",
    "ROBOT_KP",
    "ROBOT_KV",
    "ROBOT_BASE_POS_M",
    "Arm5Scene",
    "build_arm5_scene",
]

# s: 0.5 ms, one physics step per sample of the 2 kHz F/T channels (paper Sec. 3; the arm file's
# own timestep, models/arm_5dof/arm_5dof.xml)
ARM5_LAB_TIMESTEP_S = 0.0005
# m, world position of the LWR base: on a table 0.30 m lateral and 0.95 m anterior of the base
# F/T sensor, 0.45 m above it (assumption: the wrist at the default posture, (0.31, 0.45, 0.90) m,
# then lies ~0.7 m from the robot's shoulder, inside its 0.79 m reach with the elbow bent, and
# every paper perturbation (+-0.08 rad per joint) stays reachable; checked by the IK in the tests)
ROBOT_BASE_POS_M = (0.30, 0.95, 0.45)
# The LWR's servos in this lab: position mode (paper 001 Sec. 3: the robot moves the wrist along the
# planned path). kp N·m/rad: 4x models/lwr/lwr.xml's values, which are the FRI joint-impedance
# mode's ceiling ([ASM] there "for position mode"); a position-controlled LWR-III holds its joints
# far stiffer (motor-side position loop through the harmonic drive, assumption). kv N·m·s/rad: 6x
# the file's (overdamped; the commands carry velocity feed-forward, armlab.sim.arm5_trials, so the
# damping does not lag the path). With lwr.xml's own gains the robot-plus-arm rings at ~7 Hz and is
# still moving in the post-interval [200, 400] ms, biasing K_q by 15-35 % (measured); with these
# the ideal-sensor error is < 0.3 % (tests/test_arm5_stiffness_trials.py).
ROBOT_KP = (20000.0, 20000.0, 12000.0, 12000.0, 12000.0, 4000.0, 4000.0)
ROBOT_KV = (480.0, 1500.0, 300.0, 540.0, 300.0, 120.0, 120.0)
# The rigid-cuff weld: time constant 2 timesteps (MuJoCo's stable minimum), impedance close to 1
# (as armlab.models.scene.CONNECT_SOLIMP for the conditioning lab's connect)
WELD_SOLIMP = CONNECT_SOLIMP


@dataclass(frozen=True, kw_only=True, eq=False)
class Arm5Scene(SensorReadout):
    """The compiled stiffness lab and its addresses.

    Attributes:
        model: the compiled MjModel; ``xml``, ``assets`` its composed MJCF.
        arm_qpos, arm_dof: (5,) qpos / dof addresses of the arm joints (``ARM5_JOINTS`` order).
        robot_qpos, robot_dof: (7,) qpos / dof addresses of lwr_j1..7; robot_act: (7,) its servos.
        muscle_act: (12,) actuator ids of the muscles (``ARM5_MUSCLES``); muscle_actadr: (12,)
            their places in ``data.act``.
        sensors: sensor name (namespace stripped) -> slice into ``sensordata``.
        contact_site: the cuff centre (robot side of the weld), whose position
            :func:`armlab.sim.robot_ik.solve_ik` places; flange_site: the site whose orientation it
            prescribes (the cuff centre too: its frame is the wrist's at the weld).
        wrist_site: the arm's wrist site; ft_site: the wrist JR3's site; forearm_marker: the forearm
            marker cluster's site.
        tool_mass: kg, everything between the wrist JR3 and the weld (sensor half + cuff);
        tool_com: (3,) m its centre of mass in the cuff-centre (= wrist) frame.
        ft_pos, ft_rot: (3,) m, (3, 3) the JR3 site's pose in the cuff-centre frame.
        marker_to_wrist: (rotation (3, 3), offset (3,) m) of the wrist frame in the forearm marker
            cluster's frame (both on the forearm: constant; the true value the kinematic
            calibration of Eqs. (7)-(9) estimates).
    """

    model: mujoco.MjModel
    xml: str
    assets: dict
    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    robot_qpos: np.ndarray
    robot_dof: np.ndarray
    robot_act: np.ndarray
    muscle_act: np.ndarray
    muscle_actadr: np.ndarray
    sensors: dict[str, slice]
    contact_site: int
    flange_site: int
    wrist_site: int
    ft_site: int
    forearm_marker: int
    tool_mass: float
    tool_com: np.ndarray
    ft_pos: np.ndarray
    ft_rot: np.ndarray
    marker_to_wrist: tuple[np.ndarray, np.ndarray]


def _compose(robot_base_pos: Sequence[float]) -> mjcf.RootElement:
    root = mjcf.RootElement(model="arm5_lab")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = ARM5_LAB_TIMESTEP_S
    root.option.gravity = [0.0, 0.0, -9.81]  # m/s², standard gravity, as the arm file
    # the servos' velocity gains integrated implicitly (ROBOT_KV at a 0.5 ms step)
    root.option.integrator = "implicitfast"
    arm = mjcf.from_path(str(model_file("arm_5dof", "arm_5dof.xml")))
    for key in arm.find_all("key"):  # the arm's keyframe has the standalone model's nq
        key.remove()
    root.worldbody.add("site", name="arm_mount", pos=[0.0, 0.0, 0.0]).attach(arm)
    robot = mjcf.from_path(str(model_file("lwr", "lwr.xml")))
    root.worldbody.add("site", name="robot_mount", pos=list(robot_base_pos)).attach(robot)
    for i, (kp, kv) in enumerate(zip(ROBOT_KP, ROBOT_KV, strict=True), start=1):
        servo = robot.find("actuator", f"lwr_a{i}")
        if servo is None:
            raise ModelError(f"robot model 'lwr' has no servo lwr_a{i}")
        servo.kp, servo.kv = kp, kv
    flange = robot.find("site", "flange")
    if flange is None:
        raise ModelError("robot model 'lwr' has no site 'flange' to mount the cuff on")
    cuff = mjcf.from_path(str(model_file("arm_5dof", "cuff_6d.xml")))
    flange.attach(cuff)
    tc = 2.0 * ARM5_LAB_TIMESTEP_S
    root.equality.add(
        "weld",
        name="cuff_wrist",
        site1=cuff.find("site", "cuff_centre"),
        site2=arm.find("site", "wrist"),
        solref=[tc, 1.0],
        solimp=list(WELD_SOLIMP),
    )
    return root


def build_arm5_scene(robot_base_pos: Sequence[float] = ROBOT_BASE_POS_M) -> Arm5Scene:
    """Compose, compile and index the stiffness lab.

    Args:
        robot_base_pos: (3,) m, world position of the LWR base (default :data:`ROBOT_BASE_POS_M`).

    Raises:
        ModelError: the composition does not compile or lacks an expected element.
    """
    pos = np.asarray(robot_base_pos, dtype=float)
    if pos.shape != (3,) or not np.all(np.isfinite(pos)):
        raise ModelError(f"robot_base_pos must be three finite numbers (m), got {robot_base_pos!r}")
    model, xml, assets = compile_mjcf(_compose(pos), "arm5 stiffness lab", contacts=False)
    jnt, act, site = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR, mujoco.mjtObj.mjOBJ_SITE
    arm_j = [named_id(model, jnt, f"arm_5dof/{n}") for n in ARM5_JOINTS]
    robot_j = [named_id(model, jnt, f"lwr/lwr_j{i}") for i in range(1, 8)]
    muscles = np.array([named_id(model, act, f"arm_5dof/{n}") for n in ARM5_MUSCLES])
    robot_act = np.array([named_id(model, act, f"lwr/lwr_a{i}") for i in range(1, 8)])
    cuff_site = named_id(model, site, "lwr/cuff6d/cuff_centre")
    ft_site = named_id(model, site, "lwr/cuff6d/wrist_ft_site")
    # the tool between the sensor and the weld, in the cuff-centre frame (rigid: read at qpos0)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    r_c, p_c = data.site_xmat[cuff_site].reshape(3, 3), data.site_xpos[cuff_site]
    tool = [int(model.site_bodyid[ft_site]), int(model.site_bodyid[cuff_site])]
    mass = float(model.body_mass[tool].sum())
    wrist, marker = named_id(model, site, "arm_5dof/wrist"), named_id(model, site, "arm_5dof/forearm_marker")
    r_m = data.site_xmat[marker].reshape(3, 3)
    com = (model.body_mass[tool, None] * data.xipos[tool]).sum(axis=0) / mass
    return Arm5Scene(
        model=model,
        xml=xml,
        assets=assets,
        arm_qpos=model.jnt_qposadr[arm_j].copy(),
        arm_dof=model.jnt_dofadr[arm_j].copy(),
        robot_qpos=model.jnt_qposadr[robot_j].copy(),
        robot_dof=model.jnt_dofadr[robot_j].copy(),
        robot_act=robot_act,
        muscle_act=muscles,
        muscle_actadr=model.actuator_actadr[muscles].copy(),
        sensors=sensor_slices(model),
        contact_site=cuff_site,
        flange_site=cuff_site,
        wrist_site=wrist,
        ft_site=ft_site,
        forearm_marker=marker,
        tool_mass=mass,
        tool_com=r_c.T @ (com - p_c),
        ft_pos=r_c.T @ (data.site_xpos[ft_site] - p_c),
        ft_rot=r_c.T @ data.site_xmat[ft_site].reshape(3, 3),
        marker_to_wrist=(
            r_m.T @ data.site_xmat[wrist].reshape(3, 3),
            r_m.T @ (data.site_xpos[wrist] - data.site_xpos[marker]),
        ),
    )

"""The level-B scene of paper 002 (``cartesian_online``): the LWR pushing a hand through a rigid cuff.

Composed with ``dm_control.mjcf`` from the project's MJCF files: the LWR-class robot
(``models/lwr``) on its base, the F/T sensor and cuff on its flange (``models/common/cuff.xml``,
slide joints removed: the thesis's subject holds a handle), and the hand (``models/cartesian_hand``)
on world-aligned slides whose origin is the thesis's shoulder frame (Tables 3.1, 3.3), so the
hand's ``qpos`` are the thesis's ``(x, y)`` in metres. A ``connect`` equality joins the cuff's
contact site to the hand (as in :mod:`armlab.models.scene`).

The robot's base stands beside the workspace on the -y side, facing +y: the circle of Exps. 2, 4
and 5 (centre (0.95, 0.1) m, R = 0.1 m) and the Table 3.3 waypoints (x 0.80-1.10 m, y 0-0.2 m) lie
0.5-0.72 m from the base axis at the hand's height, inside the LWR's reach (1.18 m,
models/lwr/README.md), with every joint away from its limits (checked by the IK of every stop).
(On the +x side the base would have to turn by 180 deg, beyond joint 1's 170 deg.)
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.schema import SimConfig
from armlab.errors import ModelError
from armlab.models.scene import CONNECT_SOLIMP, compile_mjcf, model_file, named_id, sensor_slices

from dm_control import mjcf  # isort: skip  (armlab.models.scene sets MUJOCO_GL first)

__all__ = [
    "HAND_HEIGHT_M",
    "ROBOT_BASE_M",
    "HandScene",
    "build_hand_scene",
]

#: m, world height of the hand's horizontal plane (assumption: a seated subject's hand at the
#: robot base's level + 0.2 m keeps the LWR's elbow up and its wrist clear of its limits)
HAND_HEIGHT_M = 0.2
#: m, world position of the robot base: 0.6 m from the circle's centre (0.95, 0.1) m along -y
#: (assumption, see the module docstring)
ROBOT_BASE_M = (0.95, -0.5, 0.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class HandScene:
    """The compiled level-B scene and the addresses the simulation reads.

    Attributes:
        model: the compiled MjModel; xml: its composed MJCF.
        robot_qpos, robot_dof: (7,) addresses of the robot joints lwr_j1..7.
        robot_act: (7,) ids of the position servos lwr_a1..7.
        hand_qpos, hand_dof: (3,) addresses of the hand slides x, y, z.
        field_act: (2,) ids of the field motors (x, y).
        contact_site, flange_site, hand_site: site ids.
        sensors: sensor name -> slice into ``sensordata`` (``ft_force``: the flange's force on the
            cuff and hand, N, in the F/T site frame).
        cuff_dof: empty (rigid cuff); kept so the robot kinematics can read this scene.
        ft_load_mass_kg: kg, the mass beyond the F/T sensor's site that moves with the hand (the
            sensor's tool-side half, the cuff's mount and the hand): its inertial force is in the
            F/T reading.
    """

    model: mujoco.MjModel
    xml: str
    robot_qpos: np.ndarray
    robot_dof: np.ndarray
    robot_act: np.ndarray
    hand_qpos: np.ndarray
    hand_dof: np.ndarray
    field_act: np.ndarray
    contact_site: int
    flange_site: int
    hand_site: int
    sensors: dict[str, slice]
    cuff_dof: np.ndarray
    ft_load_mass_kg: float


def build_hand_scene(sim: SimConfig, hand_mass_kg: float | None = None) -> HandScene:
    """Compose, compile and index the level-B scene (module docstring).

    Args:
        sim: physics settings (``timestep_s``, ``integrator``).
        hand_mass_kg: kg, the hand's mass in place of models/cartesian_hand's 0.966 kg (its
            rotational inertia scaled alike); None keeps the file's.

    Raises:
        ModelError: a model file or an expected element is missing, or ``hand_mass_kg`` is not a
            positive number.
    """
    root = mjcf.RootElement(model="cartesian_hand_scene")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = sim.timestep_s
    root.option.integrator = sim.integrator
    robot = mjcf.from_path(str(model_file("lwr", "lwr.xml")))
    root.worldbody.add("site", name="robot_mount", pos=list(ROBOT_BASE_M)).attach(robot)
    flange = robot.find("site", "flange")
    cuff = mjcf.from_path(str(model_file("common", "cuff.xml")))
    for joint in cuff.find_all("joint"):
        joint.remove()  # rigid: the thesis's subject holds the robot's handle
    flange.attach(cuff)
    hand = mjcf.from_path(str(model_file("cartesian_hand", "hand.xml")))
    if hand_mass_kg is not None:
        if not (np.isfinite(hand_mass_kg) and hand_mass_kg > 0):
            raise ModelError(f"hand_mass_kg must be a positive number of kg, got {hand_mass_kg!r}")
        inertial = hand.find("body", "hand").inertial
        inertial.diaginertia = np.asarray(inertial.diaginertia) * (hand_mass_kg / inertial.mass)
        inertial.mass = hand_mass_kg
    root.worldbody.add("site", name="thesis_origin", pos=[0.0, 0.0, HAND_HEIGHT_M]).attach(hand)
    tc = 2.0 * sim.timestep_s  # the stiffest time constant MuJoCo allows, as the lab's cuff
    root.equality.add(
        "connect",
        name="cuff_hand",
        site1=cuff.find("site", "contact"),
        site2=hand.find("site", "hand"),
        solref=[tc, 1.0],
        solimp=list(CONNECT_SOLIMP),
    )
    model, xml, _ = compile_mjcf(root, "level-B hand scene", contacts=False)

    def ids(kind: mujoco.mjtObj, names: list[str]) -> np.ndarray:
        return np.array([named_id(model, kind, n) for n in names])

    joints = ids(mujoco.mjtObj.mjOBJ_JOINT, [f"lwr/lwr_j{i}" for i in range(1, 8)])
    hand_j = ids(mujoco.mjtObj.mjOBJ_JOINT, [f"hand/hand_{a}" for a in "xyz"])
    sensors = sensor_slices(model)
    if "ft_force" not in sensors:
        raise ModelError("the level-B scene lacks the cuff's F/T force sensor 'ft_force'")
    return HandScene(
        model=model,
        xml=xml,
        robot_qpos=model.jnt_qposadr[joints].copy(),
        robot_dof=model.jnt_dofadr[joints].copy(),
        robot_act=ids(mujoco.mjtObj.mjOBJ_ACTUATOR, [f"lwr/lwr_a{i}" for i in range(1, 8)]),
        hand_qpos=model.jnt_qposadr[hand_j].copy(),
        hand_dof=model.jnt_dofadr[hand_j].copy(),
        field_act=ids(mujoco.mjtObj.mjOBJ_ACTUATOR, ["hand/field_x", "hand/field_y"]),
        contact_site=named_id(model, mujoco.mjtObj.mjOBJ_SITE, "lwr/cuff/contact"),
        flange_site=named_id(model, mujoco.mjtObj.mjOBJ_SITE, "lwr/flange"),
        hand_site=named_id(model, mujoco.mjtObj.mjOBJ_SITE, "hand/hand"),
        sensors=sensors,
        cuff_dof=np.zeros(0, dtype=int),
        ft_load_mass_kg=float(
            model.body_subtreemass[named_id(model, mujoco.mjtObj.mjOBJ_BODY, "lwr/cuff/ft_sensor")]
            + model.body_mass[model.site_bodyid[named_id(model, mujoco.mjtObj.mjOBJ_SITE, "hand/hand")]]
        ),
    )

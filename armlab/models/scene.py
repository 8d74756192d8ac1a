"""Compose the lab scene from the MJCF model files with ``dm_control.mjcf``.

The scene is: the planar arm (shoulder fixed in the world, as by the paper's seat and shoulder
belts), the LWR-class robot on its own base, the F/T sensor and cuff on the robot's flange, and a
``connect`` equality joining the cuff's contact site to the arm's hand site (forces only).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from armlab.config.schema import ArmConfig, CuffConfig, RobotConfig, SimConfig
from armlab.errors import ModelError

os.environ.setdefault("MUJOCO_GL", "egl")  # dm_control imports a renderer; none is needed here
from dm_control import mjcf  # noqa: E402

__all__ = [
    "compile_mjcf",
    "named_id",
    "sensor_slices",
    "MODELS_DIR",
    "MUSCLES",
    "Scene",
    "build_scene",
    "model_file",
]

MODELS_DIR = Path(__file__).resolve().parents[2] / "models"
MUSCLES = (
    "shoulder_flexor",
    "shoulder_extensor",
    "elbow_flexor",
    "elbow_extensor",
    "biarticular_flexor",
    "biarticular_extensor",
)
ROBOT_POINTS = ("lwr_base",) + tuple(f"lwr_link{i}" for i in range(1, 8))
# The rigid-cuff equality: time constant 2 timesteps (MuJoCo's stable minimum) and impedance
# close to 1, i.e. as stiff as the solver allows.
CONNECT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)


def model_file(*parts: str) -> Path:
    """Path of a file under ``models/``; raises ModelError naming what exists if missing."""
    path = MODELS_DIR.joinpath(*parts)
    if not path.is_file():
        folder = path.parent
        have = sorted(p.name for p in folder.glob("*.xml")) if folder.is_dir() else []
        raise ModelError(f"model file {path} not found; available in {folder}: {have}")
    return path


class SensorReadout:
    """Named reads of MuJoCo sensor data, for a scene holding ``sensors`` (name -> slice into
    ``sensordata``, :func:`sensor_slices`)."""

    sensors: dict[str, slice]

    def _span(self, name: str) -> slice:
        try:
            return self.sensors[name]
        except KeyError:
            raise ModelError(f"scene has no sensor {name!r}; available: {sorted(self.sensors)}") from None

    def sensor(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """Slice one named sensor out of ``(..., nsensordata)`` sensor data."""
        return sensordata[..., self._span(name)]

    def sensors_of(self, sensordata: np.ndarray, names: Sequence[str]) -> np.ndarray:
        """The named sensors side by side, ``(..., total dim)``: a view of ``sensordata`` when they
        lie one after the other in it (no copy of a large record), else a new array."""
        spans = [self._span(n) for n in names]
        if all(a.stop == b.start for a, b in zip(spans, spans[1:], strict=False)):
            return sensordata[..., spans[0].start : spans[-1].stop]
        return np.concatenate([sensordata[..., sp] for sp in spans], axis=-1)


@dataclass(frozen=True, kw_only=True, eq=False)
class Scene(SensorReadout):
    """A compiled scene and the addresses armlab needs in it.

    Attributes:
        model: the compiled MjModel.
        xml: the composed MJCF (saved with each run), ``assets`` its mesh/include assets.
        arm_qpos, arm_dof: (2,) qpos / dof addresses of shoulder and elbow.
        robot_qpos, robot_dof: (7,) qpos / dof addresses of the robot joints.
        cuff_dof: dof addresses of the cuff slide joints (empty for a rigid cuff).
        muscle_act: (6,) actuator ids of the muscles (order of :data:`MUSCLES`), also their
            ``act`` indices; robot_act: (7,) actuator ids of the robot servos.
        sensors: sensor name (without namespace) -> slice into ``sensordata``.
        l1, l2: m, arm segment lengths (shoulder-elbow, elbow-hand) read from the model.
        shoulder_pos: (3,) m, world position of the shoulder joint.
        contact_site, hand_site, flange_site: site ids.
    """

    model: mujoco.MjModel
    xml: str
    assets: dict
    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    robot_qpos: np.ndarray
    robot_dof: np.ndarray
    cuff_dof: np.ndarray
    muscle_act: np.ndarray
    robot_act: np.ndarray
    sensors: dict[str, slice]
    l1: float
    l2: float
    shoulder_pos: np.ndarray
    contact_site: int
    hand_site: int
    flange_site: int


def _compose(arm: ArmConfig, cuff: CuffConfig, robot: RobotConfig, sim: SimConfig) -> mjcf.RootElement:
    root = mjcf.RootElement(model="armlab_scene")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = sim.timestep_s
    root.option.integrator = sim.integrator

    arm_model = mjcf.from_path(str(model_file(arm.model, f"{arm.model}_{arm.muscle}.xml")))
    root.worldbody.add("site", name="shoulder_mount", pos=list(arm.shoulder_pos_m)).attach(arm_model)

    robot_model = mjcf.from_path(str(model_file(robot.model, f"{robot.model}.xml")))
    root.worldbody.add("site", name="robot_mount", pos=list(robot.base_pos_m)).attach(robot_model)

    cuff_model = mjcf.from_path(str(model_file("common", "cuff.xml")))
    flange = robot_model.find("site", "flange")
    if flange is None:
        raise ModelError(f"robot model {robot.model!r} has no site 'flange' to mount the cuff on")
    flange.attach(cuff_model)
    hand = arm_model.find("site", "hand")
    if hand is None:
        raise ModelError(f"arm model {arm.model!r} has no site 'hand' for the cuff")
    shell_model = mjcf.from_path(str(model_file("common", "cuff_shell.xml")))
    shell_model.find("body", "shell").inertial.mass = cuff.mass_kg
    hand.attach(shell_model)
    for joint in cuff_model.find_all("joint"):
        if cuff.rigid:
            joint.remove()
        else:
            joint.stiffness = cuff.stiffness_N_per_m
            joint.damping = cuff.damping_Ns_per_m

    contact = cuff_model.find("site", "contact")
    tc = 2.0 * sim.timestep_s
    root.equality.add(
        "connect", name="cuff_hand", site1=contact, site2=hand, solref=[tc, 1.0], solimp=list(CONNECT_SOLIMP)
    )
    # positions for drawing and for the truth channels
    for site in ("shoulder_site", "elbow_site", "hand"):
        root.sensor.add("framepos", name=f"p_{site}", objtype="site", objname=arm_model.find("site", site))
    for body in ROBOT_POINTS:
        root.sensor.add("framepos", name=f"p_{body}", objtype="body", objname=robot_model.find("body", body))
    root.sensor.add("framepos", name="p_flange", objtype="site", objname=flange)
    root.sensor.add("framepos", name="p_contact", objtype="site", objname=contact)
    return root


def compile_mjcf(
    root: mjcf.RootElement, what: str, contacts: bool = True
) -> tuple[mujoco.MjModel, str, dict]:
    """Compile a composed scene: ``(model, xml, assets)``; a :class:`ModelError` naming ``what``.

    Args:
        root: the composed scene.
        what: its name in an error.
        contacts: False for a scene whose geoms never collide (``contype = conaffinity = 0``
            throughout, every coupling a joint or tendon): MuJoCo's collision detection is switched
            off (``root`` gets ``<flag contact="disable"/>``), which changes no trajectory and saves
            ~9-14 % of a physics step in the direct-drive and capstan labs and ~7 % in the
            conditioning lab's scene (measured, thread CPU time of one rollout); a geom that could
            collide is then a ModelError rather than a silently ignored contact.
    """
    if not contacts:
        root.option.flag.contact = "disable"
    xml = root.to_xml_string()
    assets = root.get_assets()
    try:
        model = mujoco.MjModel.from_xml_string(xml, assets)
    except ValueError as exc:
        raise ModelError(f"composed {what} does not compile: {exc}") from None
    colliding = np.flatnonzero(model.geom_contype | model.geom_conaffinity)
    if not contacts and model.npair:  # explicit <contact><pair>s would be dropped silently too
        raise ModelError(
            f"composed {what}: {model.npair} <contact><pair> elements, but the scene runs without contacts"
        )
    if not contacts and colliding.size:
        names = [model.geom(int(g)).name or f"geom {g}" for g in colliding]
        raise ModelError(
            f"composed {what}: geoms {names} could collide, but the scene runs without contacts; "
            'give them contype="0" conaffinity="0" (the scene couples its bodies by joints and tendons)'
        )
    return model, xml, assets


def sensor_slices(model: mujoco.MjModel) -> dict[str, slice]:
    """Sensor name (attachment namespace stripped) -> slice into ``sensordata``."""
    out = {}
    for i in range(model.nsensor):
        adr, dim = int(model.sensor_adr[i]), int(model.sensor_dim[i])
        out[model.sensor(i).name.split("/")[-1]] = slice(adr, adr + dim)
    return out


def named_id(model: mujoco.MjModel, objtype: mujoco.mjtObj, name: str) -> int:
    """Id of a named model element; a clear :class:`ModelError` instead of MuJoCo's silent -1."""
    i = mujoco.mj_name2id(model, objtype, name)
    if i < 0:
        kind = str(objtype).split(".")[-1].removeprefix("mjOBJ_").lower()
        raise ModelError(f"the model has no {kind} named {name!r}")
    return int(i)


def build_scene(arm: ArmConfig, cuff: CuffConfig, robot: RobotConfig, sim: SimConfig) -> Scene:
    """Compose, compile and index the lab scene."""
    model, xml, assets = compile_mjcf(_compose(arm, cuff, robot, sim), "scene", contacts=False)

    def jnt(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    arm_j = [jnt(f"{arm.model}/{n}") for n in ("shoulder", "elbow")]
    robot_j = [jnt(f"{robot.model}/lwr_j{i}") for i in range(1, 8)]
    cuff_j = [j for j in (jnt(f"{robot.model}/cuff/slide_{a}") for a in "xyz") if j >= 0]
    if min(arm_j + robot_j) < 0:
        raise ModelError("scene lacks the expected arm (shoulder, elbow) or robot (lwr_j1..7) joints")
    muscle_act = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{arm.model}/{n}") for n in MUSCLES]
    robot_act = [
        mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{robot.model}/lwr_a{i}") for i in range(1, 8)
    ]
    if min(muscle_act + robot_act) < 0:
        raise ModelError(f"scene lacks muscle actuators {list(MUSCLES)} or robot servos lwr_a1..7")
    sensors = sensor_slices(model)

    def site(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)

    hand_site = site(f"{arm.model}/hand")
    forearm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{arm.model}/forearm")
    return Scene(
        model=model,
        xml=xml,
        assets=assets,
        arm_qpos=model.jnt_qposadr[arm_j].copy(),
        arm_dof=model.jnt_dofadr[arm_j].copy(),
        robot_qpos=model.jnt_qposadr[robot_j].copy(),
        robot_dof=model.jnt_dofadr[robot_j].copy(),
        cuff_dof=model.jnt_dofadr[cuff_j].copy() if cuff_j else np.zeros(0, int),
        muscle_act=np.asarray(muscle_act),
        robot_act=np.asarray(robot_act),
        sensors=sensors,
        l1=float(np.linalg.norm(model.body_pos[forearm])),
        l2=float(np.linalg.norm(model.site_pos[hand_site])),
        shoulder_pos=np.asarray(arm.shoulder_pos_m, float),
        contact_site=site(f"{robot.model}/cuff/contact"),
        hand_site=hand_site,
        flange_site=site(f"{robot.model}/flange"),
    )

"""Compose the virtual-force-sensor lab (seeds/003) with ``dm_control.mjcf``.

Three loads on the capstan robot of ``models/capstan_planar``:

- ``none``: the bare robot for the identification of its dynamics (Appendix); the handle body is
  kept massless so the F/T sensor stays addressable.
- ``fixture``: the mass-spring system (Sec. II-C-1, Table I): the payload replaces the handle
  beyond the F/T sensor and the array's springs (:mod:`armlab.models.spring_array`) run from
  anchors on the bench to the grip.
- ``arm``: the planar muscle arm of ``models/arm_planar`` holding the 135 g handle (Sec. II-C-2):
  its shoulder sits ``reach`` behind the handle along +x, so that the hand is anterior to the
  shoulder and the subject faces the robot; the hand is joined to the grip by a ``connect``
  equality (forces only, as the paper's hand resting on the hemispherical handle).

The robot's motors become joint PD servos: ``ctrl`` is the link-side reference
``theta_ref + (kd / kp) theta_ref_dot`` so that the actuator force is
``kp (theta_ref - theta) + kd (theta_ref_dot - theta_dot)`` (N·m, clamped at the motors' 25 N·m),
which ``mujoco.rollout`` can run open loop. The cabling drag (``capstan.drag``) is a spatial
spring from an anchor on the base to the ``ee`` site on link 2, i.e. on the robot's side of the
F/T sensor: Method 2 does not see it, Method 1 does (Sec. IV-A).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Literal

import mujoco
import numpy as np

from armlab.config.capstan import CapstanConfig
from armlab.config.schema import ArmConfig
from armlab.errors import ConfigError, ModelError
from armlab.models.capstan_robot import CAPSTAN_RATIO, CapstanDynamics
from armlab.models.planar_arm import inverse as arm_inverse
from armlab.models.scene import MUSCLES, compile_mjcf, model_file, named_id, sensor_slices
from armlab.models.spring_array import SpringArray

os.environ.setdefault("MUJOCO_GL", "egl")
from dm_control import mjcf  # noqa: E402

__all__ = [
    "LOADS",
    "MUSCLE_DESIGN_Q_RAD",
    "CapstanScene",
    "build_capstan_scene",
]

LOADS = ("none", "fixture", "arm")
Load = Literal["none", "fixture", "arm"]
# point-like payload: spin inertia small enough that Eq. (5)'s M = m I holds (assumption)
_PAYLOAD_SPIN_KGM2 = 1e-6
# m, anchor-to-neutral-point length of the two drag springs (long, so that each acts along its axis)
_DRAG_LEVER_M = 1.0
# rad, the posture at which models/arm_planar/arm_planar_linear.xml sets every muscle's tension
# (conditioning paper IV-B; the file's header)
MUSCLE_DESIGN_Q_RAD = (0.08, 1.00)


@dataclass(frozen=True, kw_only=True, eq=False)
class CapstanScene:
    """A compiled capstan-lab scene and the addresses armlab needs in it.

    Attributes:
        model: the compiled MjModel; ``xml`` the composed MJCF; ``assets`` its assets.
        load: ``none``, ``fixture`` or ``arm``.
        robot_qpos, robot_dof: (4,) addresses of rotor1, rotor2, shoulder, elbow.
        arm_qpos, arm_dof: (2,) addresses of the arm's shoulder and elbow (empty without arm).
        muscle_act: (6,) muscle actuator ids (empty without arm); motor_act: (2,) PD servos.
        sensors: sensor name (namespace stripped) -> slice into ``sensordata``.
        dynamics: the rigid model of the robot (lengths of the MJCF, Table VI alphas).
        payload_kg: the mass beyond the F/T sensor (payload, handle or 0).
        shoulder_pos: (2,) m, the arm's shoulder in the robot frame (NaN without arm).
    """

    model: mujoco.MjModel
    xml: str
    assets: dict
    load: str
    robot_qpos: np.ndarray
    robot_dof: np.ndarray
    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    muscle_act: np.ndarray
    motor_act: np.ndarray
    sensors: dict[str, slice]
    dynamics: CapstanDynamics
    payload_kg: float
    shoulder_pos: np.ndarray
    arm_l1: float = 0.0
    arm_l2: float = 0.0
    hand_site: int = -1  # the arm's hand site (scenes with an arm)

    def sensor(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """Slice one named sensor out of ``(..., nsensordata)`` sensor data."""
        try:
            return sensordata[..., self.sensors[name]]
        except KeyError:
            raise ModelError(f"scene has no sensor {name!r}; available: {sorted(self.sensors)}") from None

    def arm_posture(self, handle_xy: np.ndarray) -> np.ndarray:
        """Arm joint angles (2,) rad with the hand on the grip at ``handle_xy`` (robot frame, m)."""
        if self.load != "arm":
            raise ModelError("arm_posture needs a scene built with load='arm'")
        # the arm's frame is the robot's turned by +90 deg (R): p_arm = R^T (X - S)
        d = np.asarray(handle_xy, float) - self.shoulder_pos
        return arm_inverse(np.array([d[1], -d[0]]), self.arm_l1, self.arm_l2, "flexed")

    def initial_state(
        self, theta: np.ndarray, arm_q: np.ndarray | None = None, act: float = 0.0
    ) -> np.ndarray:
        """Full-physics state at rest with the robot at ``theta`` (cables unstretched).

        Args:
            theta: (2,) rad, the absolute link angles (Theta of the paper).
            arm_q: (2,) rad, the arm's shoulder and elbow (scenes with an arm).
            act: muscle activation to start from (scenes with an arm).
        """
        data = mujoco.MjData(self.model)
        t1, t2 = np.asarray(theta, float)
        data.qpos[self.robot_qpos] = [CAPSTAN_RATIO * t1, CAPSTAN_RATIO * t2, t1, t2 - t1]
        if self.load == "arm":
            if arm_q is None:
                raise ModelError("a scene with an arm needs arm_q for its initial state")
            data.qpos[self.arm_qpos] = arm_q
            data.act[self.model.actuator_actadr[self.muscle_act]] = act
        mujoco.mj_forward(self.model, data)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, data, state, spec)
        return state


def _robot(cfg: CapstanConfig, load: str, payload_kg: float) -> mjcf.RootElement:
    robot = mjcf.from_path(str(model_file(cfg.model, f"{cfg.model}.xml")))
    for i in (1, 2):
        cable = robot.find("tendon", f"cable{i}")
        cable.stiffness = cfg.cable_stiffness_Nm_per_rad
        cable.damping = cfg.cable_damping_Nms_per_rad
        if cfg.cable == "rigid":
            robot.find("equality", f"rigid{i}").active = True
        # Coulomb friction on the rotor, rotor side: link-side torque / N
        robot.find("joint", f"rotor{i}").frictionloss = cfg.coulomb_Nm / CAPSTAN_RATIO
        # PD servo in place of the torque motor (module docstring); forcerange stays +-25 N·m
        motor = robot.find("actuator", f"motor{i}")
        motor.ctrlrange = None
        motor.gainprm = [cfg.kp_Nm_per_rad]
        motor.biastype = "affine"
        motor.biasprm = [0.0, -cfg.kp_Nm_per_rad, -cfg.kd_Nms_per_rad]
    handle = robot.find("body", "handle")
    if cfg.id_ee_mass_kg > 0:
        _take_ee_mass(robot, cfg.id_ee_mass_kg)
    if load == "none":
        handle.inertial.mass = cfg.id_ee_mass_kg
        handle.inertial.pos = [0.0, 0.0, 0.0]
        handle.inertial.diaginertia = [_PAYLOAD_SPIN_KGM2] * 3 if cfg.id_ee_mass_kg > 0 else [0.0] * 3
    elif load == "fixture":
        handle.inertial.mass = payload_kg
        handle.inertial.pos = [0.0, 0.0, 0.0]
        handle.inertial.diaginertia = [_PAYLOAD_SPIN_KGM2] * 3
    else:
        handle.inertial.mass = cfg.handle_mass_kg
    return robot


def _take_ee_mass(robot: mjcf.RootElement, mass_kg: float) -> None:
    """Take a point mass at the end effector out of link 2 (``capstan.id_ee_mass_kg``).

    Link 2 keeps its mass properties about the elbow minus a point mass ``mass_kg`` at the ``ee``
    site: the bare robot of the impedance trials is lighter than Table VI by exactly that point
    mass; the identification's robot (load ``none``: the mass put back on the handle, at the end
    effector) is Table VI again.
    """
    link2 = robot.find("body", "link2")
    ee = np.asarray(robot.find("site", "ee").pos[:2], float)
    inertial = link2.inertial
    m, c = float(inertial.mass), np.asarray(inertial.pos[:2], float)
    izz = float(inertial.diaginertia[2]) + m * c @ c  # about the elbow axis
    m_new = m - mass_kg
    if m_new <= 0:
        raise ConfigError(f"capstan.id_ee_mass_kg={mass_kg} kg must be below link 2's mass {m} kg")
    c_new = (m * c - mass_kg * ee) / m_new
    izz_new = izz - mass_kg * ee @ ee - m_new * c_new @ c_new
    if izz_new <= 0:
        raise ConfigError(f"capstan.id_ee_mass_kg={mass_kg} kg leaves link 2 no inertia of its own")
    inertial.mass = m_new
    inertial.pos = [c_new[0], c_new[1], float(inertial.pos[2])]
    d = list(inertial.diaginertia)
    inertial.diaginertia = [izz_new, d[1], izz_new]  # the MJCF's axes: link 2 along -y, z vertical


def _height(robot: mjcf.RootElement, body: str) -> float:
    """m, height of a body's frame above the shoulder axis's base plane (the MJCF's offsets)."""
    z = 0.0
    element = robot.find("body", body)
    while element is not None and getattr(element, "tag", None) == "body":
        z += float(element.pos[2]) if element.pos is not None else 0.0
        element = element.parent
    return z


def _add_springs(root: mjcf.RootElement, robot: mjcf.RootElement, array: SpringArray) -> None:
    grip = robot.find("site", "grip")
    height = _height(robot, "handle")  # the grip site sits at the handle's origin
    for i, spring in enumerate(array.springs):
        anchor = root.worldbody.add(
            "site", name=f"anchor_{i}", pos=[spring.anchor[0], spring.anchor[1], height], size=[0.005]
        )
        tendon = root.tendon.add(
            "spatial", name=f"spring_{i}", stiffness=spring.stiffness, springlength=[spring.rest_length] * 2
        )
        tendon.width = 0.002
        tendon.add("site", site=anchor)
        tendon.add("site", site=grip)


def _add_drag(root: mjcf.RootElement, robot: mjcf.RootElement, cfg: CapstanConfig) -> None:
    """The cabling drag force field ``-diag(k_x, k_y) (X - X_n)`` as two long axial springs.

    One spatial tendon per axis from a bench anchor ``_DRAG_LEVER_M`` behind (x) or beside (y) the
    neutral point ``X_n`` to the ``ee`` site, at rest length ``_DRAG_LEVER_M``: it pulls along its
    axis with its stiffness, and its tension across the axis adds only ``T / _DRAG_LEVER_M``
    (below 2 N/m within the fixtures' 5 cm region).
    """
    z = _height(robot, "link2")  # the ee site's plane
    xn, yn = cfg.drag_neutral_m
    for axis, k, anchor in (
        ("x", cfg.drag_stiffness_N_per_m, (xn - _DRAG_LEVER_M, yn)),
        ("y", cfg.drag_stiffness_y_N_per_m, (xn, yn - _DRAG_LEVER_M)),
    ):
        if k <= 0:
            continue
        site = root.worldbody.add("site", name=f"drag_anchor_{axis}", pos=[*anchor, z], size=[0.005])
        tendon = root.tendon.add(
            "spatial",
            name=f"drag_{axis}",
            stiffness=k,
            springlength=[_DRAG_LEVER_M] * 2,
            frictionloss=k * cfg.drag_hysteresis_m,
        )
        tendon.width = 0.002
        tendon.add("site", site=site)
        tendon.add("site", site=robot.find("site", "ee"))


def _recentre_muscles(arm_model: mjcf.RootElement, handle_from_shoulder: np.ndarray) -> None:
    """Move the linear muscles' operating point from their design posture to the test posture.

    Each muscle's tension per unit activation is ``g0 + g1 L`` on its fixed tendon of length
    ``L = coef . q``; ``g0`` is shifted so that the tension at the test posture equals the design
    tension at ``MUSCLE_DESIGN_Q_RAD`` (400 N, models/arm_planar/arm_planar_linear.xml). Stiffness
    and damping per activation (``g1``, ``g2``) are unchanged, and uniform activation again gives
    zero net torque: the relaxed hand rests where it is.
    """
    l1 = float(np.linalg.norm(arm_model.find("body", "forearm").pos))
    l2 = float(np.linalg.norm(arm_model.find("site", "hand").pos))
    q_to = arm_inverse(handle_from_shoulder, l1, l2, "flexed")
    q_from = dict(zip(("shoulder", "elbow"), MUSCLE_DESIGN_Q_RAD, strict=True))
    q_new = dict(zip(("shoulder", "elbow"), q_to, strict=True))
    for act in arm_model.find_all("actuator"):
        dl = sum(j.coef * (q_new[j.joint.name] - q_from[j.joint.name]) for j in act.tendon.joint)
        gain = list(act.gainprm)
        act.gainprm = [gain[0] - gain[1] * dl, *gain[1:]]


def _add_arm(
    root: mjcf.RootElement,
    robot: mjcf.RootElement,
    arm: ArmConfig,
    shoulder,
    reach_m: float,
    timestep_s: float,
):
    if arm.muscle != "linear":
        raise ConfigError(
            f"arm.muscle={arm.muscle!r}: the capstan lab holds the arm at the paper's posture (hand 50 cm "
            "anterior), where only the 'linear' muscles can be re-centred; set arm.muscle=linear"
        )
    arm_model = mjcf.from_path(str(model_file(arm.model, f"{arm.model}_{arm.muscle}.xml")))
    # the hand in the arm's frame: R^T (handle - shoulder) = R^T (-reach, 0) = (0, reach)
    _recentre_muscles(arm_model, np.array([0.0, reach_m]))
    # the arm's frame (x lateral right, y anterior) turned by +90 deg: anterior is the robot's -x
    mount = root.worldbody.add(
        "site",
        name="shoulder_mount",
        pos=[shoulder[0], shoulder[1], _height(robot, "handle")],
        euler=[0, 0, np.pi / 2],
    )
    mount.attach(arm_model)
    hand = arm_model.find("site", "hand")
    if hand is None:
        raise ModelError(f"arm model {arm.model!r} has no site 'hand' to hold the handle")
    root.equality.add(
        "connect",
        name="hand_grip",
        site1=robot.find("site", "grip"),
        site2=hand,
        solref=[2.0 * timestep_s, 1.0],
        solimp=[0.99, 0.999, 0.001, 0.5, 2.0],
    )
    for site in ("shoulder_site", "elbow_site", "hand"):
        root.sensor.add("framepos", name=f"p_{site}", objtype="site", objname=arm_model.find("site", site))


def build_capstan_scene(
    cfg: CapstanConfig,
    load: Load,
    *,
    timestep_s: float,
    integrator: str = "implicitfast",
    array: SpringArray | None = None,
    payload_kg: float | None = None,
    arm: ArmConfig | None = None,
    handle_xy: tuple[float, float] | None = None,
    reach_m: float = 0.5,
) -> CapstanScene:
    """Compose, compile and index one capstan-lab scene.

    Args:
        cfg: the robot as built (cables, drag, PD gains, handle).
        load: ``none`` | ``fixture`` | ``arm`` (module docstring).
        timestep_s: physics step, s.
        integrator: MuJoCo integrator name.
        array, payload_kg: the spring array and payload mass (kg) of a ``fixture`` load.
        arm, handle_xy, reach_m: the arm's config, the handle position (robot frame, m) and the
            shoulder-to-hand distance (m) of an ``arm`` load.

    Raises:
        ConfigError: an unknown load or a missing/invalid argument for it.
        ModelError: the composed scene does not compile.
    """
    if load not in LOADS:
        raise ConfigError(f"load={load!r} is not valid; choose one of {list(LOADS)}")
    root = mjcf.RootElement(model=f"capstan_lab_{load}")
    root.compiler.angle = "radian"
    root.compiler.autolimits = True
    root.option.timestep = timestep_s
    root.option.integrator = integrator
    mass = 0.0
    if load == "fixture":
        if not isinstance(array, SpringArray):
            raise ConfigError("a fixture load needs array=SpringArray (armlab.models.spring_array)")
        if not isinstance(payload_kg, (int, float)) or not np.isfinite(payload_kg) or payload_kg <= 0:
            raise ConfigError(f"a fixture load needs a payload of finite mass > 0 kg, got {payload_kg!r}")
        mass = float(payload_kg)
    elif load == "arm":
        mass = cfg.handle_mass_kg
    robot = _robot(cfg, load, mass)
    root.worldbody.attach(robot)
    shoulder = np.full(2, np.nan)
    if load == "fixture":
        _add_springs(root, robot, array)
    elif load == "arm":
        if arm is None or handle_xy is None:
            raise ConfigError("an arm load needs arm=ArmConfig and handle_xy=(x, y) m")
        shoulder = np.asarray(handle_xy, float) + np.array([reach_m, 0.0])
        _add_arm(root, robot, arm, shoulder, reach_m, timestep_s)
    if cfg.drag:
        _add_drag(root, robot, cfg)
    model, xml, assets = compile_mjcf(root, "capstan scene", contacts=False)
    return _index(model, xml, assets, load, mass, shoulder, cfg, arm)


def _index(
    model, xml, assets, load, mass, shoulder, cfg: CapstanConfig, arm: ArmConfig | None
) -> CapstanScene:
    ns = f"{cfg.model}/"
    jnt = mujoco.mjtObj.mjOBJ_JOINT
    robot_j = [named_id(model, jnt, ns + n) for n in ("rotor1", "rotor2", "shoulder", "elbow")]
    motors = [named_id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{ns}motor{i}") for i in (1, 2)]
    arm_j: list[int] = []
    muscles: list[int] = []
    l1 = l2 = 0.0
    hand = -1
    if load == "arm":
        arm_j = [named_id(model, jnt, f"{arm.model}/{n}") for n in ("shoulder", "elbow")]
        muscles = [named_id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{arm.model}/{n}") for n in MUSCLES]
        forearm = named_id(model, mujoco.mjtObj.mjOBJ_BODY, f"{arm.model}/forearm")
        hand = named_id(model, mujoco.mjtObj.mjOBJ_SITE, f"{arm.model}/hand")
        l1 = float(np.linalg.norm(model.body_pos[forearm]))
        l2 = float(np.linalg.norm(model.site_pos[hand]))
    sensors = sensor_slices(model)
    link2 = named_id(model, mujoco.mjtObj.mjOBJ_BODY, ns + "link2")
    ee = named_id(model, mujoco.mjtObj.mjOBJ_SITE, ns + "ee")
    return CapstanScene(
        model=model,
        xml=xml,
        assets=assets,
        load=load,
        robot_qpos=model.jnt_qposadr[robot_j].copy(),
        robot_dof=model.jnt_dofadr[robot_j].copy(),
        arm_qpos=model.jnt_qposadr[arm_j].copy() if arm_j else np.zeros(0, int),
        arm_dof=model.jnt_dofadr[arm_j].copy() if arm_j else np.zeros(0, int),
        muscle_act=np.asarray(muscles, int),
        motor_act=np.asarray(motors, int),
        sensors=sensors,
        dynamics=CapstanDynamics(
            l1=float(np.linalg.norm(model.body_pos[link2][:2])),
            l2=float(np.linalg.norm(model.site_pos[ee][:2])),
        ),
        payload_kg=mass,
        shoulder_pos=shoulder,
        arm_l1=l1,
        arm_l2=l2,
        hand_site=hand,
    )

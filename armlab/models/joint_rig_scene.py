"""Build the 1-DoF joint rig: the MJCF of ``models/joint_rig`` with a subject and model-level effects.

The rig is a chain on one axis, every angle absolute about it (rad, one positive direction)::

    motor (servo, encoder) -[transmission]- pedal (torque sensor side) -[cuff]- limb (subject)

In the file the subject's joint is the kinematic root (hinge ``limb``, the absolute limb angle),
the pedal hangs on it by the hinge ``cuff`` (θp − θl) and the motor on the pedal by the hinge
``transmission`` (θm − θp); the fixed tendon ``motor_angle`` (the sum of the hinges) is the motor
angle the servo drives and the encoder reads. A rigid interface (the effect off) deletes its
hinge, which welds the two bodies; the tendon is rebuilt over the hinges that remain.

What the builder sets (everything else is the file's, see ``models/joint_rig/README.md``):

- the subject (:class:`JointSubject`): limb inertia, the joint's ``stiffness`` K and ``damping``
  B about the operating angle, the pedal inertia, and the tonic torque (a constant bias of the
  ``activation`` actuator, acting as −tonic on the limb);
- ``cuff_compliance``: the ``cuff`` hinge's stiffness and damping (else the hinge is deleted);
- ``transmission_compliance``: the ``transmission`` hinge's stiffness (else deleted);
- ``joint_friction``: the ``limb`` hinge's ``frictionloss`` (Coulomb); the Stribeck excess is
  driven through the ``stribeck`` actuator by the simulation;
- ``payload_mass``: a point mass ``mass_kg`` at ``lever_m`` on the pedal (adds m·r²);
- ``cocontraction_variation``: the ``activation`` actuator's affine gain [−T_var, −K, −B], so that
  ctrl = a(t) − 1 adds −Δa·(T_var + K·θ + B·θ̇) to the limb.

The reflex changes nothing in the model (its torque is the ``reflex`` actuator's ctrl).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.effects import EffectsConfig
from armlab.errors import ConfigError, ModelError
from armlab.models.scene import model_file, named_id, sensor_slices

__all__ = [
    "PAYLOAD_OWN_INERTIA_KGM2",
    "Joint1DofScene",
    "JointSubject",
    "build_joint_rig_scene",
]

# kg·m², each principal inertia of the payload body about its own centre: a near point mass, so
# that the payload adds m·r² (+ this) to the pedal; MuJoCo needs a positive inertia.
PAYLOAD_OWN_INERTIA_KGM2 = 1e-9


def _finite(name: str, value: float, *, positive: bool = False) -> None:
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    ok = ok and math.isfinite(value) and (value > 0 if positive else value >= 0)
    if not ok:
        need = "finite and > 0" if positive else "finite and >= 0"
        raise ConfigError(f"JointSubject.{name} must be {need}, got {value!r}")


@dataclass(frozen=True)
class JointSubject:
    """The subject's joint about its operating angle, and the pedal it is strapped to.

    Typical human ankle values (Kearney & Hunter 1990, Crit. Rev. Biomed. Eng. 18:55):
    I 0.01–0.03 kg·m², B 0.3–1.5 N·m·s/rad, K 50–200 N·m/rad.

    Attributes:
        inertia_kgm2: I, kg·m², the limb (foot) about the joint axis (> 0).
        damping_Nms_per_rad: B, N·m·s/rad, intrinsic viscosity (>= 0).
        stiffness_Nm_per_rad: K, N·m/rad, intrinsic elasticity about the operating angle (>= 0).
        tonic_torque_Nm: N·m, the voluntary tonic torque; it acts as −tonic on the limb, so the
            recorded torque has the offset −tonic (any sign).
        pedal_inertia_kgm2: Ip, kg·m², pedal and sensor flange beyond the torque sensor (> 0).
    """

    inertia_kgm2: float
    damping_Nms_per_rad: float
    stiffness_Nm_per_rad: float
    tonic_torque_Nm: float = 0.0
    pedal_inertia_kgm2: float = 0.005

    def __post_init__(self) -> None:
        _finite("inertia_kgm2", self.inertia_kgm2, positive=True)
        _finite("damping_Nms_per_rad", self.damping_Nms_per_rad)
        _finite("stiffness_Nm_per_rad", self.stiffness_Nm_per_rad)
        _finite("pedal_inertia_kgm2", self.pedal_inertia_kgm2, positive=True)
        t = self.tonic_torque_Nm
        if (
            isinstance(t, bool)
            or not isinstance(t, (int, float, np.floating, np.integer))
            or not math.isfinite(t)
        ):
            raise ConfigError(f"JointSubject.tonic_torque_Nm must be a finite number (N·m), got {t!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class Joint1DofScene:
    """A compiled 1-DoF joint rig and its addresses.

    Attributes:
        model: the compiled MjModel; ``xml`` its MJCF (saved with a run).
        subject: the subject it was built for.
        limb_dof, cuff_dof, transmission_dof: dof (= qpos) addresses of the hinges; -1 where the
            interface is rigid (hinge deleted).
        servo_act, activation_act, reflex_act, stribeck_act: actuator ids.
        sensors: sensor name -> slice into ``sensordata`` (``cuff_deflection`` and
            ``transmission_deflection`` only where the hinge exists).
        motor_inertia: kg·m², the motor body alone (rotor and shaft).
        pedal_inertia: kg·m², pedal plus payload (m·r² + own inertia) when ``payload_mass`` is on.
        servo_kp: N·m/rad, servo_kv: N·m·s/rad, the position servo's gains.
        transmission_stiffness: N·m/rad, 0 where rigid; cuff_stiffness N·m/rad and
            cuff_damping N·m·s/rad, 0 where rigid.
        coulomb: N·m, the limb hinge's frictionloss.
    """

    model: mujoco.MjModel
    xml: str
    subject: JointSubject
    limb_dof: int
    cuff_dof: int
    transmission_dof: int
    servo_act: int
    activation_act: int
    reflex_act: int
    stribeck_act: int
    sensors: dict[str, slice]
    motor_inertia: float
    pedal_inertia: float
    servo_kp: float
    servo_kv: float
    transmission_stiffness: float
    cuff_stiffness: float
    cuff_damping: float
    coulomb: float

    @property
    def rigid_cuff(self) -> bool:
        return self.cuff_dof < 0

    @property
    def rigid_transmission(self) -> bool:
        return self.transmission_dof < 0

    def sensor(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """Slice one named scalar sensor out of ``(..., nsensordata)`` sensor data -> ``(...)``."""
        try:
            return sensordata[..., self.sensors[name]][..., 0]
        except KeyError:
            raise ModelError(f"scene has no sensor {name!r}; available: {sorted(self.sensors)}") from None

    def linear_rates(self, activation_ctrl: float = 0.0) -> tuple[float, float]:
        """Fastest rates of the linearised rig: ``(omega_max rad/s, damping_rate_max 1/s)``.

        ``omega_max`` is the largest natural frequency sqrt(eig(M⁻¹K)) and ``damping_rate_max``
        the largest eig(M⁻¹D), with K and D the stiffness and damping of every spring, damper
        and actuator (servo included) by central differences at rest (exact: all are linear).
        The explicit integrator is accurate when both times the timestep are small.
        """
        m = self.model
        data = mujoco.MjData(m)
        data.ctrl[self.activation_act] = activation_ctrl
        nv, eps = m.nv, 1e-6

        def force(dq: np.ndarray, dv: np.ndarray) -> np.ndarray:
            data.qpos[:] = dq
            data.qvel[:] = dv
            mujoco.mj_forward(m, data)
            return data.qfrc_passive + data.qfrc_actuator

        stiff, damp = np.zeros((nv, nv)), np.zeros((nv, nv))
        zero = np.zeros(nv)
        for j in range(nv):
            e = np.zeros(nv)
            e[j] = eps
            stiff[:, j] = -(force(e, zero) - force(-e, zero)) / (2 * eps)
            damp[:, j] = -(force(zero, e) - force(zero, -e)) / (2 * eps)
        mass = np.zeros((nv, nv))
        mujoco.mj_forward(m, data)
        mujoco.mj_fullM(m, data, mass)
        w2 = np.linalg.eigvals(np.linalg.solve(mass, stiff)).real
        rates = np.linalg.eigvals(np.linalg.solve(mass, damp)).real
        return float(np.sqrt(max(w2.max(), 0.0))), float(max(rates.max(), 0.0))


def _linear(coef: float) -> list[float]:
    """A joint's stiffness/damping polynomial [linear, higher orders] with only the linear term."""
    return [float(coef), 0.0, 0.0]


def _rebuild_tendon(spec: mujoco.MjSpec, hinges: list[str]) -> None:
    spec.delete(spec.tendon("motor_angle"))
    tendon = spec.add_tendon(name="motor_angle")
    for name in hinges:
        tendon.wrap_joint(name, 1.0)


def build_joint_rig_scene(
    subject: JointSubject, effects: EffectsConfig, *, timestep_s: float = 1e-4
) -> Joint1DofScene:
    """Build and compile the rig for ``subject`` with the model-level effects of ``effects``.

    Sensor-level effects and the reflex do not change the model and are ignored here (the
    simulation applies them); effects of other protocols are rejected by the simulation.

    Args:
        subject: the joint and pedal.
        effects: cuff_compliance, transmission_compliance, joint_friction, payload_mass and
            cocontraction_variation are read.
        timestep_s: s, physics step (> 0); dry friction's constraint time constant is 2 steps.

    Returns:
        The compiled scene.

    Raises:
        ConfigError: a bad timestep. ModelError: the file lacks an element or does not compile.
    """
    if not (isinstance(timestep_s, (int, float)) and math.isfinite(timestep_s) and timestep_s > 0):
        raise ConfigError(f"timestep_s must be a finite number > 0 s, got {timestep_s!r}")
    spec = mujoco.MjSpec.from_file(str(model_file("joint_rig", "joint_rig.xml")))
    spec.option.timestep = timestep_s
    limb, cuff, trans = spec.joint("limb"), spec.joint("cuff"), spec.joint("transmission")
    body_limb, body_pedal = spec.body("limb"), spec.body("pedal")
    activation = spec.actuator("activation")
    if None in (limb, cuff, trans, body_limb, body_pedal, activation):
        raise ModelError(
            "models/joint_rig/joint_rig.xml needs hinges limb/cuff/transmission, bodies limb/pedal "
            "and the actuator 'activation'"
        )
    s = subject
    body_limb.inertia = [s.inertia_kgm2] * 3
    body_pedal.inertia = [s.pedal_inertia_kgm2] * 3
    limb.stiffness = _linear(s.stiffness_Nm_per_rad)
    limb.damping = _linear(s.damping_Nms_per_rad)
    fric = effects.joint_friction
    limb.frictionloss = fric.coulomb_Nm if fric is not None else 0.0
    limb.solref_friction = [2.0 * timestep_s, 1.0]  # MuJoCo's stiffest safe time constant
    if fric is None or fric.coulomb_Nm == 0:
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT  # nothing to solve

    kept = ["limb"]
    cc, tc = effects.cuff_compliance, effects.transmission_compliance
    if cc is not None:
        cuff.stiffness = _linear(cc.stiffness_Nm_per_rad)
        cuff.damping = _linear(cc.damping_Nms_per_rad)
        kept.append("cuff")
    else:
        spec.delete(spec.sensor("cuff_deflection"))
        spec.delete(cuff)
    if tc is not None:
        trans.stiffness = _linear(tc.stiffness_Nm_per_rad)
        kept.append("transmission")
    else:
        spec.delete(spec.sensor("transmission_deflection"))
        spec.delete(trans)
    _rebuild_tendon(spec, kept)

    pm = effects.payload_mass
    if pm is not None and pm.mass_kg > 0:
        payload = body_pedal.add_body(name="payload", pos=[pm.lever_m, 0.0, 0.0])
        payload.explicitinertial = True
        payload.ipos = [0.0, 0.0, 0.0]  # centre of mass at the lever (unset, the compiler guesses)
        payload.mass = pm.mass_kg
        payload.inertia = [PAYLOAD_OWN_INERTIA_KGM2] * 3
    cv = effects.cocontraction_variation
    t_var = cv.tonic_torque_Nm if cv is not None else 0.0
    gain = np.zeros(10)
    gain[:3] = [-t_var, -s.stiffness_Nm_per_rad, -s.damping_Nms_per_rad]
    bias = np.zeros(10)
    bias[0] = -s.tonic_torque_Nm
    activation.gainprm = gain
    activation.biasprm = bias

    try:
        model = spec.compile()
    except ValueError as exc:
        raise ModelError(f"1-DoF joint rig does not compile: {exc}") from None
    J, A = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR

    def dof(name: str) -> int:
        return int(model.jnt_dofadr[named_id(model, J, name)]) if name in kept else -1

    servo = named_id(model, A, "servo")
    motor_body = named_id(model, mujoco.mjtObj.mjOBJ_BODY, "motor")
    pedal_inertia = s.pedal_inertia_kgm2
    if pm is not None and pm.mass_kg > 0:
        pedal_inertia += pm.mass_kg * pm.lever_m**2 + PAYLOAD_OWN_INERTIA_KGM2
    return Joint1DofScene(
        model=model,
        xml=spec.to_xml(),
        subject=subject,
        limb_dof=dof("limb"),
        cuff_dof=dof("cuff"),
        transmission_dof=dof("transmission"),
        servo_act=servo,
        activation_act=named_id(model, A, "activation"),
        reflex_act=named_id(model, A, "reflex"),
        stribeck_act=named_id(model, A, "stribeck"),
        sensors=sensor_slices(model),
        motor_inertia=float(model.body_inertia[motor_body, 2]),
        pedal_inertia=float(pedal_inertia),
        servo_kp=float(model.actuator_gainprm[servo, 0]),
        servo_kv=float(-model.actuator_biasprm[servo, 2]),
        transmission_stiffness=tc.stiffness_Nm_per_rad if tc is not None else 0.0,
        cuff_stiffness=cc.stiffness_Nm_per_rad if cc is not None else 0.0,
        cuff_damping=cc.damping_Nms_per_rad if cc is not None else 0.0,
        coulomb=float(model.dof_frictionloss[dof("limb")]),
    )

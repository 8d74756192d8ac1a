"""The catalogue of unmodelled effects: typed, parameterised changes to a simulation.

Each effect is a ``@dataclass(kw_only=True)`` whose fields are its parameters (unit in the name,
typical magnitude and its source in the comment) and whose class attributes say where it acts
(``LEVEL``: model, controller or sensor), what physics it adds (``PHYSICS``), where its typical
magnitude comes from (``SOURCE``) and which other effects it cannot be told apart from with a
protocol's trials (``CONFUSABLE``: name -> the extra trial that separates them). Which effects
act in a protocol's lab, and which its simulation applies, each protocol declares itself
(:class:`armlab.protocols.Protocol` ``catalogue`` and ``effects``).

Hydra: every effect is an option of the ``effects`` group stored in the ConfigStore by
:func:`register_effect_configs` (its dataclass defaults, no YAML copy); select any number with
``effects=[reflex,joint_friction]`` and tune with ``effects.reflex.delay_s=0.05``.
An effect left at ``None`` in :class:`EffectsConfig` is off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import ClassVar, get_args

from hydra.core.config_store import ConfigStore

from armlab.config.choices import EffectLevel
from armlab.errors import ConfigError

__all__ = [
    "EFFECTS",
    "LEVELS",
    "AccelMisalignment",
    "AccelNoise",
    "BaseSensorDrift",
    "CableDrag",
    "ChannelDelay",
    "CocontractionVariation",
    "CuffCompliance",
    "Effect",
    "EffectsConfig",
    "EncoderQuantisation",
    "ForceSensorBandwidth",
    "ForceSensorDrift",
    "ForceSensorNoise",
    "JointFriction",
    "MarkerSoftTissue",
    "NonQuadraticField",
    "PayloadMass",
    "PlaneTilt",
    "PositionSensorNoise",
    "Reflex",
    "RobotModelError",
    "TorsoTranslation",
    "TransmissionCompliance",
    "VoluntaryTorque",
    "enabled_effects",
    "register_effect_configs",
]

LEVELS = get_args(EffectLevel)


@dataclass(kw_only=True)
class Effect:
    """Base of every catalogue entry: positive, finite parameters unless a field says otherwise."""

    NAME: ClassVar[str] = ""
    LEVEL: ClassVar[EffectLevel] = "model"  # a ClassVar, not an OmegaConf field: the Literal stays
    PHYSICS: ClassVar[str] = ""
    SOURCE: ClassVar[str] = ""
    CONFUSABLE: ClassVar[dict[str, str]] = {}
    SIGNED: ClassVar[tuple[str, ...]] = ()  # fields that may be negative

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                continue
            ok = math.isfinite(v) and (f.name in self.SIGNED or v >= 0)
            if not ok:
                sign = "finite" if f.name in self.SIGNED else "finite and >= 0"
                raise ConfigError(f"effects.{self.NAME}.{f.name} must be {sign}, got {v!r}")

    def params(self) -> dict[str, float]:
        """The parameters as a name -> value dict (units in the names)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(kw_only=True)
class Reflex(Effect):
    NAME: ClassVar[str] = "reflex"
    PHYSICS: ClassVar[str] = (
        "stretch-reflex pathway: joint torque opposing stretch, gain * 2nd-order low-pass of the "
        "half-wave rectified stretch velocity delayed by the loop latency"
    )
    SOURCE: ClassVar[str] = (
        "Kearney, Stein & Parameswaran 1997 (IEEE TBME 44:493) parallel-cascade ankle model: "
        "40-50 ms latency, reflex dynamics a low-pass near 3-4 Hz; conditioning paper Sec. II"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {}
    SIGNED: ClassVar[tuple[str, ...]] = ("direction",)
    delay_s: float = 0.045  # s, loop latency, Kearney 1997 (40-50 ms at the ankle)
    gain_Nms_per_rad: float = 10.0  # N·m·s/rad, velocity gain; ankle fits give 5-30 (Kearney 1997)
    cutoff_hz: float = 3.0  # Hz, natural frequency of the activation low-pass (Kearney 1997)
    damping_ratio: float = 0.7  # 1, of that low-pass
    direction: float = 1.0  # +1: stretch is positive joint velocity, -1: negative


@dataclass(kw_only=True)
class CuffCompliance(Effect):
    NAME: ClassVar[str] = "cuff_compliance"
    PHYSICS: ClassVar[str] = (
        "a spring-damper between the handle/pedal and the limb (soft tissue, strap, grasp): the "
        "limb no longer follows the handle rigidly; the handle's own inertia stays on the sensor side"
    )
    SOURCE: ClassVar[str] = (
        "ankle: foot-pedal interface 300-1500 N·m/rad (Kearney & Hunter 1990 Crit. Rev. Biomed. Eng.); "
        "arm: hand-handle 1-5 kN/m (conditioning paper Sec. III, cuff)"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "transmission_compliance": "an accelerometer on the handle/pedal beside the motor encoder"
    }
    stiffness_Nm_per_rad: float = 800.0  # N·m/rad, rotational (1-DoF joint protocols)
    damping_Nms_per_rad: float = 0.5  # N·m·s/rad
    stiffness_N_per_m: float = 3000.0  # N/m, translational (endpoint protocols)
    damping_Ns_per_m: float = 20.0  # N·s/m


@dataclass(kw_only=True)
class TransmissionCompliance(Effect):
    NAME: ClassVar[str] = "transmission_compliance"
    PHYSICS: ClassVar[str] = (
        "a compliant capstan/cable/gear between the motor (where the encoder is) and the handle: "
        "the handle lags the encoder by torque / stiffness"
    )
    SOURCE: ClassVar[str] = "virtual-force-sensor paper (capstan drive), ~2000 N·m/rad at the joint"
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "cuff_compliance": "an accelerometer on the handle/pedal beside the motor encoder"
    }
    stiffness_Nm_per_rad: float = 2000.0  # N·m/rad, joint-side, virtual-force-sensor paper


@dataclass(kw_only=True)
class CableDrag(Effect):
    NAME: ClassVar[str] = "cable_drag"
    PHYSICS: ClassVar[str] = "elastic drag of the cable harness: a spring from the base to the end effector"
    SOURCE: ClassVar[str] = "virtual-force-sensor paper Sec. V (drag of the sensor cables), ~40 N/m"
    CONFUSABLE: ClassVar[dict[str, str]] = {"arm stiffness": "empty-handle trials (no subject)"}
    stiffness_N_per_m: float = 40.0  # N/m
    rest_length_m: float = 0.25  # m


@dataclass(kw_only=True)
class JointFriction(Effect):
    NAME: ClassVar[str] = "joint_friction"
    PHYSICS: ClassVar[str] = (
        "Coulomb friction with a Stribeck peak at the joint/bearing on the sensor side: "
        "(Fc + Fs·exp(-(v/vs)^2))·sign(v)"
    )
    SOURCE: ClassVar[str] = (
        "Olsson et al. 1998 (Eur. J. Control 4:176) friction models; capstan rig 0.05 N·m "
        "(virtual-force-sensor paper Table VI)"
    )
    coulomb_Nm: float = 0.3  # N·m
    stribeck_Nm: float = 0.0  # N·m, extra static friction near zero velocity
    stribeck_velocity_rad_s: float = 0.05  # rad/s


@dataclass(kw_only=True)
class ForceSensorNoise(Effect):
    NAME: ClassVar[str] = "force_sensor_noise"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "extra white noise on the force/torque channel (sets the noise floor, not a gap)"
    SOURCE: ClassVar[str] = "JR3 50M31 datasheet; ATI Mini45: ~0.01-0.05 N·m per sample"
    std: float = 0.05  # N·m or N


@dataclass(kw_only=True)
class ForceSensorDrift(Effect):
    NAME: ClassVar[str] = "force_sensor_drift"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "offset and linear thermal drift of the force/torque channel"
    SOURCE: ClassVar[str] = "strain-gauge drift 0.1-1 % FS per minute (ATI F/T manual, temperature effects)"
    SIGNED: ClassVar[tuple[str, ...]] = ("bias", "drift_per_s")
    bias: float = 0.0  # N·m or N
    drift_per_s: float = 0.02  # N·m/s or N/s


@dataclass(kw_only=True)
class ForceSensorBandwidth(Effect):
    NAME: ClassVar[str] = "force_sensor_bandwidth"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "2nd-order Butterworth low-pass of the force/torque channel (electronics, DSP)"
    SOURCE: ClassVar[str] = "JR3 DSP filters 8-500 Hz; ankle rigs low-pass torque at 50-200 Hz"
    cutoff_hz: float = 20.0  # Hz


@dataclass(kw_only=True)
class AccelNoise(Effect):
    NAME: ClassVar[str] = "accel_noise"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "white noise and offset of the accelerometer"
    SOURCE: ClassVar[str] = "ADXL203 datasheet: 110 µg/sqrt(Hz), offset ±25 mg"
    SIGNED: ClassVar[tuple[str, ...]] = ("bias_m_s2",)
    std_m_s2: float = 0.02  # m/s²
    bias_m_s2: float = 0.1  # m/s²


@dataclass(kw_only=True)
class AccelMisalignment(Effect):
    NAME: ClassVar[str] = "accel_misalignment"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "accelerometer axes rotated in the plane relative to the handle frame"
    SOURCE: ClassVar[str] = "mounting tolerance ~1-3 deg (ADXL203 datasheet: axis alignment ±1 deg)"
    SIGNED: ClassVar[tuple[str, ...]] = ("angle_deg",)
    angle_deg: float = 2.0  # deg


@dataclass(kw_only=True)
class EncoderQuantisation(Effect):
    NAME: ClassVar[str] = "encoder_quantisation"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "position rounded to the encoder's resolution before differentiation"
    SOURCE: ClassVar[str] = "16-bit absolute encoder: 2π/65536 rad ≈ 9.6e-5 rad; capstan rig 2 µm"
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "position_sensor_noise": "none needed: the recorded angle's changes are whole steps of one grid",
        "force_sensor_noise": "a recording at rest (the grid's error is constant while the angle holds "
        "still, the torque sensor's noise is not)",
    }
    step: float = 9.6e-5  # rad (joint) or m (Cartesian)


@dataclass(kw_only=True)
class PositionSensorNoise(Effect):
    NAME: ClassVar[str] = "position_sensor_noise"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = (
        "white noise on the recorded angle (analogue potentiometer/resolver electronics, an "
        "interpolated encoder) before differentiation: the nominal's regressors carry it "
        "(errors in variables)"
    )
    SOURCE: ClassVar[str] = (
        "assumption, no measured source: the order of a 12-bit conversion of a ±π rad potentiometer "
        "(2π/4096 rad steps, step/√12 = 4.4e-4 rad rms)"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "encoder_quantisation": "none needed: the recorded angle's changes are whole steps of one grid",
        "force_sensor_noise": "a recording at rest (the angle's spread there is its sensor's noise alone)",
    }
    std_rad: float = 2e-4  # rad, rms (the SOURCE's assumption)


@dataclass(kw_only=True)
class ChannelDelay(Effect):
    NAME: ClassVar[str] = "channel_delay"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = "the force channel recorded later than the position channel (separate DAQ/buses)"
    SOURCE: ClassVar[str] = "USB/EtherCAT F/T sensors vs encoder counters: 1-20 ms skew (JR3/ATI manuals)"
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "force_sensor_bandwidth": "a step or impulse perturbation (a pure delay keeps the edge sharp)"
    }
    SIGNED: ClassVar[tuple[str, ...]] = ("delay_s",)
    delay_s: float = 0.008  # s, force channel after position channel


@dataclass(kw_only=True)
class PayloadMass(Effect):
    NAME: ClassVar[str] = "payload_mass"
    PHYSICS: ClassVar[str] = "an unmodelled handle/pedal/payload mass beyond the force sensor"
    SOURCE: ClassVar[str] = "handles 0.1-0.5 kg (virtual-force-sensor paper: 135 g handle)"
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "limb inertia": "empty-handle trials (no subject attached)",
        "arm inertia": "empty-handle trials (no subject attached)",
    }
    mass_kg: float = 0.2  # kg
    lever_m: float = 0.1  # m, distance from the joint axis (1-DoF protocols)


@dataclass(kw_only=True)
class CocontractionVariation(Effect):
    NAME: ClassVar[str] = "cocontraction_variation"
    PHYSICS: ClassVar[str] = (
        "slow fluctuation of the subject's muscle activation: stiffness, damping and tonic torque "
        "scale together with it (intrinsic stiffness grows linearly with active torque)"
    )
    SOURCE: ClassVar[str] = (
        "Hunter & Kearney 1982 (J. Biomech. 15:747): ankle stiffness linear in voluntary torque; "
        "tonic-contraction tracking error ~10-20 % of target"
    )
    depth: float = 0.2  # 1, rms of the relative activation fluctuation
    bandwidth_hz: float = 0.3  # Hz, of the fluctuation
    tonic_torque_Nm: float = 5.0  # N·m, tonic torque at the mean activation


@dataclass(kw_only=True)
class VoluntaryTorque(Effect):
    NAME: ClassVar[str] = "voluntary_torque"
    PHYSICS: ClassVar[str] = (
        "a slow torque the subject adds voluntarily or posturally (holding a tonic level, tracking a "
        "target), band-limited below ~1-2 Hz and independent of the perturbation: the position does "
        "not predict it, and it reaches the recorded torque in full"
    )
    SOURCE: ClassVar[str] = (
        "issue 18: the REKLAB trial z_df3 has most of its nominal gap at 0-2 Hz; voluntary torque "
        "control of the ankle is limited to a few Hz (Kearney & Hunter 1990, Crit. Rev. Biomed. Eng. "
        "18:55, which is why the perturbation band starts above it); its rms is this catalogue's "
        "assumption (tonic-contraction tracking error ~10-20 % of a few N·m target)"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "cocontraction_variation": "trials at a constant, monitored tonic torque (the co-contraction "
        "changes the stiffness with the torque, a voluntary torque changes only the torque)",
        "force_sensor_drift": "a trial with the subject at rest or the pedal empty (a drift stays)",
    }
    rms_Nm: float = 0.5  # N·m, rms of the slow torque (assumption, see SOURCE)
    bandwidth_hz: float = 1.0  # Hz, top of its band (issue 18: below ~1-2 Hz)


@dataclass(kw_only=True)
class OperatingPointImpedance(Effect):
    NAME: ClassVar[str] = "operating_point_impedance"
    PHYSICS: ClassVar[str] = (
        "the joint's stiffness and damping change with its operating angle: a slow, large movement "
        "carries the joint through postures where muscle lengths, moment arms and passive tissue "
        "differ, so the impedance about each posture is not the one about another"
    )
    SOURCE: ClassVar[str] = (
        "Weiss, Kearney & Hunter 1986 (J. Biomech. 19:727 and 19:737): ankle stiffness varies "
        "several-fold over the range of motion; Ludvig et al. 2011 (IEEE TBME 58:1715): its "
        "time-varying identification during movement"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "cocontraction_variation": "trials at fixed postures with a constant tonic contraction, "
        "or a movement at a constant tonic contraction (the operating angle changes, the activation "
        "does not)"
    }
    SIGNED: ClassVar[tuple[str, ...]] = ("stiffness_slope_per_rad", "damping_slope_per_rad")
    stiffness_slope_per_rad: float = 3.0  # 1/rad, relative change of K per rad of operating angle
    damping_slope_per_rad: float = 1.0  # 1/rad, relative change of B per rad of operating angle


@dataclass(kw_only=True)
class NonQuadraticField(Effect):
    NAME: ClassVar[str] = "non_quadratic_field"
    PHYSICS: ClassVar[str] = (
        "the hand's stiffness field over the workspace is not the quadratic polynomial of the "
        "position the model assumes (Eq. 2.2.4 of paper 002): a third-order term, relative to the "
        "stiffness at the workspace's centre, at the edge of the perturbed region"
    )
    SOURCE: ClassVar[str] = (
        "paper 002 (MSc thesis) §2.2 and Exp. 5: the quadratic is a fit of refs [27]/[28]; the "
        "polar model's anti-diagonal needs order >= 2-3 (measured, docs of paper 002)"
    )
    relative_amplitude: float = 0.03  # 1, cubic term at the circle's radius / K at its centre


@dataclass(kw_only=True)
class RobotModelError(Effect):
    NAME: ClassVar[str] = "robot_model_error"
    LEVEL: ClassVar[EffectLevel] = "controller"
    PHYSICS: ClassVar[str] = (
        "the robot's dynamic parameters used by the virtual force sensor differ from the real robot's"
    )
    SOURCE: ClassVar[str] = "virtual-force-sensor paper Appendix (identified vs CAD, Table VI)"
    SIGNED: ClassVar[tuple[str, ...]] = ("relative_error",)
    relative_error: float = 0.1  # 1, on every inertial parameter


@dataclass(kw_only=True)
class PlaneTilt(Effect):
    NAME: ClassVar[str] = "plane_tilt"
    PHYSICS: ClassVar[str] = "the movement plane tilted from horizontal: a component of gravity acts in it"
    SOURCE: ClassVar[str] = "table and robot base levelling tolerance ~0.5-2 deg"
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "arm stiffness": "the same perturbations at a second posture or with the plane rotated (the "
        "gravity gradient changes with posture, the muscles' stiffness does not follow it)"
    }
    SIGNED: ClassVar[tuple[str, ...]] = ("angle_deg",)
    angle_deg: float = 1.0  # deg
    azimuth_deg: float = 0.0  # deg, direction of the downhill slope in the plane


@dataclass(kw_only=True)
class TorsoTranslation(Effect):
    NAME: ClassVar[str] = "torso_translation"
    PHYSICS: ClassVar[str] = "the shoulder is not fixed: the trunk moves on a spring-damper"
    SOURCE: ClassVar[str] = (
        "trunk compliance 2-10 kN/m when strapped (Perreault et al. 2004 J. Neurophysiol.)"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "cuff_compliance": "a marker or accelerometer on the shoulder (acromion) beside the robot encoders"
    }
    stiffness_N_per_m: float = 5000.0  # N/m
    damping_Ns_per_m: float = 100.0  # N·s/m
    mass_kg: float = 10.0  # kg, trunk mass moving with the shoulder


@dataclass(kw_only=True)
class MarkerSoftTissue(Effect):
    NAME: ClassVar[str] = "marker_soft_tissue"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = (
        "the skin under a forearm marker cluster slides over the radius and ulna: the cluster turns "
        "about the forearm (pronation) axis by only (1 - slip) of the bone's pronation"
    )
    SOURCE: ClassVar[str] = (
        "soft-tissue artefact of skin-mounted clusters under axial rotation of a long bone (Cutti et "
        "al. 2005, Gait & Posture 21:341, the humerus: tens of percent); the forearm's size here is "
        "an assumption (0.01-0.3)"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "cuff_compliance": "a second marker cluster on the cuff (the cuff's stretch grows with the "
        "wrench, the skin's slip with the pronation angle)"
    }
    slip: float = 0.1  # 1, fraction of the pronation change the cluster misses (assumption, see SOURCE)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.slip < 1.0:
            raise ConfigError(f"effects.{self.NAME}.slip must lie in [0, 1), got {self.slip!r}")


@dataclass(kw_only=True)
class BaseSensorDrift(Effect):
    NAME: ClassVar[str] = "base_sensor_drift"
    LEVEL: ClassVar[EffectLevel] = "sensor"
    PHYSICS: ClassVar[str] = (
        "the base (seat) F/T sensor's readings drift at a constant rate per axis since its tare "
        "(thermal drift of the gauges); the wrist sensor is unaffected"
    )
    SOURCE: ClassVar[str] = (
        "strain-gauge drift 0.1-1 % FS per minute (ATI F/T manual, temperature effects); JR3 base "
        "unit range 2000 N / 200 N·m (armlab.sensors JR3_BASE_FORCE/_TORQUE): up to ~0.3 N/s, 0.03 N·m/s"
    )
    CONFUSABLE: ClassVar[dict[str, str]] = {
        "force_sensor_drift": "the same drift on the wrist sensor: the base sensor alone drifts here"
    }
    SIGNED: ClassVar[tuple[str, ...]] = (
        "fx_N_per_s",
        "fy_N_per_s",
        "fz_N_per_s",
        "mx_Nm_per_s",
        "my_Nm_per_s",
        "mz_Nm_per_s",
    )
    fx_N_per_s: float = 0.0  # N/s, along the base sensor's x (world) axis
    fy_N_per_s: float = 0.0  # N/s
    fz_N_per_s: float = 0.1  # N/s, ~0.3 % FS/min of a 2000 N unit (ATI manual's range)
    mx_Nm_per_s: float = 0.0  # N·m/s
    my_Nm_per_s: float = 0.0  # N·m/s
    mz_Nm_per_s: float = 0.0  # N·m/s

    def rates(self) -> tuple[float, ...]:
        """(6,) N/s, N·m/s: the drift rates in the order fx, fy, fz, mx, my, mz."""
        return tuple(getattr(self, k) for k in self.SIGNED)


EFFECTS: dict[str, type[Effect]] = {
    cls.NAME: cls
    for cls in (
        Reflex,
        CuffCompliance,
        TransmissionCompliance,
        CableDrag,
        JointFriction,
        ForceSensorNoise,
        ForceSensorDrift,
        ForceSensorBandwidth,
        AccelNoise,
        AccelMisalignment,
        EncoderQuantisation,
        PositionSensorNoise,
        ChannelDelay,
        PayloadMass,
        CocontractionVariation,
        VoluntaryTorque,
        OperatingPointImpedance,
        NonQuadraticField,
        RobotModelError,
        PlaneTilt,
        TorsoTranslation,
        MarkerSoftTissue,
        BaseSensorDrift,
    )
}


@dataclass(kw_only=True)
class EffectsConfig:
    """Which effects are on (a non-None field) and their parameters."""

    reflex: Reflex | None = None
    cuff_compliance: CuffCompliance | None = None
    transmission_compliance: TransmissionCompliance | None = None
    cable_drag: CableDrag | None = None
    joint_friction: JointFriction | None = None
    force_sensor_noise: ForceSensorNoise | None = None
    force_sensor_drift: ForceSensorDrift | None = None
    force_sensor_bandwidth: ForceSensorBandwidth | None = None
    accel_noise: AccelNoise | None = None
    accel_misalignment: AccelMisalignment | None = None
    encoder_quantisation: EncoderQuantisation | None = None
    position_sensor_noise: PositionSensorNoise | None = None
    channel_delay: ChannelDelay | None = None
    payload_mass: PayloadMass | None = None
    cocontraction_variation: CocontractionVariation | None = None
    voluntary_torque: VoluntaryTorque | None = None
    operating_point_impedance: OperatingPointImpedance | None = None
    non_quadratic_field: NonQuadraticField | None = None
    robot_model_error: RobotModelError | None = None
    plane_tilt: PlaneTilt | None = None
    torso_translation: TorsoTranslation | None = None
    marker_soft_tissue: MarkerSoftTissue | None = None
    base_sensor_drift: BaseSensorDrift | None = None


def enabled_effects(cfg: EffectsConfig) -> dict[str, Effect]:
    """The effects switched on in ``cfg``, in catalogue order."""
    return {n: getattr(cfg, n) for n in EFFECTS if getattr(cfg, n) is not None}


def register_effect_configs() -> None:
    """Store every catalogue effect as an option of Hydra's ``effects`` group (idempotent).

    ``effects=[reflex,joint_friction]`` then switches those on with their dataclass defaults
    (no YAML repeats them); ``effects.reflex.delay_s=0.05`` tunes one.
    """
    cs = ConfigStore.instance()
    for name, cls in EFFECTS.items():
        cs.store(group="effects", name=name, package="effects", node={name: cls})

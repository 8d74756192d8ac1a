"""Catalogue effects of the subject, the mechanics and the controller (``LEVEL`` model or
controller): reflex, compliances, friction, drag, payload, the subject's own variation, fields and
model errors (:mod:`armlab.config.effects`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from armlab.config.choices import EffectLevel
from armlab.config.effect_base import Effect

__all__ = [
    "CableDrag",
    "CocontractionVariation",
    "CuffCompliance",
    "JointFriction",
    "NonQuadraticField",
    "OperatingPointImpedance",
    "PayloadMass",
    "PlaneTilt",
    "Reflex",
    "RobotModelError",
    "TorsoTranslation",
    "TransmissionCompliance",
    "VoluntaryTorque",
]


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

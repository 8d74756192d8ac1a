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

The entries live in :mod:`armlab.config.effects_model` (subject, mechanics, controller) and
:mod:`armlab.config.effects_sensor` (sensors and channels), their base in
:mod:`armlab.config.effect_base`; this module is the catalogue (its order is the reports' order).
"""

from __future__ import annotations

from dataclasses import dataclass

from hydra.core.config_store import ConfigStore

from armlab.config.effect_base import LEVELS, Effect
from armlab.config.effects_model import (
    CableDrag,
    CocontractionVariation,
    CuffCompliance,
    JointFriction,
    NonQuadraticField,
    OperatingPointImpedance,
    PayloadMass,
    PlaneTilt,
    Reflex,
    RobotModelError,
    TorsoTranslation,
    TransmissionCompliance,
    VoluntaryTorque,
)
from armlab.config.effects_sensor import (
    AccelMisalignment,
    AccelNoise,
    BaseSensorDrift,
    ChannelDelay,
    EncoderQuantisation,
    ForceSensorBandwidth,
    ForceSensorDrift,
    ForceSensorNoise,
    MarkerSoftTissue,
    PositionSensorNoise,
)

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

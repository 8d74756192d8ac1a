"""Catalogue effects that act in a sensor or its channel (``LEVEL = "sensor"``): noise, drift,
bandwidth, quantisation, delay, misalignment and marker artefacts (:mod:`armlab.config.effects`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from armlab.config.choices import EffectLevel
from armlab.config.effect_base import Effect
from armlab.errors import ConfigError

__all__ = [
    "AccelMisalignment",
    "AccelNoise",
    "BaseSensorDrift",
    "ChannelDelay",
    "EncoderQuantisation",
    "ForceSensorBandwidth",
    "ForceSensorDrift",
    "ForceSensorNoise",
    "MarkerSoftTissue",
    "PositionSensorNoise",
]


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

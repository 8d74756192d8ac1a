"""Named sensor presets and the sensor suite of the conditioning-window protocol.

The lab of the conditioning paper (seed 000, section IV-A) pushes the hand with a KUKA/DLR
lightweight robot (LWR-III class) carrying a six-axis JR3 force/torque sensor; forces, torques
and robot positions are recorded by VxWorks at 1 kHz. The presets below give each of those
instruments a :class:`~armlab.sensors.channel.ChannelSpec`. Where a figure could not be checked
against a datasheet it is marked *assumption* with the reasoning behind it.

:func:`measure` applies a :class:`SensorSuite` to the clean simulated channels.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields
from typing import ClassVar

import numpy as np

from armlab.cpus import usable_cpus
from armlab.errors import ConfigError
from armlab.sensors.channel import ChannelSpec, apply_channel

__all__ = [
    "ADXL203_ACCEL",
    "CAPSTAN_ENCODER",
    "JR3_50M31_FORCE",
    "JR3_BASE_FORCE",
    "JR3_BASE_TORQUE",
    "Arm5SensorSuite",
    "VICON_MARKER_POS",
    "VICON_MARKER_QUAT",
    "DD_ENCODER",
    "JR3_FORCE",
    "JR3_TORQUE",
    "LWR_ENCODER",
    "LWR_JOINT_TORQUE",
    "SENSOR_PRESETS",
    "get_preset",
    "SensorSuite",
    "CapstanSensorSuite",
    "CHANNEL_SPEC_FIELDS",
    "measure",
]

# --- JR3 six-axis F/T sensor (85M35A / 67M25A class), sampled at 1 kHz ------------------------
# Rated range assumed 200 N (Fx, Fy) and 12 N·m (Mx, My): a common 85M35A load rating. JR3's DSP
# receivers report each axis as a signed 16-bit count with full scale at 16384 counts (JR3 DSP
# manual, recalled, not re-checked here), so one count is 200/16384 = 0.0122 N and
# 12/16384 = 7.3e-4 N·m.
# Noise, residual offset after taring and drift: assumptions, no datasheet figure found. Noise of
# a few counts is typical of strain-gauge F/T sensors at 1 kHz; the offset after taring comes from
# cuff preload and hysteresis (of order 0.1 N), the drift from gauge warm-up (~0.1 N per minute).
# Bandwidth: the JR3 DSP offers cascaded low-pass outputs (cut-offs 500, 125, 31.25 Hz, ... at its
# 8 kHz internal rate, JR3 DSP manual, recalled); 500 Hz is the Nyquist frequency of a 1 kHz log,
# so the 125 Hz output is the usable one, modelled as a 2nd-order Butterworth (assumption).
# Delay: one 1 ms VxWorks cycle between the sensor sample and the logged value (assumption).
JR3_FORCE = ChannelSpec(
    noise_std=0.05,  # N, assumption (~4 counts of 0.0122 N)
    bias_std=0.1,  # N, assumption (residual offset after taring with the cuff mounted)
    drift_per_s=0.002,  # N/s, assumption (~0.1 N per minute of thermal drift)
    quant_step=200.0 / 16384,  # N, 200 N full scale / 16384 counts (JR3 DSP, see above)
    bandwidth_hz=125.0,  # Hz, JR3 DSP filter-2 output (see above)
    filter_order=2,
    delay_s=0.001,  # s, one 1 kHz cycle (assumption)
)
JR3_TORQUE = ChannelSpec(
    noise_std=0.003,  # N·m, assumption (~4 counts of 7.3e-4 N·m)
    bias_std=0.005,  # N·m, assumption (same relative size as the force offset)
    drift_per_s=1e-4,  # N·m/s, assumption (same relative size as the force drift)
    quant_step=12.0 / 16384,  # N·m, 12 N·m full scale / 16384 counts (JR3 DSP, see above)
    bandwidth_hz=125.0,  # Hz, JR3 DSP filter-2 output (see above)
    filter_order=2,
    delay_s=0.001,  # s, one 1 kHz cycle (assumption)
)

# --- LWR-III class robot ------------------------------------------------------------------------
# Link-side joint position sensor: absolute optical sensor resolving 0.01° (DLR, "Light-Weight
# Robot III: joint position sensor", dlr.de/rm). Absolute, so no offset after taring and no drift;
# a tiny white noise well below one step stands for electronic jitter (assumption).
LWR_ENCODER = ChannelSpec(
    noise_std=2e-5,  # rad, assumption (about 1/9 of a step)
    quant_step=math.radians(0.01),  # rad, 0.01° = 1.745e-4 rad (DLR LWR-III joint position sensor)
)
# Joint torque sensors: strain gauges on radial beams in each joint (DLR LWR-III). No noise or
# resolution figure found: assumptions. Resolution: a 16-bit reading over ±176 N·m (the largest
# LWR4+ joint torque rating) gives 0.0054 N·m, rounded to 0.005 N·m. Noise 0.05 N·m, offset
# 0.3 N·m and drift 0.002 N·m/s: joint torque sensors are not tared before each trial and their
# offset depends on temperature. Delay: one 1 ms robot-interface cycle (assumption).
LWR_JOINT_TORQUE = ChannelSpec(
    noise_std=0.05,  # N·m, assumption
    bias_std=0.3,  # N·m, assumption (untared offset)
    drift_per_s=0.002,  # N·m/s, assumption (thermal drift)
    quant_step=0.005,  # N·m, assumption (16 bit over ±176 N·m)
    delay_s=0.001,  # s, one 1 kHz cycle (assumption)
)

# --- Direct-drive motor encoder (fractional-elbow paper, seeds/004, III-A) ---------------------
# The AKD drive's encoder emulator outputs quadrature pulses; 8192 lines x 4 edges = 32768 counts
# per revolution (assumption: a common emulated resolution), one count = 1.92e-4 rad.
DD_ENCODER = ChannelSpec(quant_step=2 * math.pi / 32768)

# --- Virtual-force-sensor lab (seeds/003, Sec. II-B) ----------------------------------------
# Capstan robot's motor encoders in link-side radians: the paper gives "a Cartesian resolution of
# better than 0.002 mm"; one count of each joint moves the end effector by at most (l1 + l2) x
# step, so step = 0.002 mm / 0.7 m = 2.86e-6 rad (about 2.2 M counts per link turn).
CAPSTAN_ENCODER = ChannelSpec(quant_step=0.002e-3 / 0.7)
# ADXL203 two-axis accelerometer (Analog Devices ADXL103/ADXL203 datasheet, Rev. B): noise
# density 110 ug/sqrt(Hz) rms; bandwidth set by the output capacitors, 50 Hz with C = 0.1 uF
# (datasheet's f_-3dB = 1 / (2 pi 32 kOhm C)), a single-pole filter. White noise at the 1 kHz
# samples with that density over the 500 Hz Nyquist band: 110e-6 x 9.81 x sqrt(500) = 0.024 m/s²
# before the 50 Hz pole. Zero-g offset after a static calibration: 0.02 m/s² (assumption; the
# datasheet's uncalibrated offset is +-25 mg).
ADXL203_ACCEL = ChannelSpec(
    noise_std=110e-6 * 9.81 * math.sqrt(500.0),  # m/s², datasheet noise density over 0-500 Hz
    bias_std=0.02,  # m/s², assumption (residual after calibration)
    bandwidth_hz=50.0,  # Hz, C_x = C_y = 0.1 uF (datasheet)
    filter_order=1,
)
# JR3 50M31A3 F/T sensor (the paper's model; 50 mm, rated +-100 N in Fx, Fy: assumption, JR3's
# "-I25" class is 25 lbf = 111 N): same DSP (16384 counts full scale, 125 Hz output) and the same
# noise/offset/drift assumptions as JR3_FORCE above, scaled to the smaller range.
JR3_50M31_FORCE = ChannelSpec(
    noise_std=0.025,  # N, assumption (~4 counts of 0.0068 N)
    bias_std=0.05,  # N, assumption (offset after taring)
    drift_per_s=0.001,  # N/s, assumption
    quant_step=111.0 / 16384,  # N, 111 N full scale / 16384 counts
    bandwidth_hz=125.0,  # Hz, JR3 DSP filter-2 output
    filter_order=2,
)

# --- Base JR3 under the seat of the 5-DoF arm lab (seeds/001 Sec. 3) ------------------------------
# Rated range assumed +-2000 N / +-200 N·m (the subject sits on it: a large-capacity JR3 class;
# spec Set-up, assumption). Same DSP convention as JR3_FORCE above: full scale at 16384 counts, so
# one count is 2000/16384 = 0.122 N and 200/16384 = 0.0122 N·m; noise of 3 counts (assumption, as
# JR3_FORCE's ~4). The offset is not tared (the subject's weight loads it): 2 N / 0.2 N·m std,
# drawn once per session (assumption); the static regression's intercept absorbs it. No drift and
# no low-pass: the lab holds each configuration 1 s and averages it (seeds/001 Sec. 4.1), so the
# filter has no effect on the mean and a drift over 1 s is below one count (assumption).
JR3_BASE_FORCE = ChannelSpec(
    noise_std=3 * 2000.0 / 16384,  # N, assumption (3 counts)
    bias_std=2.0,  # N, assumption (untared offset under the seated subject)
    quant_step=2000.0 / 16384,  # N, 2000 N full scale / 16384 counts (JR3 DSP, see JR3_FORCE)
)
JR3_BASE_TORQUE = ChannelSpec(
    noise_std=3 * 200.0 / 16384,  # N·m, assumption (3 counts)
    bias_std=0.2,  # N·m, assumption (same relative size as the force offset)
    quant_step=200.0 / 16384,  # N·m, 200 N·m full scale / 16384 counts (JR3 DSP, see JR3_FORCE)
)

# --- Vicon marker clusters of the 5-DoF arm lab (seeds/001 Sec. 3: Vicon T10 at 500 Hz) ----------
# Noise 0.2 mm per axis on a cluster's position and 0.3 deg per axis on its orientation (spec 001,
# Set-up, assumption). The orientation is recorded as a unit quaternion (w, x, y, z): a small
# rotation by theta per axis moves its vector part by theta / 2, so each component gets
# radians(0.3) / 2 of white noise and the reader renormalises (assumption: small-angle model).
VICON_MARKER_POS = ChannelSpec(noise_std=0.2e-3)  # m, spec 001 assumption
VICON_MARKER_QUAT = ChannelSpec(noise_std=math.radians(0.3) / 2)  # quaternion units, see above

SENSOR_PRESETS: dict[str, ChannelSpec] = {
    "capstan_encoder": CAPSTAN_ENCODER,
    "adxl203": ADXL203_ACCEL,
    "jr3_50m31_force": JR3_50M31_FORCE,
    "jr3_base_force": JR3_BASE_FORCE,
    "jr3_base_torque": JR3_BASE_TORQUE,
    "vicon_marker_pos": VICON_MARKER_POS,
    "vicon_marker_quat": VICON_MARKER_QUAT,
    "jr3_force": JR3_FORCE,
    "jr3_torque": JR3_TORQUE,
    "lwr_encoder": LWR_ENCODER,
    "dd_encoder": DD_ENCODER,
    "lwr_joint_torque": LWR_JOINT_TORQUE,
    "ideal": ChannelSpec.ideal(),
}


def get_preset(name: str) -> ChannelSpec:
    """Return the preset called ``name`` (a key of :data:`SENSOR_PRESETS`)."""
    try:
        return SENSOR_PRESETS[name]
    except KeyError:
        raise ConfigError(f"unknown sensor preset {name!r}; valid names: {sorted(SENSOR_PRESETS)}") from None


# Clean channel name -> SensorSuite field. The order is fixed forever: each channel's random stream
# is the child at this position, so new channels must be appended at the end.
CHANNEL_SPEC_FIELDS: dict[str, str] = {
    "ft_force": "ft_force",
    "ft_torque": "ft_torque",
    "robot_q": "encoder",
    "robot_tau": "joint_torque",
}


@dataclass(frozen=True, kw_only=True)
class _Suite:
    """A set of named channel models; ``CHANNELS`` maps clean channel names to fields, in the fixed
    order of the random streams (new channels are appended, never inserted)."""

    CHANNELS: ClassVar[dict[str, str]] = {}

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, ChannelSpec):
                raise ConfigError(
                    f"{type(self).__name__}.{f.name} must be a ChannelSpec, got {type(value).__name__}"
                )

    @classmethod
    def ideal(cls):
        """Perfect sensors everywhere: measured channels equal the clean ones."""
        return cls(**{f.name: ChannelSpec.ideal() for f in fields(cls)})

    @classmethod
    def channel_fields(cls) -> dict[str, str]:
        """Clean channel name -> field, in the fixed order of the random streams."""
        return cls.CHANNELS

    def check_rate(self, fs_hz: float, n_samples: int) -> None:
        """Raise :class:`ConfigError` if any channel cannot be recorded at ``fs_hz`` for
        ``n_samples`` samples (see :meth:`ChannelSpec.check_rate`); the message names the channel
        and says that ``sensors.fs_hz`` (or ``sensors.preset=ideal``) is what to change."""
        for channel, field_name in self.CHANNELS.items():
            try:
                getattr(self, field_name).check_rate(fs_hz, n_samples, f"{channel} ({field_name})")
            except ConfigError as exc:
                raise ConfigError(
                    f"sensors.fs_hz={fs_hz:g}: {exc}; the realistic sensors need a higher sensors.fs_hz "
                    f"(or use sensors.preset=ideal)"
                ) from None

    def spec_for(self, channel: str) -> ChannelSpec:
        """The spec applied to clean channel ``channel`` (a key of :meth:`channel_fields`)."""
        try:
            return getattr(self, self.CHANNELS[channel])
        except KeyError:
            raise ConfigError(
                f"no sensor model for channel {channel!r}; valid channels: {list(self.CHANNELS)}"
            ) from None


@dataclass(frozen=True, kw_only=True)
class SensorSuite(_Suite):
    """The sensors the conditioning-window protocol records.

    Attributes:
        ft_force: F/T sensor forces, N (channel ``ft_force``).
        ft_torque: F/T sensor torques, N·m (channel ``ft_torque``).
        encoder: robot joint positions, rad (channel ``robot_q``).
        joint_torque: robot joint torque sensors, N·m (channel ``robot_tau``).
    """

    CHANNELS: ClassVar[dict[str, str]] = CHANNEL_SPEC_FIELDS
    ft_force: ChannelSpec
    ft_torque: ChannelSpec
    encoder: ChannelSpec
    joint_torque: ChannelSpec

    @classmethod
    def realistic(cls) -> SensorSuite:
        """JR3-class F/T sensor and LWR-III encoders and joint torque sensors (the presets)."""
        return cls(
            ft_force=JR3_FORCE, ft_torque=JR3_TORQUE, encoder=LWR_ENCODER, joint_torque=LWR_JOINT_TORQUE
        )


def measure(
    clean: Mapping[str, np.ndarray],
    suite: SensorSuite,
    fs_hz: float,
    rng: np.random.Generator,
    t0_s: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Apply the suite's sensor models to clean simulated channels.

    One child seed per known channel is drawn from ``rng`` in the fixed order of
    :data:`CHANNEL_SPEC_FIELDS`, whether or not that channel is present, and each channel gets its
    own generator from its seed. A channel's measurement therefore depends only on ``rng``'s state
    and its own data: adding or removing other channels does not change it.

    Args:
        clean: channel name -> (n_trials, n_samples, n_axes) clean signal; names among
            ``ft_force`` (N), ``ft_torque`` (N·m), ``robot_q`` (rad), ``robot_tau`` (N·m).
        suite: the sensor models (:class:`SensorSuite`, :class:`CapstanSensorSuite`).
        fs_hz: sample rate, Hz.
        rng: the only source of randomness; advanced by a fixed number of draws.
        t0_s: (n_trials,) s since taring at each record's first sample (see
            :func:`~armlab.sensors.channel.apply_channel`).

    Returns:
        The measured channels under the same names, float64, same shapes.

    Raises:
        ConfigError: a name in ``clean`` has no sensor model.
    """
    order = suite.channel_fields()
    unknown = sorted(set(clean) - set(order))
    if unknown:
        raise ConfigError(f"no sensor model for channels {unknown}; valid channels: {list(order)}")
    seeds = rng.integers(0, 2**63, size=len(order), dtype=np.int64)
    # The channels are independent (each has its own generator and data), so they are measured
    # concurrently on the cores (NumPy and SciPy release the GIL in their array loops); the results
    # are bit-identical to measuring them one after the other, and the first channel in order that
    # fails raises, as it would serially.
    with ThreadPoolExecutor(min(len(clean), usable_cpus()) or 1) as pool:
        jobs = {
            name: pool.submit(
                apply_channel,
                clean[name],
                fs_hz,
                suite.spec_for(name),
                np.random.default_rng(int(seed)),
                t0_s=t0_s,
            )
            for seed, name in zip(seeds, order, strict=True)
            if name in clean
        }
        return {name: job.result() for name, job in jobs.items()}


@dataclass(frozen=True, kw_only=True)
class CapstanSensorSuite(_Suite):
    """The sensors of the virtual-force-sensor lab (seeds/003 Sec. II-B).

    Attributes:
        encoder: motor encoders, link-side rad (channel ``theta``).
        motor_torque: the controller's recorded torque command, N·m (channel ``tau``; ideal in
            the realistic suite: the paper records it from the controller, Table II).
        accelerometer: ADXL203 x, y, m/s² (channel ``acc_site``).
        ft_force: F/T sensor x, y, N (channel ``ft_site``).
    """

    CHANNELS: ClassVar[dict[str, str]] = {
        "theta": "encoder",
        "tau": "motor_torque",
        "acc_site": "accelerometer",
        "ft_site": "ft_force",
    }
    encoder: ChannelSpec
    motor_torque: ChannelSpec
    accelerometer: ChannelSpec
    ft_force: ChannelSpec

    @classmethod
    def realistic(cls) -> CapstanSensorSuite:
        """Capstan encoders, ADXL203 accelerometer, JR3 50M31 F/T sensor, exact torque command."""
        return cls(
            encoder=CAPSTAN_ENCODER,
            motor_torque=ChannelSpec.ideal(),
            accelerometer=ADXL203_ACCEL,
            ft_force=JR3_50M31_FORCE,
        )


@dataclass(frozen=True, kw_only=True)
class Arm5SensorSuite(_Suite):
    """The sensors of the 5-DoF stiffness lab (seeds/001 Sec. 3).

    Attributes:
        wrist_force, wrist_torque: the JR3 between robot and cuff, N and N·m (channels
            ``wrist_force``, ``wrist_torque``; 2 kHz).
        base_force, base_torque: the JR3 under the seat, N and N·m (channels ``base_force``,
            ``base_torque``; 2 kHz).
        marker_pos, marker_quat: a Vicon marker cluster's position m and unit quaternion (channels
            ``forearm_marker_pos``, ``forearm_marker_quat``; 500 Hz).
    """

    CHANNELS: ClassVar[dict[str, str]] = {
        "wrist_force": "wrist_force",
        "wrist_torque": "wrist_torque",
        "base_force": "base_force",
        "base_torque": "base_torque",
        "forearm_marker_pos": "marker_pos",
        "forearm_marker_quat": "marker_quat",
    }
    wrist_force: ChannelSpec
    wrist_torque: ChannelSpec
    base_force: ChannelSpec
    base_torque: ChannelSpec
    marker_pos: ChannelSpec
    marker_quat: ChannelSpec

    @classmethod
    def realistic(cls) -> Arm5SensorSuite:
        """The JR3 presets at the wrist and under the seat, Vicon marker noise."""
        return cls(
            wrist_force=JR3_FORCE,
            wrist_torque=JR3_TORQUE,
            base_force=JR3_BASE_FORCE,
            base_torque=JR3_BASE_TORQUE,
            marker_pos=VICON_MARKER_POS,
            marker_quat=VICON_MARKER_QUAT,
        )

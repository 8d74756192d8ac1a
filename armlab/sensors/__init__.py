"""Sensor models applied to clean simulated signals (noise, bias, drift, quantisation, bandwidth, delay)."""

from armlab.sensors.channel import ChannelSpec, apply_channel
from armlab.sensors.presets import (
    ADXL203_ACCEL,
    CAPSTAN_ENCODER,
    CHANNEL_SPEC_FIELDS,
    JR3_50M31_FORCE,
    JR3_BASE_FORCE,
    JR3_BASE_TORQUE,
    JR3_FORCE,
    JR3_TORQUE,
    LWR_ENCODER,
    LWR_JOINT_TORQUE,
    SENSOR_PRESETS,
    CapstanSensorSuite,
    SensorSuite,
    get_preset,
    measure,
)

__all__ = [
    "ChannelSpec",
    "apply_channel",
    "CHANNEL_SPEC_FIELDS",
    "JR3_FORCE",
    "JR3_TORQUE",
    "LWR_ENCODER",
    "LWR_JOINT_TORQUE",
    "SENSOR_PRESETS",
    "SensorSuite",
    "get_preset",
    "measure",
    "ADXL203_ACCEL",
    "CAPSTAN_ENCODER",
    "JR3_50M31_FORCE",
    "JR3_BASE_FORCE",
    "JR3_BASE_TORQUE",
    "CapstanSensorSuite",
]

"""Sensor models applied to clean simulated signals (noise, bias, drift, quantisation, bandwidth, delay)."""

from armlab.sensors.channel import ChannelSpec, apply_channel
from armlab.sensors.presets import (
    CHANNEL_SPEC_FIELDS,
    JR3_FORCE,
    JR3_TORQUE,
    LWR_ENCODER,
    LWR_JOINT_TORQUE,
    SENSOR_PRESETS,
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
]

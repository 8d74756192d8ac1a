"""Protocol ``virtual_force_sensor``: arm impedance without a force sensor (../shared/seeds/003).

A capstan-driven planar robot identifies its own dynamics, then mass-spring fixtures of known
stiffness and a relaxed arm; Method 1 (virtual sensor) against Method 2 (F/T sensor).
"""

from armlab.protocols.base import Protocol
from armlab.protocols.virtual_force_sensor import hooks, preflight
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig

__all__ = ["PROTOCOL", "VirtualForceSensorConfig"]

PROTOCOL = Protocol(
    name="virtual_force_sensor",
    paper="seeds/003: arm impedance without a force sensor (capstan planar robot, fixtures, arm)",
    summary="capstan robot, mass-spring fixtures and relaxed arm; virtual force sensor vs F/T sensor",
    schema=VirtualForceSensorConfig,
    groups={"arm": "planar_hill", "sensors": "realistic"},
    simulate=hooks.simulate,
    validate=preflight.validate,
    reestimate_group="vfs",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    examples=(
        "run protocol=virtual_force_sensor capstan.cable=rigid capstan.drag=false",
        "run protocol=virtual_force_sensor sensors=ideal capstan.cable=rigid capstan.drag=false "
        "capstan.coulomb_Nm=0 capstan.id_ee_mass_kg=0 subject.enabled=false",
        "estimate outputs/virtual_force_sensor/<run> vfs.robot_model=table_vi",
    ),
    lab_effects={
        "cable_drag": "capstan.drag",
        "transmission_compliance": "capstan.cable",
        "joint_friction": "capstan.coulomb_Nm",
        "robot_model_error": "capstan.id_ee_mass_kg",
        "cocontraction_variation": "subject.enabled",
    },
    catalogue=(
        "reflex",
        "cuff_compliance",
        "transmission_compliance",
        "cable_drag",
        "joint_friction",
        "force_sensor_noise",
        "force_sensor_drift",
        "force_sensor_bandwidth",
        "accel_noise",
        "accel_misalignment",
        "encoder_quantisation",
        "channel_delay",
        "payload_mass",
        "cocontraction_variation",
        "robot_model_error",
        "plane_tilt",
        "torso_translation",
    ),
)

"""Protocol ``fractional_elbow``: fractional-order models of the elbow (../shared/seeds/004).

A direct-drive motor applies a random-phase multisine force to the hand of a 1-DoF elbow; the
frequency response G = theta / F by Welch's method and Levy fits of Table I's structures.
"""

from armlab.protocols.base import Protocol
from armlab.protocols.fractional_elbow import hooks, preflight
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig

__all__ = ["PROTOCOL", "FractionalElbowConfig"]

PROTOCOL = Protocol(
    name="fractional_elbow",
    paper="seeds/004: fractional-order models of the elbow (direct-drive motor, 1-DoF elbow)",
    summary="direct-drive motor pushes the 1-DoF elbow; FRF and Levy fits of Table I's structures",
    schema=FractionalElbowConfig,
    groups={"sensors": "realistic", "scenario": "fractional_elbow"},
    simulate=hooks.simulate,
    validate=preflight.validate,
    reestimate_group="frf",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    examples=(
        "run protocol=fractional_elbow elbow.impedance=fractional elbow.fractional_order=0.5",
        "estimate outputs/fractional_elbow/<run> frf.welch_window=10000",
    ),
    lab_effects={"reflex": "reflex.enabled", "cocontraction_variation": "subject.enabled"},
    catalogue=(
        "reflex",
        "joint_friction",
        "force_sensor_noise",
        "force_sensor_drift",
        "force_sensor_bandwidth",
        "encoder_quantisation",
        "channel_delay",
        "payload_mass",
        "cocontraction_variation",
    ),
)

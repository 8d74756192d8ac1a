"""Protocol ``conditioning_window``: conditioning vs. observation window (../shared/seeds/000).

The LWR-class robot perturbs the planar arm held at q0 through the cuff; 26 windows x 30 trials
of fifth-order perturbations; the full and reduced joint-space least squares per window, the
conditioning criteria, and the sim-to-real diagnosis of the paper's Eq. (9) model.
"""

from armlab.protocols.base import Protocol
from armlab.protocols.conditioning_window import hooks, preflight
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.diagnosis import HOOKS
from armlab.sim.lab import LAB_EFFECTS, load_compiled

__all__ = ["PROTOCOL", "ConditioningWindowConfig"]


PROTOCOL = Protocol(
    name="conditioning_window",
    paper="seeds/000: conditioning vs. excitation time (LWR-III, 2-DoF arm)",
    summary="LWR perturbs the planar arm; K, D, xi per observation window and when they become reliable",
    schema=ConditioningWindowConfig,
    groups={
        "arm": "planar_hill",
        "robot": "lwr",
        "sensors": "realistic",
        "scenario": "conditioning_window",
        "estimator": "joint_ls",
    },
    simulate=hooks.simulate,
    preload=load_compiled,
    validate=preflight.validate,
    reestimate_group="estimator",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    effects=LAB_EFFECTS,
    lab_effects={
        "reflex": "reflex.enabled",
        "cuff_compliance": "cuff.rigid",
        "cocontraction_variation": "subject.enabled",
    },
    examples=(
        "run protocol=conditioning_window seed=3 arm=planar_linear reflex.enabled=false",
        "run --multirun protocol=conditioning_window seed=0,1,2 hydra/launcher=joblib",
        "estimate outputs/conditioning_window/<run> estimator.lowpass_hz=30",
        "diagnose data=outputs/conditioning_window/<run> protocol=conditioning_window",
    ),
    catalogue=(
        "reflex",
        "cuff_compliance",
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
        "plane_tilt",
        "torso_translation",
    ),
    diagnosis=HOOKS,
)

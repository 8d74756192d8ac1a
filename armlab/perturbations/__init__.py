"""Perturbation waveforms applied by the robot to the arm."""

from armlab.perturbations.cartesian_timeline import (
    EXPERIMENTS,
    SEQUENCE_DIRECTIONS,
    StopTimeline,
    experiment_timeline,
    stop_path_times,
    stop_timeline,
)
from armlab.perturbations.joint_families import (
    PERTURBATION_FAMILIES,
    JointPerturbation,
    perturbation_signal,
)
from armlab.perturbations.multisine import ForceScenario, load_force_scenario, multisine
from armlab.perturbations.prbs import prbs_position
from armlab.perturbations.quintic import (
    PAPER_DIRECTIONS,
    QuinticPerturbation,
    conditioning_ratio,
    observation_durations,
    polynomial_coefficients,
    quintic_profile,
    window_durations,
)
from armlab.perturbations.ramp_waveforms import (
    MIN_SAMPLES_PER_SEGMENT,
    TRAPEZOIDAL,
    TRIANGULAR,
    RampWaveform,
    Shape,
    ramp_waveform,
)
from armlab.perturbations.reference_paths import (
    CIRCLE_CENTRE_M,
    CIRCLE_RADIUS_M,
    MOTION_DURATION_S,
    TABLE_3_3,
    ReferencePath,
    circle_path,
    golden_omega,
    sinusoid_path,
    spiral_path,
    table_3_3_path,
)
from armlab.perturbations.segments import QUINTIC_PEAK_ACC, QUINTIC_PEAK_VEL, SegmentWaveform
from armlab.perturbations.sum_of_sines import SumOfSines, sum_of_sines

__all__ = [
    "multisine",
    "load_force_scenario",
    "ForceScenario",
    "prbs_position",
    "PERTURBATION_FAMILIES",
    "JointPerturbation",
    "perturbation_signal",
    "PAPER_DIRECTIONS",
    "QuinticPerturbation",
    "conditioning_ratio",
    "observation_durations",
    "polynomial_coefficients",
    "quintic_profile",
    "window_durations",
    "SumOfSines",
    "sum_of_sines",
    "EXPERIMENTS",
    "SEQUENCE_DIRECTIONS",
    "StopTimeline",
    "experiment_timeline",
    "stop_path_times",
    "stop_timeline",
    "MIN_SAMPLES_PER_SEGMENT",
    "TRAPEZOIDAL",
    "TRIANGULAR",
    "RampWaveform",
    "ramp_waveform",
    "CIRCLE_CENTRE_M",
    "CIRCLE_RADIUS_M",
    "MOTION_DURATION_S",
    "TABLE_3_3",
    "ReferencePath",
    "circle_path",
    "golden_omega",
    "sinusoid_path",
    "spiral_path",
    "table_3_3_path",
    "Shape",
    "QUINTIC_PEAK_ACC",
    "QUINTIC_PEAK_VEL",
    "SegmentWaveform",
]

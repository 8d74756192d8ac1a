"""Perturbation waveforms applied by the robot to the arm."""

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
from armlab.perturbations.sum_of_sines import SumOfSines, sum_of_sines

__all__ = [
    "multisine",
    "load_force_scenario",
    "ForceScenario",
    "prbs_position",
    "PAPER_DIRECTIONS",
    "QuinticPerturbation",
    "conditioning_ratio",
    "observation_durations",
    "polynomial_coefficients",
    "quintic_profile",
    "window_durations",
    "SumOfSines",
    "sum_of_sines",
]

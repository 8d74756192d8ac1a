"""Perturbation waveforms applied by the robot to the arm."""

from armlab.perturbations.quintic import (
    PAPER_DIRECTIONS,
    QuinticPerturbation,
    conditioning_ratio,
    observation_durations,
    polynomial_coefficients,
    quintic_profile,
    window_durations,
)

__all__ = [
    "PAPER_DIRECTIONS",
    "QuinticPerturbation",
    "conditioning_ratio",
    "observation_durations",
    "polynomial_coefficients",
    "quintic_profile",
    "window_durations",
]

"""Per-trial, per-step muscle commands of a subject whose activation fluctuates.

:class:`~armlab.config.subject.SubjectConfig` describes the fluctuation; :func:`activation_commands`
draws it from the run's seeded generator, vectorised over trials, samples and muscles.
"""

from __future__ import annotations

import numpy as np

from armlab.config.subject import SubjectConfig
from armlab.dsp import lowpass_noise

__all__ = ["BURN_IN_PERIODS", "activation_commands"]

# periods of the low-pass corner drawn and dropped before the record starts, so that the
# fluctuation is stationary from the first sample (the filter's start-up transient is gone)
BURN_IN_PERIODS = 4.0


def activation_commands(
    base: np.ndarray,
    subject: SubjectConfig,
    n_trials: int,
    n_steps: int,
    substeps: int,
    fs_hz: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Muscle commands of every trial at every physics step.

    The fluctuation is drawn at the sample rate ``fs_hz`` and held over the ``substeps`` physics
    steps of each sample (the activation dynamics smooth the steps).

    Args:
        base: (n_muscles,) the hold's activation commands.
        subject: the fluctuation (its ``active`` must be true).
        n_trials, n_steps: trials and physics steps of the batch.
        substeps: physics steps per sample.
        fs_hz: Hz, sample rate.
        rng: the subject's generator (advanced by one normal per trial, then the noise array).

    Returns:
        (n_trials, n_steps, n_muscles) commands in [0, 1].
    """
    base = np.asarray(base, float)
    n_mus = base.shape[0]
    n_samples = -(-n_steps // substeps)
    eta = rng.standard_normal(n_trials)
    eps = lowpass_noise(
        rng,
        (n_trials, n_samples, n_mus),
        fs_hz,
        subject.fluctuation_hz,
        burn_in_periods=BURN_IN_PERIODS,
        name="subject.fluctuation_hz",
    )
    rel = 1.0 + subject.trial_cv * eta[:, None, None] + subject.fluctuation_cv * eps
    cmd = np.clip(base * rel, 0.0, 1.0)
    return np.repeat(cmd, substeps, axis=1)[:, :n_steps]

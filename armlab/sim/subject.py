"""Per-trial, per-step muscle commands of a subject whose activation fluctuates.

:class:`~armlab.config.subject.SubjectConfig` describes the fluctuation; :func:`activation_commands`
draws it from the run's seeded generator, vectorised over trials, samples and muscles.
"""

from __future__ import annotations

import numpy as np

from armlab.config.subject import SubjectConfig
from armlab.noise import lowpass_noise

__all__ = ["BURN_IN_PERIODS", "activation_commands", "commands", "fluctuation", "sample_commands"]

# periods of the low-pass corner drawn and dropped before the record starts, so that the
# fluctuation is stationary from the first sample (the filter's start-up transient is gone)
BURN_IN_PERIODS = 4.0


def fluctuation(
    subject: SubjectConfig,
    n_trials: int,
    n_samples: int,
    n_muscles: int,
    fs_hz: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """The relative activation ``1 + trial_cv η + fluctuation_cv ε`` of every trial at every sample.

    η: one standard normal per trial; ε: unit-rms low-pass noise (:func:`armlab.noise.lowpass_noise`).
    Needs no scene: a caller may draw it while the scene is built and settled.

    Args:
        subject: the fluctuation (its ``active`` must be true).
        n_trials, n_samples: trials and samples of the batch.
        n_muscles: muscles.
        fs_hz: Hz, sample rate.
        rng: the subject's generator (advanced by one normal per trial, then the noise array).

    Returns:
        (n_trials, n_samples, n_muscles), dimensionless.
    """
    eta = rng.standard_normal(n_trials)
    eps = lowpass_noise(
        rng,
        (n_trials, n_samples, n_muscles),
        fs_hz,
        subject.fluctuation_hz,
        burn_in_periods=BURN_IN_PERIODS,
        name="subject.fluctuation_hz",
    )
    # 1 + trial_cv η + fluctuation_cv ε, computed in ε's own memory (the same sums and products)
    np.multiply(eps, subject.fluctuation_cv, out=eps)
    return np.add(eps, 1.0 + subject.trial_cv * eta[:, None, None], out=eps)


def sample_commands(base: np.ndarray, rel: np.ndarray, *, overwrite: bool = False) -> np.ndarray:
    """(n_trials, n_samples, n_muscles) commands in [0, 1] of every sample: ``base · rel`` clipped.

    ``overwrite=True`` computes them in ``rel``'s memory (a caller done with ``rel``): the same
    numbers, without a second array of the batch's size.
    """
    out = rel if overwrite else None
    return np.clip(np.multiply(np.asarray(base, float), rel, out=out), 0.0, 1.0, out=out)


def commands(base: np.ndarray, rel: np.ndarray, n_steps: int, substeps: int) -> np.ndarray:
    """(n_trials, n_steps, n_muscles) commands in [0, 1]: :func:`sample_commands`, each sample's value
    held over its ``substeps`` physics steps (the activation dynamics smooth the steps)."""
    return np.repeat(sample_commands(base, rel), substeps, axis=1)[:, :n_steps]


def activation_commands(
    base: np.ndarray,
    subject: SubjectConfig,
    n_trials: int,
    n_steps: int,
    substeps: int,
    fs_hz: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Muscle commands of every trial at every physics step (:func:`fluctuation` then
    :func:`commands`).

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
    rel = fluctuation(subject, n_trials, -(-n_steps // substeps), base.shape[0], fs_hz, rng)
    return commands(base, rel, n_steps, substeps)

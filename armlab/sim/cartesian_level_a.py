"""Level A of paper 002's Cartesian protocol: the thesis's own algebraic generator (Ch. 3).

The robot is an ideal position source and the arm has no inertia (thesis Ch. 3): the hand follows
``q_h = q_r + q_p`` exactly (Eq. 3.1.1) and pushes back with ``F = D(q_h)·q̇_h + K(q_h)·q_p``
(Eqs. 2.2.1, 2.2.2, 2.2.4 without the inertial term). Optional white force noise (an F/T sensor's)
is drawn from an explicit generator. The thesis logs only during perturbations (§3.2.2); the whole
timeline is kept here (it costs < 20 ms) and :attr:`CartesianRecord.logged` marks what it logged.

Which velocity multiplies D: the thesis writes ``q̇_p`` in Eq. 2.2.1 and regresses on ``q̇_h``
(§3.1.2); the two agree wherever data is logged (the reference is stopped), so ``q̇_h`` is used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.models.cartesian_field import QuadraticImpedanceField
from armlab.perturbations.cartesian_timeline import StopTimeline

__all__ = [
    "CartesianRecord",
    "simulate_level_a",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class CartesianRecord:
    """One simulated Cartesian experiment: the timeline, the field, and the hand forces.

    Attributes:
        timeline: the stop-and-perturb timeline (positions, velocities, labels).
        field: the true impedance field.
        sigma: co-contraction index used (thesis: never stated; 0 by default).
        force_clean: (n, 2) N, model force.
        force: (n, 2) N, model force plus sensor noise (equal to ``force_clean`` without noise).
        noise_std_n: N, standard deviation of the white force noise per axis.
    """

    timeline: StopTimeline
    field: QuadraticImpedanceField
    sigma: float
    force_clean: np.ndarray
    force: np.ndarray
    noise_std_n: float

    @property
    def logged(self) -> np.ndarray:
        """(n,) bool: the samples the thesis records (during perturbations, §3.2.2)."""
        return self.timeline.perturbation >= 0

    def stiffness_true(self) -> np.ndarray:
        """(n, 2) N/m, the true diagonal stiffness along the hand path."""
        return self.field.stiffness(self.timeline.q_h, self.sigma)


def simulate_level_a(
    timeline: StopTimeline,
    field: QuadraticImpedanceField,
    *,
    noise_std_n: float = 0.0,
    rng: np.random.Generator | None = None,
    sigma: float = 0.0,
) -> CartesianRecord:
    """Hand forces of the thesis's algebraic model along ``timeline`` (thesis Ch. 3, level A).

    Args:
        timeline: from :func:`armlab.perturbations.experiment_timeline` or ``stop_timeline``.
        field: the impedance field (e.g. ``THESIS_FIELD``, optionally ``.scaled(s)``).
        noise_std_n: N, standard deviation of white force noise added to both axes (>= 0).
        rng: the generator drawing that noise; required when ``noise_std_n > 0``.
        sigma: co-contraction index in [0, 1] (*assumption* of spec 002: 0, never stated).

    Returns:
        The :class:`CartesianRecord` (arrays read-only).

    Raises:
        ConfigError: for negative noise, or noise without a generator.
    """
    if not (np.isfinite(noise_std_n) and noise_std_n >= 0):
        raise ConfigError(f"noise_std_n must be a non-negative number of newtons, got {noise_std_n!r}")
    if noise_std_n > 0 and not isinstance(rng, np.random.Generator):
        raise ConfigError(
            "force noise needs an explicit numpy.random.Generator (rng=np.random.default_rng(seed))"
        )
    clean = field.force(timeline.q_h, timeline.qd_h, timeline.q_p, sigma)
    noisy = clean + noise_std_n * rng.standard_normal(clean.shape) if noise_std_n > 0 else clean.copy()
    clean.flags.writeable = False
    noisy.flags.writeable = False
    return CartesianRecord(
        timeline=timeline,
        field=field,
        sigma=float(sigma),
        force_clean=clean,
        force=noisy,
        noise_std_n=float(noise_std_n),
    )

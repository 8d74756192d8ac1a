"""Scoring an estimated stiffness *field* against the truth over the workspace (paper 002).

On one circle the six monomials of Eq. 2.2.4 are nearly dependent (``x² + y²`` is linear in x and
y there; only the ±8 mm excursions separate them), so the raw coefficients are ill-conditioned
even when the field they describe is right (spec 002's trap). The score is therefore the
thesis's relative error (Eq. 3.1.2), ``100·|K − K̂|/K``, evaluated over a grid of the workspace
the path covers: by default the disc the §3.2.1 circle encloses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.models.cartesian_field import QuadraticImpedanceField, quadratic_basis
from armlab.perturbations.reference_paths import CIRCLE_CENTRE_M, CIRCLE_RADIUS_M

__all__ = [
    "FieldError",
    "disc_grid",
    "field_error",
    "relative_error_pct",
]


def relative_error_pct(truth: np.ndarray, estimate: np.ndarray) -> np.ndarray:
    """Eq. 3.1.2: ``100·|K − K̂| / |K|`` elementwise, %."""
    truth = np.asarray(truth, dtype=float)
    return 100.0 * np.abs(truth - np.asarray(estimate, dtype=float)) / np.abs(truth)


def disc_grid(
    centre: tuple[float, float] = CIRCLE_CENTRE_M, radius_m: float = CIRCLE_RADIUS_M, n_per_axis: int = 41
) -> np.ndarray:
    """Points of a square grid inside a disc: (m, 2) m (the workspace of Exps. 2, 4, 5)."""
    if not (np.isfinite(radius_m) and radius_m > 0) or not (isinstance(n_per_axis, int) and n_per_axis >= 3):
        raise ConfigError("radius_m must be positive and n_per_axis an integer >= 3")
    g = np.linspace(-1.0, 1.0, n_per_axis)
    gx, gy = np.meshgrid(g, g)
    inside = gx**2 + gy**2 <= 1.0 + 1e-12
    return np.stack([centre[0] + radius_m * gx[inside], centre[1] + radius_m * gy[inside]], axis=1)


@dataclass(frozen=True, kw_only=True, eq=False)
class FieldError:
    """Relative error of estimated diagonal stiffness fields over a set of points.

    Attributes:
        error_pct: (..., m, 2) %, Eq. 3.1.2 at each point for K_xx and K_yy.
        max_pct: (...) %, the largest over points and axes.
        rms_pct: (...) %, root mean square over points and axes.
    """

    error_pct: np.ndarray
    max_pct: np.ndarray
    rms_pct: np.ndarray


def field_error(
    coefficients: np.ndarray, truth: QuadraticImpedanceField, points: np.ndarray, sigma: float = 0.0
) -> FieldError:
    """Score estimated Eq. 2.2.4 coefficients against a true field over ``points``.

    Args:
        coefficients: (..., 2, 6) estimated ``k_x0…k_x5`` and ``k_y0…k_y5`` (e.g. one row per
            sequence), N/m per power of m. NaN rows (rank deficient) give NaN scores.
        truth: the true field.
        points: (m, 2) m, where to compare.
        sigma: the co-contraction index in [0, 1] the data were generated at (its ``k_σ·σ`` is
            part of the true K, Eq. 2.2.4).

    Returns:
        The :class:`FieldError`.
    """
    c = np.asarray(coefficients, dtype=float)
    if c.shape[-2:] != (2, 6):
        raise ConfigError(f"coefficients must end in (2, 6), got {c.shape}")
    k_true = truth.stiffness(points, sigma)  # (m, 2)
    k_hat = np.einsum("mj,...aj->...ma", quadratic_basis(points), c)
    err = relative_error_pct(k_true, k_hat)
    return FieldError(
        error_pct=err, max_pct=err.max(axis=(-2, -1)), rms_pct=np.sqrt((err**2).mean(axis=(-2, -1)))
    )

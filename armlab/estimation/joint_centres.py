"""Joint centre of two marker clusters by linear least squares (seed paper 001, Eqs. (7)-(9)).

Two clusters on adjacent segments rotate about a common point r. With p_k the cluster position
and R_k its rotation from the world to the cluster frame (so R_k^T maps cluster coordinates to
the world), r = p_1 + R_1^T d_1 = p_2 + R_2^T d_2 for constant offsets d_1, d_2 (Eqs. (7)-(8)).
Minimising the mean squared gap of Eq. (9) over the samples is the stacked linear least-squares
problem [R_1^T, -R_2^T] [d_1; d_2] = p_2 - p_1 (after Biryukova et al. 2000, the paper's ref. [1]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError, EstimationError
from armlab.estimation.least_squares import least_squares

__all__ = [
    "JointCentreFit",
    "joint_centre",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class JointCentreFit:
    """Estimated joint centre.

    Attributes:
        d1, d2: (3,) m, the centre in the frames of cluster 1 and 2 (Eqs. (7)-(8)).
        centre: (N, 3) m, the centre in the world per sample, the mean of r_1 and r_2.
        rms_gap: m, sqrt of the criterion S of Eq. (9) at the solution.
        covariance: (6, 6) m², covariance of (d1, d2) from the residual variance (Gauss-Markov).
        condition: the 2-norm condition number of the stacked regressor (large: the motion did not
            rotate the clusters relative to each other about two independent axes).
    """

    d1: np.ndarray
    d2: np.ndarray
    centre: np.ndarray
    rms_gap: float
    covariance: np.ndarray
    condition: float


def _check(name: str, a: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.shape[1:] != shape or a.ndim != len(shape) + 1:
        raise DataError(f"{name} must have shape (N, {', '.join(map(str, shape))}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise DataError(f"{name} contains NaN or inf")
    return a


def joint_centre(p1: np.ndarray, rot1: np.ndarray, p2: np.ndarray, rot2: np.ndarray) -> JointCentreFit:
    """Eqs. (7)-(9): the point fixed in both cluster frames.

    Args:
        p1, p2: (N, 3) m, cluster positions in the world.
        rot1, rot2: (N, 3, 3), cluster orientations (columns: the cluster's axes in the world), i.e.
            R_k^T of Eq. (7); a motion-capture frame's orientation matrix as it comes.

    Returns:
        :class:`JointCentreFit`.

    Raises:
        DataError: on mismatched shapes or non-finite samples.
        EstimationError: on fewer than 3 samples or a rank-deficient regressor (no relative rotation
            about two independent axes).
    """
    p1, p2 = _check("p1", p1, (3,)), _check("p2", p2, (3,))
    rot1, rot2 = _check("rot1", rot1, (3, 3)), _check("rot2", rot2, (3, 3))
    n = len(p1)
    if not (len(p2) == len(rot1) == len(rot2) == n):
        raise DataError(
            "p1, rot1, p2, rot2 must have the same number of samples, got "
            f"{len(p1)}, {len(rot1)}, {len(p2)}, {len(rot2)}"
        )
    if n < 3:
        raise EstimationError(f"a joint centre needs at least 3 samples, got {n}")
    a = np.concatenate([rot1, -rot2], axis=2).reshape(3 * n, 6)
    b = (p2 - p1).reshape(3 * n)
    ls = least_squares(a, b)
    x = ls.x
    if ls.rank < 6:
        raise EstimationError(
            f"the joint-centre regressor has rank {ls.rank} < 6: the clusters must rotate relative to each "
            "other about at least two independent axes during the calibration motion"
        )
    cov = ls.inv_normal * ls.residual_variance
    d1, d2 = x[:3], x[3:]
    r1 = p1 + rot1 @ d1
    r2 = p2 + rot2 @ d2
    return JointCentreFit(
        d1=d1,
        d2=d2,
        centre=0.5 * (r1 + r2),
        rms_gap=float(np.sqrt(np.mean(np.sum((r1 - r2) ** 2, axis=1)))),
        covariance=cov,
        condition=ls.condition,
    )

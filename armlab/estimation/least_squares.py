"""Ordinary least squares with the covariance of its estimate, for the static regressions of paper 001.

One solve shared by the joint centres, the static inertial regression and the static stiffness
(:mod:`.joint_centres`, :mod:`.static_inertial`, :mod:`.static_stiffness`): ``numpy.linalg.lstsq``
(optionally on unit-norm columns), ``(AᵀA)⁻¹`` and the residual variance per right-hand side. With
as many equations as unknowns the residual is zero by construction and says nothing about the
noise: the variance is then NaN (not 0, which would claim certainty). Each caller keeps its own
rank requirement and says in its own words which motion was missing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LeastSquares", "least_squares"]


@dataclass(frozen=True, kw_only=True, eq=False)
class LeastSquares:
    """A least-squares solution of ``A x = b``.

    Attributes:
        x: (c,) or (c, k) the solution.
        inv_normal: (c, c) ``(AᵀA)⁻¹`` (the covariance per unit residual variance); NaN when A has
            rank < c.
        residual_variance: () or (k,) residual sum of squares / (r - c) per column of ``b``; NaN
            when r <= c.
        rank: rank of A (of its unit-norm columns when scaled).
        condition: largest / smallest singular value of the solved matrix.
    """

    x: np.ndarray
    inv_normal: np.ndarray
    residual_variance: np.ndarray
    rank: int
    condition: float


def least_squares(a: np.ndarray, b: np.ndarray, *, scale_columns: bool = False) -> LeastSquares:
    """Solve ``a x = b`` (a (r, c), b (r,) or (r, k)); ``scale_columns`` solves on unit-norm columns
    (regressors whose columns differ by orders of magnitude) and scales the solution back."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    r, c = a.shape
    if scale_columns:
        scale = np.linalg.norm(a, axis=0)
        x, _, rank, sv = np.linalg.lstsq(a / scale, b, rcond=None)
        x = x / (scale if x.ndim == 1 else scale[:, None])
    else:
        x, _, rank, sv = np.linalg.lstsq(a, b, rcond=None)
    ss = np.sum((a @ x - b) ** 2, axis=0)
    variance = ss / (r - c) if r > c else np.full(np.shape(ss), np.nan)
    inv_normal = np.linalg.inv(a.T @ a) if rank == c else np.full((c, c), np.nan)
    return LeastSquares(
        x=x,
        inv_normal=inv_normal,
        residual_variance=variance,
        rank=int(rank),
        condition=float(sv[0] / sv[-1]),
    )

"""Static joint stiffness with gravity compensation (seed paper 001, Eqs. (14)-(15)).

Per disturbance j the means over an interval before the onset (the working point q_d, tau_d) and
over an interval after the displacement give Delta q_j = q_post - q_pre and
b_j = [tau_ext - G(q)]_post - [tau_ext - G(q)]_pre with tau_ext = J_limb^T w_wrist, since at rest
K_q (q - q_d) = tau_ext - G(q) - tau_d (Eq. (14), G = Gamma(q, xi_red) static). Stacking gives
A X = B (Eq. (15)) with A = [Delta q_j^T], B = [b_j^T] and X = K_q^T; it is solved by ordinary
least squares and by the SPD area criterion (:mod:`armlab.estimation.spd_stiffness`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError, EstimationError
from armlab.estimation.least_squares import least_squares
from armlab.estimation.spd_stiffness import SPDStiffness, chen_mcinroy

__all__ = [
    "StaticStiffness",
    "external_joint_torque",
    "static_stiffness",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class StaticStiffness:
    """Joint stiffness from N disturbances (Eqs. (14)-(17)).

    Attributes:
        K_ls: (n, n) N·m/rad, ordinary least squares of A X = B (X transposed back; not symmetric).
        K_ls_std: (n, n) N·m/rad, standard errors of K_ls's entries (Gauss-Markov: each torque
            component's residual variance times the diagonal of (A^T A)^-1).
        K: (n, n) N·m/rad, the SPD solution of the area criterion (Eqs. (16)-(17)).
        spd: the full :class:`SPDStiffness` (P, Q, residual, eigenvalues).
        A: (N, n) rad, the displacements; B: (N, n) N·m, the compensated torque changes.
        gravity_compensated: whether G entered B.
    """

    K_ls: np.ndarray
    K_ls_std: np.ndarray
    K: np.ndarray
    spd: SPDStiffness
    A: np.ndarray
    B: np.ndarray
    gravity_compensated: bool


def external_joint_torque(J_limb: np.ndarray, wrench: np.ndarray) -> np.ndarray:
    """tau_ext = J_limb^T w (..., n) N·m from the wrist wrench w (..., 6) (f N, m N·m, world
    frame, exerted on the limb) and J_limb (..., 6, n)."""
    return np.einsum("...ij,...i->...j", np.asarray(J_limb, float), np.asarray(wrench, float))


def static_stiffness(
    q_pre: np.ndarray,
    q_post: np.ndarray,
    tau_pre: np.ndarray,
    tau_post: np.ndarray,
    g_pre: np.ndarray | None = None,
    g_post: np.ndarray | None = None,
) -> StaticStiffness:
    """Eqs. (14)-(15): K_q from interval means of N disturbances.

    Args:
        q_pre, q_post: (N, n) rad, mean joint angles before the onset and after the displacement.
        tau_pre, tau_post: (N, n) N·m, mean external joint torques J_limb^T w in the same intervals.
        g_pre, g_post: (N, n) N·m, G(q) at the interval means (e.g. from the identified xi_red);
            both None: no gravity compensation (the ablation of the spec's check 6).

    Returns:
        :class:`StaticStiffness`.

    Raises:
        DataError: on mismatched shapes, non-finite values, or only one of g_pre / g_post.
        EstimationError: on fewer than n disturbances or singular Gram matrices.
    """
    arrays = [np.asarray(a, dtype=float) for a in (q_pre, q_post, tau_pre, tau_post)]
    shape = arrays[0].shape
    if len(shape) != 2 or any(a.shape != shape for a in arrays):
        raise DataError(
            f"q_pre, q_post, tau_pre, tau_post must be (N, n) of one shape, got {[a.shape for a in arrays]}"
        )
    if (g_pre is None) != (g_post is None):
        raise DataError("give both g_pre and g_post (gravity compensated) or neither (uncompensated)")
    A = arrays[1] - arrays[0]
    B = arrays[3] - arrays[2]
    if g_pre is not None:
        gp, gq = np.asarray(g_pre, dtype=float), np.asarray(g_post, dtype=float)
        if gp.shape != shape or gq.shape != shape:
            raise DataError(f"g_pre and g_post must be {shape}, got {gp.shape} and {gq.shape}")
        B = B - (gq - gp)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise DataError("the interval means contain NaN or inf")
    if shape[0] < shape[1]:
        raise EstimationError(f"need at least n = {shape[1]} disturbances, got {shape[0]}")
    spd = chen_mcinroy(A, B)  # raises on a singular A^T A before the inverse below
    ls = least_squares(A, B)
    x_ls = ls.x
    x_std = np.sqrt(np.outer(np.diag(ls.inv_normal), ls.residual_variance))  # NaN with N = n (no dof)
    return StaticStiffness(
        K_ls=x_ls.T, K_ls_std=x_std.T, K=spd.K, spd=spd, A=A, B=B, gravity_compensated=g_pre is not None
    )

"""Numerical inverse kinematics of the 5-DoF arm and its Jacobian (seed paper 001, Eq. (10)).

q = argmin ||T(q) T_d^{-1} - I||_F for every sample, where T(q) is the wrist frame of the
(calibrated) kinematic chain and T_d the measured one; minimising the squared Frobenius norm has
the same minimiser. The samples are independent 12-residual, 5-unknown problems, solved all at
once by a batched Levenberg-Marquardt iteration (one (N, 5, 5) batched solve per iteration, no
loop over samples). Why not ``scipy.optimize.least_squares`` on the stacked problem: its sparse
trust-region solver (LSMR) needs ~150 Krylov iterations per step on the block-diagonal Jacobian
(every block has its own singular values), 3-12 s for 30 s of 500 Hz markers on this machine
against ~1 s here; the test checks this solver against ``least_squares`` sample by sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError, EstimationError
from armlab.models.limb_kinematics import LimbKinematics

__all__ = [
    "IKResult",
    "frobenius_residual",
    "inverse_kinematics",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class IKResult:
    """Joint angles from Eq. (10).

    Attributes:
        q: (N, 5) rad.
        J_limb: (N, 6, 5) wrist Jacobian at ``q`` (rows: linear m/rad, angular rad/rad), world frame.
        cost: (N,) ||T(q) T_d^{-1} - I||_F at the solution.
        nfev: iterations of the solver.
    """

    q: np.ndarray
    J_limb: np.ndarray
    cost: np.ndarray
    nfev: int


def frobenius_residual(
    kin: LimbKinematics, q: np.ndarray, rot_d: np.ndarray, pos_d: np.ndarray
) -> np.ndarray:
    """Entries of T(q) T_d^{-1} - I (Eq. (10)) without the constant last row, (..., 12).

    With T = [R, p] and T_d = [R_d, p_d]: T T_d^{-1} = [R R_d^T, p - R R_d^T p_d].
    """
    rot, pos = kin.forward(q)
    rr = rot @ np.swapaxes(rot_d, -1, -2)
    top = rr - np.eye(3)
    trans = pos - np.einsum("...ij,...j->...i", rr, pos_d)
    return np.concatenate([top.reshape(*top.shape[:-2], 9), trans], axis=-1)


def _residual_jacobian(
    kin: LimbKinematics, q: np.ndarray, rot_d: np.ndarray, pos_d: np.ndarray
) -> np.ndarray:
    """d(residual)/dq, (N, 12, 5), analytic: with w_j the world axis of joint j and RR = R R_d^T,
    d(RR)/dq_j = [w_j]x RR and d(p - RR p_d)/dq_j = J_v[:, j] - [w_j]x RR p_d."""
    pose = kin.pose(q)
    rr = pose.wrist_rot @ np.swapaxes(rot_d, -1, -2)  # (N, 3, 3)
    w = pose.axes  # (N, 5, 3)
    d_top = np.cross(w[:, :, :, None], rr[:, None, :, :], axis=2)  # (N, 5, 3, 3): w x (columns of RR)
    rp = np.einsum("nij,nj->ni", rr, pos_d)
    jv = np.cross(w, pose.wrist[:, None, :] - pose.origins)
    d_trans = jv - np.cross(w, rp[:, None, :])
    return np.swapaxes(np.concatenate([d_top.reshape(len(q), 5, 9), d_trans], axis=2), 1, 2)


def inverse_kinematics(
    kin: LimbKinematics,
    rot_d: np.ndarray,
    pos_d: np.ndarray,
    q_init: np.ndarray,
    *,
    # rad: a step this small changes no angle beyond rounding (the solution's own precision is
    # ~1e-15 rad on clean data); 1e-9 would give the same angles to 1e-10 rad in 2/3 of the
    # iterations on noisy markers (measured: 15 vs 24), the default keeps the recovery tests exact
    tol: float = 1e-12,
    max_iter: int = 50,
) -> IKResult:
    """Solve Eq. (10) for every measured wrist frame.

    Args:
        kin: the kinematic chain (e.g. ``limb_kinematics(arm)`` or its calibrated version).
        rot_d: (N, 3, 3) measured wrist orientations (world).
        pos_d: (N, 3) m measured wrist positions (world).
        q_init: (5,) or (N, 5) rad starting guess: start near the solution (the previous sample, the
            commanded configuration); three intersecting shoulder hinges have a second branch
            (q1 + pi, pi - q2, q3 + pi) with the same wrist frame, which a far start can reach.
        tol: rad, stop when every sample's step is below it.
        max_iter: iteration budget.

    Returns:
        :class:`IKResult` (``nfev``: the iterations run); each angle is the 2 pi-equivalent nearest
        ``q_init``.

    Raises:
        DataError: on mismatched shapes or non-finite input.
        EstimationError: when some sample has not converged within ``max_iter``.
    """
    rot_d = np.asarray(rot_d, dtype=float)
    pos_d = np.asarray(pos_d, dtype=float)
    if rot_d.ndim != 3 or rot_d.shape[1:] != (3, 3) or pos_d.shape != (len(rot_d), 3):
        raise DataError(f"rot_d must be (N, 3, 3) and pos_d (N, 3), got {rot_d.shape} and {pos_d.shape}")
    if not (np.all(np.isfinite(rot_d)) and np.all(np.isfinite(pos_d))):
        raise DataError("rot_d or pos_d contains NaN or inf")
    n = len(rot_d)
    try:
        q = np.array(np.broadcast_to(np.asarray(q_init, dtype=float), (n, 5)))
    except ValueError:
        raise DataError(f"q_init must be (5,) or (N, 5) with N = {n}, got {np.shape(q_init)}") from None
    mu = np.full(n, 1e-3)  # Levenberg damping relative to the Gauss-Newton matrix's scale
    res = frobenius_residual(kin, q, rot_d, pos_d)
    cost = np.sum(res * res, axis=1)
    for it in range(1, max_iter + 1):  # noqa: B007 (it is reported as nfev)
        jac = _residual_jacobian(kin, q, rot_d, pos_d)
        jtj = np.swapaxes(jac, 1, 2) @ jac
        grad = np.einsum("nij,ni->nj", jac, res)
        scale = np.trace(jtj, axis1=1, axis2=2) / 5.0
        step = -np.linalg.solve(jtj + (mu * scale)[:, None, None] * np.eye(5), grad[..., None])[..., 0]
        q_try = q + step
        res_try = frobenius_residual(kin, q_try, rot_d, pos_d)
        cost_try = np.sum(res_try * res_try, axis=1)
        better = cost_try <= cost
        q[better], res[better], cost[better] = q_try[better], res_try[better], cost_try[better]
        mu = np.where(better, np.maximum(mu / 10.0, 1e-12), mu * 10.0)
        if np.all(np.max(np.abs(step), axis=1) < tol):
            break
    else:
        raise EstimationError(
            f"inverse kinematics did not converge in {max_iter} iterations "
            f"(worst ||T T_d^-1 - I||_F = {np.sqrt(cost.max()):.3g}); check the chain and the start posture"
        )
    # hinges are 2 pi periodic: report the equivalent angle nearest the start
    start = np.broadcast_to(np.asarray(q_init, dtype=float), (n, 5))
    q = start + (q - start + np.pi) % (2.0 * np.pi) - np.pi
    return IKResult(q=q, J_limb=kin.jacobian(q), cost=np.sqrt(cost), nfev=it)

"""Symmetric positive-definite stiffness by the area criterion of Chen and McInroy (2002), seed
paper 001, Eqs. (15)-(19).

For A X = B with X = K_q^T (Eq. (15)), the criterion f(Y) = ||A Y - B Y^{-T}||_F with X = Y Y^T
(Eq. (16)) expands to tr(P X) + tr(Q X^{-1}) - 2 tr(A^T B) with P = A^T A, Q = B^T B; its
stationary point satisfies X P X = Q, whose unique SPD solution is
X = P^{-1/2} (P^{1/2} Q P^{1/2})^{1/2} P^{-1/2}. The printed Eq. (17) is garbled; its
eigen-decomposition form is used: P = U_P S_P² U_P^T (Eq. (18)),
Q~ = S_P U_P^T Q U_P S_P = U_Q S_Q² U_Q^T (Eq. (19)), K = U_P S_P^{-1} U_Q S_Q U_Q^T S_P^{-1} U_P^T.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError, EstimationError
from armlab.estimation.criteria import symmetric_part

__all__ = [
    "SPDStiffness",
    "area_criterion",
    "chen_mcinroy",
    "spd_from_pq",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class SPDStiffness:
    """The SPD solution of Eqs. (16)-(19).

    Attributes:
        K: (n, n) SPD estimate (units of B over units of A, e.g. N·m/rad).
        P, Q: (n, n) the Gram matrices A^T A and B^T B.
        residual: ||K P K - Q||_F / ||Q||_F (zero up to rounding for a well-conditioned P).
        eigenvalues: (n,) ascending eigenvalues of K (all > 0).
    """

    K: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    residual: float
    eigenvalues: np.ndarray


def spd_from_pq(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """The unique SPD X with X P X = Q (Eqs. (17)-(19)), P and Q SPD (n, n)."""
    lam_p, u_p = np.linalg.eigh(symmetric_part(P))
    if lam_p[0] <= 1e-14 * lam_p[-1]:
        raise EstimationError(
            f"P = A^T A is singular (eigenvalues {lam_p[0]:.3g} .. {lam_p[-1]:.3g}): the displacements "
            "must span every joint direction"
        )
    s_p = np.sqrt(lam_p)
    q_t = (s_p[:, None] * (u_p.T @ Q @ u_p)) * s_p[None, :]
    lam_q, u_q = np.linalg.eigh(symmetric_part(q_t))
    if lam_q[0] <= 1e-14 * lam_q[-1]:
        raise EstimationError(
            f"Q = B^T B is singular (eigenvalues {lam_q[0]:.3g} .. {lam_q[-1]:.3g}): the torque changes "
            "must span every joint direction"
        )
    mid = (u_q * np.sqrt(lam_q)) @ u_q.T
    left = u_p / s_p
    X = left @ mid @ left.T
    return symmetric_part(X)


def chen_mcinroy(A: np.ndarray, B: np.ndarray) -> SPDStiffness:
    """SPD least-squares solution of A X = B by the area criterion (Eqs. (15)-(19)).

    Args:
        A: (N, n) displacements, one row per disturbance (Delta q^T, rad).
        B: (N, n) torque changes (Delta(tau_ext - G))^T, N·m.

    Returns:
        :class:`SPDStiffness` with K = X (= K_q^T = K_q, symmetric).

    Raises:
        DataError: on mismatched or non-finite input.
        EstimationError: when A^T A or B^T B is singular (fewer than n independent disturbances).
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    if A.ndim != 2 or A.shape != B.shape:
        raise DataError(f"A and B must be (N, n) arrays of the same shape, got {A.shape} and {B.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise DataError("A or B contains NaN or inf")
    if A.shape[0] < A.shape[1]:
        raise EstimationError(f"need at least n = {A.shape[1]} disturbances, got {A.shape[0]}")
    P, Q = A.T @ A, B.T @ B
    K = spd_from_pq(P, Q)
    residual = float(np.linalg.norm(K @ P @ K - Q) / np.linalg.norm(Q))
    return SPDStiffness(K=K, P=P, Q=Q, residual=residual, eigenvalues=np.linalg.eigvalsh(K))


def area_criterion(Y: np.ndarray, A: np.ndarray, B: np.ndarray) -> float:
    """f(Y) = ||A Y - B Y^{-T}||_F of Eq. (16), Y (n, n) invertible."""
    return float(np.linalg.norm(A @ Y - B @ np.linalg.inv(Y).T))

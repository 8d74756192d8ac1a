"""Recursive least squares over blocks of samples, with forgetting (paper 002's "future work").

The thesis re-solves batch LS after each perturbation and names recursive LS (with the parameters
initialised from past subjects) as future work (Discussion, "Future development"). This is the
square-root (QR) form of RLS: the state is the triangular factor ``R`` of the λ-weighted
information matrix and ``z = R θ``; each block of ``n`` rows ``Φ``, ``y`` updates it by one QR,

    [R⁺ z⁺] = triu(QR([λ^(n/2) R, λ^(n/2) z; √W Φ, √W y])),   W = diag(λ^(n−1−i)),

which equals per-sample exponentially weighted RLS (information ``R⁺ᵀR⁺ = λⁿ RᵀR + ΦᵀWΦ``)
without ever forming ``ΦᵀΦ`` (the covariance form squares the condition number, which the
quadratic field on one circle cannot afford; spec 002). With λ = 1 and no prior it therefore
equals cumulative LS (:func:`armlab.estimation.online_ls.cumulative_ls`) to rounding. A prior
``θ₀, P₀`` (e.g. from past subjects) enters as ``R₀ = chol(P₀⁻¹)ᵀ``, ``z₀ = R₀θ₀``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError
from armlab.estimation.online_ls import RANK_RTOL, _blocks, _check

__all__ = [
    "RLSResult",
    "recursive_ls",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class RLSResult:
    """Recursive LS estimates after each block.

    Attributes:
        blocks: (b,) block labels in order of arrival.
        theta: (b, p) estimate after each block (NaN while the data is not yet full rank).
        rank: (b,) numerical rank of the column-scaled factor after each block.
        forgetting: λ.
    """

    blocks: np.ndarray
    theta: np.ndarray
    rank: np.ndarray
    forgetting: float


def recursive_ls(
    phi: np.ndarray,
    y: np.ndarray,
    block: np.ndarray,
    *,
    forgetting: float = 1.0,
    theta0: np.ndarray | None = None,
    p0: np.ndarray | None = None,
) -> RLSResult:
    """Block-wise square-root RLS with exponential forgetting (see the module docstring).

    Args:
        phi: (n, p) regressor rows in time order.
        y: (n,) outputs.
        block: (n,) block labels (contiguous runs); an estimate is reported after each block.
        forgetting: λ in (0, 1], per sample (1: no forgetting, equal to cumulative LS).
        theta0: (p,) prior estimate; needs ``p0``.
        p0: (p, p) prior ``P`` (symmetric positive definite, parameter units).

    Returns:
        The :class:`RLSResult`.

    Raises:
        DataError: for a forgetting factor outside (0, 1] or a malformed prior.
    """
    phi, y = _check(phi, y)
    if not (np.isfinite(forgetting) and 0 < forgetting <= 1):
        raise DataError(f"forgetting must lie in (0, 1], got {forgetting!r}")
    if (theta0 is None) != (p0 is None):
        raise DataError("a prior needs both theta0 and p0")
    labels, edges = _blocks(block, len(y))
    n_par = phi.shape[1]
    lam = float(forgetting)
    # column scaling keeps the factor balanced (it cancels in θ); causal: a column's scale is its
    # norm in the first block where it is non-zero (the prior's 1/√P₀ᵢᵢ when there is one)
    scale = np.ones(n_par)
    unset = np.ones(n_par, dtype=bool)
    r_mat = np.zeros((n_par, n_par))
    z = np.zeros(n_par)
    if theta0 is not None:
        t0, p_0 = np.asarray(theta0, dtype=float), np.asarray(p0, dtype=float)
        if t0.shape != (n_par,) or p_0.shape != (n_par, n_par) or not np.allclose(p_0, p_0.T):
            raise DataError(f"theta0 must be ({n_par},) and p0 a symmetric ({n_par}, {n_par}) matrix")
        if not np.all(np.diag(p_0) > 0):
            raise DataError("p0 must be positive definite")
        scale = 1.0 / np.sqrt(np.diag(p_0))
        unset[:] = False
        try:
            # information of the prior in scaled units: (D⁻¹ P₀ D⁻¹)⁻¹ = D P₀⁻¹ D
            r_mat = np.linalg.cholesky(np.linalg.inv(p_0 / np.outer(scale, scale))).T
        except np.linalg.LinAlgError:
            raise DataError("p0 must be positive definite") from None
        z = r_mat @ (t0 * scale)
    theta_out = np.full((len(labels), n_par), np.nan)
    rank = np.zeros(len(labels), dtype=int)
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        m = b - a
        norms = np.linalg.norm(phi[a:b], axis=0)
        new = unset & (norms > 0)
        if np.any(new):
            old = scale.copy()
            scale[new] = norms[new]
            r_mat = r_mat * (old / scale)[None, :]  # R θ_s = z with θ_s = θ·scale
            unset &= ~new
        sw = np.sqrt(lam ** np.arange(m - 1, -1, -1))[:, None]
        decay = lam ** (m / 2)
        stacked = np.block([[decay * r_mat, decay * z[:, None]], [sw * phi[a:b] / scale, sw * y[a:b, None]]])
        tri = np.linalg.qr(stacked, mode="r")[: n_par + 1]
        if tri.shape[0] < n_par + 1:  # fewer rows than unknowns so far
            tri = np.vstack([tri, np.zeros((n_par + 1 - tri.shape[0], n_par + 1))])
        r_mat, z = tri[:n_par, :n_par], tri[:n_par, n_par]
        sv = np.linalg.svd(r_mat, compute_uv=False)
        rank[k] = int(np.sum(sv > RANK_RTOL * sv[0])) if sv[0] > 0 else 0
        if rank[k] < n_par:
            continue
        theta_out[k] = np.linalg.solve(r_mat, z) / scale
    return RLSResult(blocks=labels, theta=theta_out, rank=rank, forgetting=lam)

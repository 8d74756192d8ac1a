"""Batch least squares re-solved as data arrives: paper 002's "online LS" (thesis §3.1.2–3.4.2).

The thesis solves ``θ̂ = (1/N Σ φφᵀ)⁻¹ (1/N Σ φ F)`` either on the data of one perturbation or
sequence (Exps. 1, 2, 5: :func:`per_block_ls`) or on all data so far, "the stored vectors ... not
discarded" (Exps. 3, 4: :func:`cumulative_ls`); "it is possible to limit the length of the vector"
(§3.4.2): the ``window_blocks`` option keeps only the last blocks. A *block* is the data of one
perturbation or one sequence, labelled by an integer per sample.

Every solve scales the regressor's columns to unit norm and calls ``numpy.linalg.lstsq`` (SVD):
the same solution as the normal equations, without squaring their condition number, which the
quadratic field regressor on one circle needs (spec 002: its six monomials are nearly dependent).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError

__all__ = [
    "RANK_RTOL",
    "LSFit",
    "OnlineLS",
    "cumulative_ls",
    "ls_fit",
    "per_block_ls",
]

#: Relative singular-value threshold below which a column-scaled regressor counts as rank
#: deficient: exact dependences sit at ~1e-15, the Exp. 4 circle's near-dependence at ~1e-5.
RANK_RTOL = 1e-10


@dataclass(frozen=True, kw_only=True, eq=False)
class LSFit:
    """One least-squares solution ``y ≈ Φ θ``.

    Attributes:
        theta: (p,) parameters (units of y over those of each column).
        covariance: (p, p) ``σ̂²(ΦᵀΦ)⁻¹`` with ``σ̂²`` the residual variance over ``n − p`` (NaN
            when rank deficient or n <= p).
        residuals: (n,) ``y − Φθ``.
        rank: numerical rank of the column-scaled regressor.
        condition: ratio of its largest to smallest singular value.
        n: number of samples.
    """

    theta: np.ndarray
    covariance: np.ndarray
    residuals: np.ndarray
    rank: int
    condition: float
    n: int

    @property
    def full_rank(self) -> bool:
        """Whether every parameter is identified."""
        return self.rank == len(self.theta)

    @property
    def std(self) -> np.ndarray:
        """(p,) standard errors (NaN when not available)."""
        return np.sqrt(np.diag(self.covariance))


def _check(phi: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    phi, y = np.asarray(phi, dtype=float), np.asarray(y, dtype=float)
    if phi.ndim != 2 or y.shape != (phi.shape[0],):
        raise DataError(f"regressor must be (n, p) and output (n,), got {phi.shape} and {y.shape}")
    if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(y))):
        raise DataError("regressor and output must be finite (NaN or inf found)")
    return phi, y


def ls_fit(phi: np.ndarray, y: np.ndarray) -> LSFit:
    """Least squares with column equilibration (thesis §3.1.2's solution, computed by SVD).

    Args:
        phi: (n, p) regressor rows ``φᵀ``.
        y: (n,) outputs (forces, N).

    Returns:
        The :class:`LSFit`; a rank-deficient problem gets the minimum-norm solution, its rank and
        a NaN covariance.
    """
    phi, y = _check(phi, y)
    n, p = phi.shape
    scale = np.linalg.norm(phi, axis=0)
    scale[scale == 0] = 1.0
    a = phi / scale
    sol, _, _, sv = np.linalg.lstsq(a, y, rcond=RANK_RTOL)
    rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv.size and sv[0] > 0 else 0
    theta = sol / scale
    res = y - phi @ theta
    if rank == p and n > p:
        sigma2 = float(res @ res) / (n - p)
        inv = np.linalg.inv(a.T @ a)
        cov = sigma2 * inv / np.outer(scale, scale)
    else:
        cov = np.full((p, p), np.nan)
    cond = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
    return LSFit(theta=theta, covariance=cov, residuals=res, rank=rank, condition=cond, n=n)


@dataclass(frozen=True, kw_only=True, eq=False)
class OnlineLS:
    """The estimates after each block (perturbation or sequence).

    Attributes:
        blocks: (b,) the block labels, in order of arrival.
        theta: (b, p) the estimate after each block (NaN rows where no data).
        std: (b, p) its standard errors (NaN when rank deficient or noise-free-exact).
        rank: (b,) numerical rank after each block.
        fits: the :class:`LSFit` of each block.
    """

    blocks: np.ndarray
    theta: np.ndarray
    std: np.ndarray
    rank: np.ndarray
    fits: tuple[LSFit, ...]


def _blocks(block: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    block = np.asarray(block)
    if block.shape != (n,):
        raise DataError(f"block labels must be one per sample ({n}), got shape {block.shape}")
    change = np.flatnonzero(np.diff(block)) + 1
    starts = np.concatenate([[0], change])
    labels = block[starts]
    if len(np.unique(labels)) != len(labels):
        raise DataError("each block's samples must be contiguous (labels must not come back)")
    return labels, np.concatenate([starts, [n]])


def _collect(fits: list[LSFit], labels: np.ndarray) -> OnlineLS:
    return OnlineLS(
        blocks=labels,
        theta=np.array([f.theta for f in fits]),
        std=np.array([f.std for f in fits]),
        rank=np.array([f.rank for f in fits]),
        fits=tuple(fits),
    )


def per_block_ls(phi: np.ndarray, y: np.ndarray, block: np.ndarray) -> OnlineLS:
    """One LS per block on that block's data only (Exps. 1, 2, 5; thesis §3.1.2, §3.2.2).

    Args:
        phi: (n, p) regressor rows, in time order.
        y: (n,) outputs.
        block: (n,) block label of each row (contiguous runs).
    """
    phi, y = _check(phi, y)
    labels, edges = _blocks(block, len(y))
    fits = [ls_fit(phi[a:b], y[a:b]) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return _collect(fits, labels)


def cumulative_ls(
    phi: np.ndarray, y: np.ndarray, block: np.ndarray, *, window_blocks: int | None = None
) -> OnlineLS:
    """LS re-solved after each block on all data so far (Exps. 3, 4; thesis §3.3.2, §3.4.2).

    Args:
        phi: (n, p) regressor rows, in time order.
        y: (n,) outputs.
        block: (n,) block label of each row (contiguous runs).
        window_blocks: keep only the last this many blocks (the thesis's "limit the length of the
            vector"); ``None`` keeps everything.
    """
    phi, y = _check(phi, y)
    if window_blocks is not None and not (isinstance(window_blocks, int) and window_blocks >= 1):
        raise DataError(f"window_blocks must be a positive integer or None, got {window_blocks!r}")
    labels, edges = _blocks(block, len(y))
    fits = []
    for k in range(len(labels)):
        first = 0 if window_blocks is None else edges[max(0, k + 1 - window_blocks)]
        fits.append(ls_fit(phi[first : edges[k + 1]], y[first : edges[k + 1]]))
    return _collect(fits, labels)

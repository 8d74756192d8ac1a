"""Confidence criteria of Sec. III-C and IV-D of the conditioning paper.

An estimate is trusted when the condition number of ``W`` (Eq. (19)) is small, the stiffness is
positive definite (Eq. (20)) and symmetric (Eq. (22)); Sec. IV-D also asks that the parameters be
*quasi-constant* over longer observation windows. These functions evaluate each criterion and find
the shortest observation window from which it holds for good (:func:`first_satisfied`).
All matrix functions broadcast over leading dimensions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError, DataError

__all__ = [
    "CriteriaConfig",
    "asymmetry",
    "condition_number",
    "eig_symmetric_part",
    "first_satisfied",
    "is_positive_definite",
    "quasi_constant_flags",
    "relative_error",
    "symmetric_part",
]


@dataclass(frozen=True, kw_only=True)
class CriteriaConfig:
    """Thresholds of the confidence criteria (Sec. IV-D of the conditioning paper).

    Attributes:
        symmetry_tol: a matrix is *quasi-symmetric* when :func:`asymmetry` <= this, in (0, 1].
        constancy_tol: parameters are *quasi-constant* when their change to the next window,
            relative to their block's magnitude (see :func:`quasi_constant_flags`), is <= this, > 0.
    """

    symmetry_tol: float = 0.1
    constancy_tol: float = 0.05

    def __post_init__(self) -> None:
        if not (np.isfinite(self.symmetry_tol) and 0 < self.symmetry_tol <= 1):
            raise ConfigError(f"symmetry_tol must lie in (0, 1], got {self.symmetry_tol!r}")
        if not (np.isfinite(self.constancy_tol) and self.constancy_tol > 0):
            raise ConfigError(f"constancy_tol must be a positive number, got {self.constancy_tol!r}")


def _square(A: np.ndarray) -> np.ndarray:
    A = np.asarray(A, dtype=float)
    if A.ndim < 2 or A.shape[-1] != A.shape[-2]:
        raise DataError(f"expected square matrices (..., n, n), got shape {A.shape}")
    return A


def condition_number(W: np.ndarray) -> np.ndarray | float:
    """Condition number ``sigma_max / sigma_min`` of Eq. (19) of the conditioning paper.

    Args:
        W: (..., r, c) observation matrix.

    Returns:
        (...) condition number; ``inf`` where ``W`` is rank deficient (sigma_min = 0).
    """
    W = np.asarray(W, dtype=float)
    if W.ndim < 2:
        raise DataError(f"W must be a matrix (..., r, c), got shape {W.shape}")
    s = np.linalg.svd(W, compute_uv=False)
    smax, smin = s[..., 0], s[..., -1]
    out = np.divide(smax, smin, out=np.full(smax.shape, np.inf), where=smin > 0)
    return float(out) if out.ndim == 0 else out


def symmetric_part(A: np.ndarray) -> np.ndarray:
    """``A_s = (A + A^T) / 2`` (Sec. IV-D of the conditioning paper); (..., n, n) -> (..., n, n)."""
    A = _square(A)
    return 0.5 * (A + np.swapaxes(A, -1, -2))


def eig_symmetric_part(A: np.ndarray) -> np.ndarray:
    """Eigenvalues ``lambda = eig(A_s)`` of the symmetric part, ascending (Sec. IV-D, Eq. (20)).

    Args:
        A: (..., n, n), e.g. a stiffness in N·m/rad.

    Returns:
        (..., n) in the units of ``A``.
    """
    return np.linalg.eigvalsh(symmetric_part(A))


def is_positive_definite(A: np.ndarray) -> np.ndarray | bool:
    """Whether ``dq^T A dq > 0`` for all ``dq != 0`` (Eq. (20)), i.e. ``eig(A_s) > 0``.

    Args:
        A: (..., n, n).

    Returns:
        (...) bool.
    """
    out = eig_symmetric_part(A)[..., 0] > 0
    return bool(out) if out.ndim == 0 else out


def asymmetry(A: np.ndarray) -> np.ndarray | float:
    """Relative asymmetry ``|A - A^T|_F / |A + A^T|_F``, 0 for a symmetric matrix (Eq. (22)).

    Args:
        A: (..., n, n).

    Returns:
        (...) dimensionless; 0 for the zero matrix, ``inf`` for a nonzero skew-symmetric one.
    """
    A = _square(A)
    At = np.swapaxes(A, -1, -2)
    num = np.linalg.norm(A - At, axis=(-2, -1))
    den = np.linalg.norm(A + At, axis=(-2, -1))
    out = np.where(num == 0, 0.0, np.divide(num, den, out=np.full(num.shape, np.inf), where=den > 0))
    return float(out) if out.ndim == 0 else out


def first_satisfied(t_obs: np.ndarray, flags: np.ndarray) -> float | None:
    """Shortest window from which a criterion holds for it and every longer window (Sec. IV-D).

    Args:
        t_obs: (n_windows,) s, strictly increasing observation window lengths.
        flags: (n_windows,) bool, whether the criterion holds for each window.

    Returns:
        The smallest ``t_obs[k]`` with ``flags[k:]`` all true, in s; None if the last window fails.
    """
    t_obs = np.asarray(t_obs, dtype=float)
    flags = np.asarray(flags)
    if t_obs.ndim != 1 or flags.shape != t_obs.shape or flags.dtype != bool:
        raise DataError(
            f"t_obs and flags must be 1-D of equal length with bool flags; got "
            f"{t_obs.shape} and {flags.dtype} {flags.shape}"
        )
    if t_obs.size == 0:
        raise DataError("need at least one window")
    if np.any(np.diff(t_obs) <= 0):
        raise DataError("t_obs must be strictly increasing")
    holds_on = np.logical_and.accumulate(flags[::-1])[::-1]
    if not holds_on[-1]:
        return None
    return float(t_obs[np.argmax(holds_on)])


def _default_blocks(c: int) -> list[slice]:
    if c == 11:  # Eq. (10): xi, D, K
        return [slice(0, 3), slice(3, 7), slice(7, 11)]
    if c == 8:  # Eq. (23): D, K
        return [slice(0, 4), slice(4, 8)]
    return [slice(0, c)]


def quasi_constant_flags(
    params: np.ndarray,
    tol: float,
    blocks: Sequence[slice] | None = None,
    floor: float = 1e-12,
    t_obs: np.ndarray | None = None,
) -> np.ndarray:
    """Quasi-constancy of the parameters over the observation window (Sec. IV-D of the conditioning paper).

    Window ``k`` is quasi-constant when every parameter ``i`` changes to window ``k + 1`` by at most
    ``tol`` times the Euclidean norm of its block (xi, D or K) in window ``k``:
    ``|p[k+1, i] - p[k, i]| <= tol · max(|p[k, block(i)]|, floor)``. Scaling by the block norm rather
    than by each parameter keeps small entries (e.g. off-diagonal stiffness near 0) from failing on
    changes that are negligible for the matrix as a whole, while keeping blocks of different units
    apart. The last window, having no successor, is judged by its change from the previous one; a
    single window has neither, and is never quasi-constant.

    Args:
        params: (n_windows, c) parameter vectors ordered by increasing window length.
        tol: relative tolerance (> 0), e.g. :attr:`CriteriaConfig.constancy_tol`.
        blocks: index slices of the blocks; default xi/D/K for c = 11 (Eq. (10)), D/K for c = 8
            (Eq. (23)) and a single block otherwise.
        floor: lower bound of a block norm, avoiding division by zero.
        t_obs: (n_windows,) s, strictly increasing window lengths. Given, ``tol`` is a rate per
            second of window: the allowed change to the next window is ``tol · (t[k+1] - t[k])``
            times the block norm, so unevenly spaced windows (10 ms steps, then 30-50 ms
            extension steps) are judged alike. None: ``tol`` per step, as above.

    Returns:
        (n_windows,) bool.
    """
    p = np.asarray(params, dtype=float)
    if p.ndim != 2 or p.shape[0] < 1:
        raise DataError(f"params must be (n_windows >= 1, c), got shape {p.shape}")
    if not (np.isfinite(tol) and tol > 0):
        raise ConfigError(f"tol must be a positive number, got {tol!r}")
    c = p.shape[1]
    blocks = _default_blocks(c) if blocks is None else list(blocks)
    covered = np.concatenate([np.arange(c)[b] for b in blocks]) if blocks else np.array([], int)
    if np.sort(covered).tolist() != list(range(c)):
        raise ConfigError(f"blocks must partition the {c} parameters exactly once, got {blocks}")
    scale = np.empty_like(p)
    for b in blocks:  # a handful of blocks, vectorised over windows
        scale[:, b] = np.maximum(np.linalg.norm(p[:, b], axis=1), floor)[:, None]
    if p.shape[0] == 1:
        return np.zeros(1, bool)
    step = np.ones(p.shape[0] - 1)
    if t_obs is not None:
        t = np.asarray(t_obs, dtype=float)
        if t.shape != (p.shape[0],) or np.any(np.diff(t) <= 0):
            raise DataError(f"t_obs must be ({p.shape[0]},) strictly increasing, got {t.tolist()}")
        step = np.diff(t)
    ok = np.all(np.abs(np.diff(p, axis=0)) <= tol * step[:, None] * scale[:-1], axis=1)
    return np.append(ok, ok[-1])


def relative_error(est: np.ndarray, true: np.ndarray) -> float:
    """Relative error ``|est - true|_F / |true|_F``.

    Args:
        est: estimated array.
        true: ground truth of the same shape, not all zero.

    Returns:
        Dimensionless relative error.
    """
    est, true = np.asarray(est, dtype=float), np.asarray(true, dtype=float)
    if est.shape != true.shape:
        raise DataError(f"est and true must have the same shape, got {est.shape} and {true.shape}")
    ref = np.linalg.norm(true)
    if ref == 0:
        raise DataError("relative_error is undefined for an all-zero ground truth")
    return float(np.linalg.norm(est - true) / ref)

"""The quadratic field with the model's own damping, ``D = δ√K`` (paper 002, Eqs. 2.2.2, 2.2.4).

Eq. 3.4.1 gives the damping two *constant* coefficients per axis, but the thesis's model damping
is ``δ√K(q_h)``, which changes with the hand position (±25 % around the §3.2.1 circle): the linear
regressor is mis-specified, so even noise-free its stiffness coefficients stay ~10 % off on one
circle (the field itself is good to ~0.03 %; see docs/cartesian_online.md). Fitting the model as
the thesis wrote it, 6 k's and one δ per axis (its "12 + 2" parameters, §3.5.2),

    F_a = δ_a √(b(q_h)ᵀk_a) ȧ_h + b(q_h)ᵀk_a a_p,     b = [1, x, y, x², 2xy, y²],

is a nonlinear least-squares problem, solved here by ``scipy.optimize.least_squares`` with the
analytic Jacobian ``∂F/∂k = b (a_p + δ ȧ_h / (2√K))``, ``∂F/∂δ = √K ȧ_h``, started from the Eq.
3.4.1 linear solution. Without noise it recovers Table 3.1 exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from armlab.errors import EstimationError
from armlab.estimation.cartesian_regressors import quadratic_field_regressor
from armlab.estimation.online_ls import _blocks, ls_fit
from armlab.models.cartesian_field import quadratic_basis

__all__ = [
    "SqrtDampingFit",
    "cumulative_sqrt_damping_fit",
    "fit_sqrt_damping_field",
]

_K_FLOOR = 1e-9  # N/m: √K is evaluated at max(K, floor) so an iterate crossing 0 stays finite


@dataclass(frozen=True, kw_only=True, eq=False)
class SqrtDampingFit:
    """One axis of the ``D = δ√K`` quadratic field fit.

    Attributes:
        k: (6,) N/m per power of m, the Eq. 2.2.4 coefficients of this axis.
        delta: √kg, the damping factor of Eq. 2.2.2.
        covariance: (7, 7) Gauss–Newton covariance of ``(k, δ)`` (σ̂²(JᵀJ)⁻¹).
        residual_rms: N.
        nfev: function evaluations used.
    """

    k: np.ndarray
    delta: float
    covariance: np.ndarray
    residual_rms: float
    nfev: int


def fit_sqrt_damping_field(
    q_h: np.ndarray,
    q_p: np.ndarray,
    qd_h: np.ndarray,
    force: np.ndarray,
    axis: int,
    *,
    start: tuple[np.ndarray, float] | None = None,
) -> SqrtDampingFit:
    """Fit ``(k_a, δ_a)`` of one axis by nonlinear least squares (module docstring).

    Args:
        q_h, q_p, qd_h: (n, 2) logged hand position m, perturbation m, hand velocity m/s.
        force: (n,) N, the force along ``axis``.
        axis: 0 (x) or 1 (y).
        start: ``(k, δ)`` to start from; default the Eq. 3.4.1 linear solution with
            ``δ = D̂_aa / √K̂`` at the mean logged position.

    Raises:
        EstimationError: when the linear start is rank deficient (too little data: the six
            monomials need perturbations at more than one stop, e.g. one Exp. 4 sequence is not
            enough).
    """
    phi, _ = quadratic_field_regressor(q_h, q_p, qd_h, axis)
    basis = quadratic_basis(q_h)
    p_a, v_a = np.asarray(q_p, float)[:, axis], np.asarray(qd_h, float)[:, axis]
    y = np.asarray(force, dtype=float)
    if start is None:
        lin = ls_fit(phi, y)
        if not lin.full_rank:
            raise EstimationError(
                f"the quadratic field regressor has rank {lin.rank} < 8 on this data: perturb at more stops"
            )
        k0 = lin.theta[:6]
        k_mean = float(quadratic_basis(np.mean(q_h, axis=0)) @ k0)
        delta0 = lin.theta[6 + axis] / np.sqrt(max(k_mean, _K_FLOOR))
    else:
        k0, delta0 = np.asarray(start[0], dtype=float), float(start[1])
    scale = np.concatenate([np.abs(k0) + 1e-12, [abs(delta0) + 1e-12]])

    def parts(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        k, delta = x[:6] * scale[:6], x[6] * scale[6]
        stiff = basis @ k
        return stiff, np.sqrt(np.maximum(stiff, _K_FLOOR)), delta

    def residual(x: np.ndarray) -> np.ndarray:
        stiff, root, delta = parts(x)
        return delta * root * v_a + stiff * p_a - y

    def jac(x: np.ndarray) -> np.ndarray:
        _, root, delta = parts(x)
        dk = basis * (p_a + delta * v_a / (2 * root))[:, None]
        return np.concatenate([dk, (root * v_a)[:, None]], axis=1) * scale

    x0 = np.ones(7)
    sol = least_squares(residual, x0, jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    theta = sol.x * scale
    res = sol.fun
    n = len(y)
    j = sol.jac / scale
    sigma2 = float(res @ res) / max(n - 7, 1)
    try:
        cov = sigma2 * np.linalg.inv(j.T @ j)
    except np.linalg.LinAlgError:
        cov = np.full((7, 7), np.nan)
    return SqrtDampingFit(
        k=theta[:6],
        delta=float(theta[6]),
        covariance=cov,
        residual_rms=float(np.sqrt(np.mean(res**2))),
        nfev=int(sol.nfev),
    )


def cumulative_sqrt_damping_fit(
    q_h: np.ndarray,
    q_p: np.ndarray,
    qd_h: np.ndarray,
    force: np.ndarray,
    axis: int,
    block: np.ndarray,
) -> list[SqrtDampingFit | None]:
    """:func:`fit_sqrt_damping_field` re-solved after each block on all data so far (Exp. 4).

    Each solve starts from the previous one once there is one. Returns one fit per block, ``None``
    while the data is still rank deficient.
    """
    labels, edges = _blocks(block, len(force))
    out: list[SqrtDampingFit | None] = []
    prev: SqrtDampingFit | None = None
    for k in range(len(labels)):
        e = edges[k + 1]
        try:
            start = None if prev is None else (prev.k, prev.delta)
            prev = fit_sqrt_damping_field(q_h[:e], q_p[:e], qd_h[:e], force[:e], axis, start=start)
        except EstimationError:
            prev = None
        out.append(prev)
    return out

"""Five-element arm parameters fitted to a frequency response, integer or with a fractional arm damper.

The five-element model of Sec. IV-B of seeds/004 puts the hand grasp (spring ``k1``, damper
``d1``) in series with the arm (mass ``M``, spring ``k2``, damper ``d2``); its hand displacement per
hand force is ``1/(d1 s + k1) + 1/(M s² + d2 s + k2)`` (Eq. (31)). Its transfer function (27) has
six coefficients for five parameters, so a Levy fit of (27) read by Eqs. (32)-(37) is inconsistent
by the noise it absorbed; :func:`refine_five_element` fits the five parameters to the response
directly (log-parameters, relative complex residual, bounded trust-region least squares).

The fractional generalisation replaces the arm damper by a springpot ``d2 s^beta`` (a fractional
viscoelastic element between spring, ``beta = 0``, and damper, ``beta = 1``). Levy's commensurate
structures cannot express a grasp in series with it without freeing products of parameters as
independent coefficients (nine for six), and with that much freedom the measurement noise, not
``beta``, decides the fit. :func:`fractional_five_element_sweep` keeps the physical structure and
sweeps ``beta`` over the paper's grid (steps of 0.1 in ``]0, 2[``, Sec. IV-A), continuing each
fit from its neighbour's parameters and starting at the integer five-element fit (``beta = 1``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from armlab.errors import ConfigError, EstimationError
from armlab.estimation.levy import FitIndices, alpha_grid, fit_indices
from armlab.models.tf_structures import FiveElement, check_alpha

__all__ = [
    "FractionalFiveElementSweep",
    "best_five_element",
    "five_element_guesses",
    "five_element_response",
    "fractional_five_element_sweep",
    "refine_five_element",
]

_NAMES = ("M", "k1", "k2", "d1", "d2")
_GUESS_FN_HZ = (2.0, 4.0, 8.0)  # Hz, natural frequencies of the shape-based starts
_GUESS_ZETA = (0.3, 1.0)  # damping ratios of the shape-based starts
_LOG_SPAN = 12.0  # natural-log bound on each parameter around its start (a factor of 1.6e5)


def five_element_response(element: FiveElement, f_hz: np.ndarray, beta: float = 1.0) -> np.ndarray:
    """Hand displacement per hand force (m/N) of the five-element model with arm damper ``d2 s^beta``."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    e = element
    return 1.0 / (e.d1 * s + e.k1) + 1.0 / (e.M * s**2 + e.d2 * s**beta + e.k2)


def _check(f_hz, G) -> tuple[np.ndarray, np.ndarray]:
    f = np.asarray(f_hz, dtype=float)
    G = np.asarray(G, dtype=complex)
    if f.ndim != 1 or f.shape != G.shape or f.size < len(_NAMES) + 1:
        raise EstimationError(
            f"need matching 1-D frequency and response arrays with more than {len(_NAMES)} points, "
            f"got shapes {f.shape} and {G.shape}"
        )
    if not (np.all(np.isfinite(G)) and np.all(np.abs(G) > 0) and np.all(f > 0)):
        raise EstimationError("the response must be finite and non-zero at positive frequencies")
    return f, G


def _fit(f: np.ndarray, G: np.ndarray, start: FiveElement, beta: float) -> tuple[FiveElement, float]:
    x0 = np.log([getattr(start, n) for n in _NAMES])
    s = 2j * np.pi * f
    scale = np.abs(G)

    def residual(x: np.ndarray) -> np.ndarray:  # five_element_response inlined: no dataclass per call
        M, k1, k2, d1, d2 = np.exp(x)
        r = (1.0 / (d1 * s + k1) + 1.0 / (M * s**2 + d2 * s**beta + k2) - G) / scale
        return np.concatenate([r.real, r.imag])

    # each parameter within a factor e^_LOG_SPAN of its start: keeps exp() finite on wild steps
    sol = least_squares(residual, x0, bounds=(x0 - _LOG_SPAN, x0 + _LOG_SPAN), method="trf")
    element = FiveElement(**dict(zip(_NAMES, np.exp(sol.x), strict=True)))
    return element, float(np.mean(sol.fun**2) * 2)  # mean |relative complex residual|²


def five_element_guesses(f_hz, G_m_per_N) -> list[FiveElement]:
    """Starts from the response's shape alone, for when no (27) reading exists (or to check it).

    Arm spring from the low-frequency compliance (grasp taken 5x stiffer than the arm), grasp
    damping for a grasp corner at the top of the band, and the arm's mass and damper from a grid
    of natural frequencies (2, 4, 8 Hz) and damping ratios (0.3, 1): the span of the arm models of
    seeds/004 Table II, whose -3 dB bandwidths lie at 2.8-8.3 Hz.
    """
    f, G = _check(f_hz, G_m_per_N)
    compliance = float(np.abs(G[: max(1, f.size // 20)]).mean())
    k2 = 1.2 / compliance  # 1/k1 + 1/k2 = compliance with k1 = 5 k2
    k1 = 5.0 * k2
    d1 = k1 / (2 * np.pi * float(f[-1]))
    out = []
    for fn in _GUESS_FN_HZ:
        M = k2 / (2 * np.pi * fn) ** 2
        out.extend(FiveElement(M=M, k1=k1, k2=k2, d1=d1, d2=2 * z * np.sqrt(k2 * M)) for z in _GUESS_ZETA)
    return out


def best_five_element(f_hz, G_m_per_N, starts: list[FiveElement], beta: float = 1.0) -> FiveElement:
    """Refine from every start (integer or fractional arm damper) and keep the smallest residual."""
    f, G = _check(f_hz, G_m_per_N)
    check_alpha(beta)
    if not starts:
        raise EstimationError("best_five_element needs at least one start")
    fits = [_fit(f, G, s0, beta) for s0 in starts]
    return min(fits, key=lambda fc: fc[1])[0]


def refine_five_element(f_hz, G_m_per_N, start: FiveElement, beta: float = 1.0) -> FiveElement:
    """The five parameters (arm damper ``d2 s^beta``) fitted to a response in m/N from ``start``."""
    f, G = _check(f_hz, G_m_per_N)
    check_alpha(beta)
    return _fit(f, G, start, beta)[0]


@dataclass(frozen=True, kw_only=True)
class FractionalFiveElementSweep:
    """Fits of the fractional five-element model over a grid of springpot orders.

    Attributes:
        betas: the orders tried.
        cost: mean squared relative complex residual of each fit (the fitted criterion).
        indices: Eqs. (24)-(26) of each fit on the response's magnitude (units of the response).
        elements: the fitted parameters at each order.
        best_index: index of the order with the smallest ``cost``.
    """

    betas: np.ndarray
    cost: np.ndarray
    indices: tuple[FitIndices, ...]
    elements: tuple[FiveElement, ...]
    best_index: int

    @property
    def best_beta(self) -> float:
        return float(self.betas[self.best_index])

    @property
    def best(self) -> FiveElement:
        return self.elements[self.best_index]


def fractional_five_element_sweep(
    f_hz, G_m_per_N, start: FiveElement, step: float = 0.1
) -> FractionalFiveElementSweep:
    """Sweep the arm damper's order ``beta`` over ``step, 2 step, ...`` below 2 (Sec. IV-A's grid).

    Args:
        f_hz: frequencies (Hz).
        G_m_per_N: measured hand displacement per force (m/N); an angle-per-force response times
            the link length.
        start: integer five-element parameters (e.g. :func:`refine_five_element` at ``beta = 1``),
            the start of the continuation.
        step: grid step; ``1 / step`` must be an integer so that ``beta = 1`` lies on the grid.

    Returns:
        The :class:`FractionalFiveElementSweep`.
    """
    f, G = _check(f_hz, G_m_per_N)
    try:
        betas = alpha_grid(step)
    except ConfigError as exc:
        raise EstimationError(str(exc)) from None
    elements: list[FiveElement | None] = [None] * betas.size
    cost = np.full(betas.size, np.inf)
    i1 = int(np.flatnonzero(np.isclose(betas, 1.0))[0])  # the grid holds beta = 1
    for order in (range(i1, -1, -1), range(i1, betas.size)):  # continue down, then up, from beta = 1
        prev = start
        for i in order:
            if elements[i] is None:
                elements[i], cost[i] = _fit(f, G, prev, float(betas[i]))
            prev = elements[i]
    mag = np.abs(G)
    indices = tuple(
        fit_indices(mag, np.abs(five_element_response(e, f, b))) for e, b in zip(elements, betas, strict=True)
    )
    return FractionalFiveElementSweep(
        betas=betas, cost=cost, indices=indices, elements=tuple(elements), best_index=int(np.argmin(cost))
    )

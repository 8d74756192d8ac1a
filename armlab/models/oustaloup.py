"""A fractional viscoelastic element ``c s^beta`` realised by Oustaloup's rational approximation.

Oustaloup's recursive filter approximates ``s^beta`` (0 < beta < 1) over a band
``[w_b, w_h]`` by ``N``+``N``+1 interlaced real zeros and poles,

    s^beta ~ w_h^beta * prod_k (s + z_k) / (s + p_k),   k = -N..N,
    z_k = w_b (w_h / w_b)^((k + N + (1 - beta) / 2) / (2N + 1)),
    p_k = w_b (w_h / w_b)^((k + N + (1 + beta) / 2) / (2N + 1)),

(A. Oustaloup et al., IEEE Trans. Circuits Syst. I 47(1), 2000). The simulation applies the
element's torque ``-c (H * phi)`` from a bilinear (Tustin) discretisation of ``H`` at the
control rate; its exact frequency response is the ground truth of the fractional option.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from armlab.errors import ConfigError

__all__ = [
    "FractionalElement",
    "oustaloup_zpk",
]


def oustaloup_zpk(
    beta: float, band_hz: tuple[float, float], order: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles (rad/s, negative real) and gain of Oustaloup's approximation of ``s^beta``."""
    if not 0.0 < beta < 1.0:
        raise ConfigError(f"Oustaloup order beta must lie in (0, 1), got {beta}")
    lo, hi = (2 * np.pi * float(f) for f in band_hz)
    if not 0 < lo < hi:
        raise ConfigError(f"Oustaloup band must satisfy 0 < low < high Hz, got {band_hz}")
    if order < 1:
        raise ConfigError(f"Oustaloup order N must be >= 1, got {order}")
    k = np.arange(-order, order + 1)
    ratio = hi / lo
    zeros = -lo * ratio ** ((k + order + 0.5 * (1 - beta)) / (2 * order + 1))
    poles = -lo * ratio ** ((k + order + 0.5 * (1 + beta)) / (2 * order + 1))
    return zeros, poles, hi**beta


@dataclass(frozen=True, kw_only=True, eq=False)
class FractionalElement:
    """The element torque ``tau = -coeff * (H * phi)`` as a discrete state-space filter.

    Attributes:
        beta: fractional order; ``coeff`` N·m·s^beta/rad.
        zeros, poles, gain: Oustaloup's continuous approximation of ``s^beta`` (rad/s).
        A, B, C, D: its Tustin discretisation at ``dt`` s (state x, input phi, output H*phi).
    """

    beta: float
    coeff: float
    zeros: np.ndarray
    poles: np.ndarray
    gain: float
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: float
    dt: float

    @classmethod
    def build(cls, beta: float, coeff: float, band_hz: tuple[float, float], order: int, dt: float):
        """Design the approximation and discretise it for a control period ``dt`` s."""
        z, p, k = oustaloup_zpk(beta, band_hz, order)
        if 1.0 / dt < 4 * band_hz[1]:
            raise ConfigError(
                f"Oustaloup band upper edge {band_hz[1]} Hz is too close to the control rate "
                f"{1 / dt:.0f} Hz; keep it below a quarter of the rate ({0.25 / dt:.0f} Hz)"
            )
        # partial fractions H = k + sum_i r_i / (s - p_i) (distinct real poles): a diagonal,
        # well-conditioned realisation (a companion form over 5 decades of poles is not)
        r = np.array([k * np.prod(pi - z) / np.prod(pi - np.delete(p, i)) for i, pi in enumerate(p)])
        A, B, C, D = np.diag(p), np.ones((p.size, 1)), r[None, :], np.array([[k]])
        Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), dt, method="bilinear")
        return cls(
            beta=float(beta),
            coeff=float(coeff),
            zeros=z,
            poles=p,
            gain=float(k),
            A=Ad,
            B=Bd[:, 0],
            C=Cd[0],
            D=float(Dd[0, 0]),
            dt=float(dt),
        )

    def response(self, f_hz: np.ndarray, realised: bool = True) -> np.ndarray:
        """Complex impedance ``coeff * s^beta`` (ideal) or ``coeff * H(s)`` (realised), N·m/rad."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        if not realised:
            return self.coeff * s**self.beta
        h = self.gain * np.prod((s[..., None] - self.zeros) / (s[..., None] - self.poles), axis=-1)
        return self.coeff * h

    def initial_state(self, phi0: float) -> np.ndarray:
        """Filter state at rest with input ``phi0`` (steady state of ``x = A x + B phi0``)."""
        n = self.A.shape[0]
        return np.linalg.solve(np.eye(n) - self.A, self.B * phi0)

"""Transfer-function models of the human arm: the commensurate type and the published models.

:class:`CommensurateTF` is Eq. (23) of the fractional-elbow paper (Tejado et al., "Fractional
order identification of human arm dynamics"), the type :mod:`armlab.estimation.levy` fits. The
module also holds, as data, the arm models that paper compares in Table II (Diaz, Speich, Vlugt,
Fu, all third order, Eq. (31)) with the paper's own fractional model (30), its identified models
(27)-(29), and the five-element model of Sec. IV-B: an arm mass ``M`` held by the arm's spring and
damper ``k2, d2``, driven through the hand grasp ``k1, d1`` in series (Eqs. (31)-(37)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from armlab.errors import ConfigError, EstimationError

__all__ = [
    "IDENTIFIED_MODELS",
    "LITERATURE_MODELS",
    "bandwidth_hz",
    "PUBLISHED_BANDWIDTH_HZ",
    "CommensurateTF",
    "FiveElement",
    "FiveElementFit",
    "check_alpha",
    "five_element_from_tf",
    "s_power",
    "third_order_tf",
]

# -3 dB as an amplitude ratio (Table II's "BW ... where gain is -3 dB", relative to the DC gain).
_MINUS_3DB = 10.0 ** (-3.0 / 20.0)


def check_alpha(alpha: float) -> float:
    """Return ``alpha`` as float if it lies in ``]0, 2[`` (the stable range of Sec. IV-A)."""
    if isinstance(alpha, bool) or not (np.isfinite(alpha) and 0.0 < alpha < 2.0):
        raise ConfigError(f"alpha must lie in the open interval (0, 2), got {alpha!r}")
    return float(alpha)


def s_power(f_hz: np.ndarray, exponents: np.ndarray) -> np.ndarray:
    """``(j 2 pi f)^e`` on the principal branch: ``omega^e exp(j e pi / 2)``.

    Args:
        f_hz: (f,) Hz, >= 0.
        exponents: (K,) real exponents (``k alpha``).

    Returns:
        (f, K) complex, in (rad/s)^e.
    """
    omega = 2.0 * np.pi * np.asarray(f_hz, dtype=float)[:, None]
    e = np.asarray(exponents, dtype=float)[None, :]
    return np.power(omega, e) * np.exp(0.5j * np.pi * e)


def bandwidth_hz(response, dc_gain_abs: float, f_max_hz: float = 1e3, n_grid: int = 4000) -> float:
    """-3 dB bandwidth of any response: lowest frequency where ``|response(f)|`` falls 3 dB below
    ``dc_gain_abs`` (Table II's column).

    A log grid from 1e-4 Hz to ``f_max_hz`` locates the first downward crossing (past any resonance
    peak) and Brent's method refines it to 1e-12 Hz.

    Args:
        response: callable, frequencies (Hz, array) -> complex response.
        dc_gain_abs: ``|G(0)|``, the reference level.
        f_max_hz: Hz, upper end of the search.
        n_grid: grid points.
    """
    f = np.logspace(-4, np.log10(f_max_hz), int(n_grid))
    below = np.flatnonzero(np.abs(response(f)) < _MINUS_3DB * dc_gain_abs)
    if below.size == 0 or below[0] == 0:
        raise EstimationError(
            f"|G| does not fall 3 dB below its low-frequency value between 1e-4 and {f_max_hz:g} Hz"
        )
    i = int(below[0])
    return float(
        brentq(
            lambda x: abs(response(np.array([x]))[0]) - _MINUS_3DB * dc_gain_abs, f[i - 1], f[i], xtol=1e-12
        )
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class CommensurateTF:
    """``G(s) = sum_k b_k s^(k alpha) / sum_k a_k s^(k alpha)`` with ``a_0 = 1``, Eq. (23).

    Attributes:
        b: (m + 1,) numerator coefficients ``b_0 .. b_m``; ``b_k`` in (units of G)·s^(k alpha).
        a: (n + 1,) denominator coefficients, ``a[0] = 1``; ``a_k`` in s^(k alpha).
        alpha: commensurate order in ``]0, 2[`` (1 for integer models).
        name: label for reports.
        units: units of G (e.g. ``"rad/N"``), for reports.
    """

    b: np.ndarray
    a: np.ndarray
    alpha: float = 1.0
    name: str = ""
    units: str = ""

    def __post_init__(self) -> None:
        b, a = np.atleast_1d(np.asarray(self.b, dtype=float)), np.atleast_1d(np.asarray(self.a, dtype=float))
        if b.ndim != 1 or a.ndim != 1 or not (np.all(np.isfinite(b)) and np.all(np.isfinite(a))):
            raise ConfigError(f"b and a must be finite 1-D coefficient arrays, got {b.shape}, {a.shape}")
        if a[0] != 1.0:
            raise ConfigError(
                f"the denominator must be normalised to a[0] = 1 (Eq. (23)), got a[0] = {a[0]!r}"
            )
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "alpha", check_alpha(self.alpha))

    def response(self, f_hz: np.ndarray) -> np.ndarray:
        """Frequency response ``G(j 2 pi f)``; ``f_hz`` (...) Hz >= 0 -> (...) complex."""
        f = np.asarray(f_hz, dtype=float)
        S = s_power(f.reshape(-1), np.arange(max(self.b.size, self.a.size)) * self.alpha)
        return (S[:, : self.b.size] @ self.b / (S[:, : self.a.size] @ self.a)).reshape(f.shape)

    @property
    def dc_gain(self) -> float:
        """Low-frequency value ``G(0) = b_0``, in units of G."""
        return float(self.b[0])

    @property
    def is_stable(self) -> bool:
        """Matignon's condition: every root ``w`` of ``sum a_k w^k`` has ``|arg w| > alpha pi / 2``."""
        roots = np.roots(self.a[::-1]) if np.any(self.a[1:] != 0) else np.array([])
        return bool(np.all(np.abs(np.angle(roots)) > 0.5 * np.pi * self.alpha))

    def bandwidth_hz(self, f_max_hz: float = 1e3, n_grid: int = 4000) -> float:
        """-3 dB bandwidth: lowest frequency where ``|G|`` falls 3 dB below ``|G(0)|`` (Table II).

        A log grid from 1e-4 Hz to ``f_max_hz`` locates the first downward crossing (past any
        resonance peak) and Brent's method refines it to 1e-12 Hz.

        Args:
            f_max_hz: Hz, upper end of the search.
            n_grid: grid points.

        Returns:
            The bandwidth, Hz.
        """
        ref = abs(self.dc_gain)
        if ref == 0:
            raise EstimationError(
                "the bandwidth needs a nonzero low-frequency gain b_0; this model has b_0 = 0"
            )
        return bandwidth_hz(self.response, ref, f_max_hz, n_grid)


def third_order_tf(
    a3: float, a2: float, a1: float, b2: float, b1: float, b0: float, name: str = "", units: str = ""
) -> CommensurateTF:
    """Eq. (31): ``(b2 s² + b1 s + b0) / (a3 s³ + a2 s² + a1 s + 1)``, in Table II's column order."""
    return CommensurateTF(b=np.array([b0, b1, b2]), a=np.array([1.0, a1, a2, a3]), name=name, units=units)


# Table II of the fractional paper, "Parameters for model (31)", with the column scales undone
# (a3 x1e-7, a2 x1e-5, a1 x1e-2, b2 x1e-7, b1 x1e-6, b0 x1e-3). The paper does not state their
# units: the five-element models are hand displacement per hand force (m/N, s in s), model (30)
# elbow angle per hand force (rad/N); bandwidths are ratios and do not depend on them.
LITERATURE_MODELS: dict[str, CommensurateTF] = {
    # Diaz [4] of the fractional paper, Table II row 1.
    "Diaz": third_order_tf(7.19e-7, 225.4e-5, 7.01e-2, 6.093e-7, 22.32e-6, 10.42e-3, "Diaz"),
    # Speich [18], Table II row 2.
    "Speich": third_order_tf(2724e-7, 670.9e-5, 14.48e-2, 211e-7, 640.8e-6, 11.23e-3, "Speich"),
    # Vlugt [3], Table II row 3.
    "Vlugt": third_order_tf(304.4e-7, 316.9e-5, 6.28e-2, 1.71e-7, 19.58e-6, 1.431e-3, "Vlugt"),
    # Fu [6], Table II row 4.
    "Fu": third_order_tf(7.57e-7, 81.82e-5, 6.748e-2, 9.757e-7, 90.05e-6, 4.979e-3, "Fu"),
    # Tejado, model (30) = (28), alpha = 1.4, with Table II's digits (b0 = 3.751e-3, a1 = 1.032e-2;
    # Eq. (30) prints them rounded to 0.0037 and 0.0103).
    "Tejado": CommensurateTF(
        b=np.array([3.751e-3, 6.375e-6]),
        a=np.array([1.0, 1.032e-2, 3.121e-5]),
        alpha=1.4,
        name="Tejado (30)",
        units="rad/N",
    ),
}

#: Table II, column "BW (Hz)": published -3 dB bandwidths, Hz.
PUBLISHED_BANDWIDTH_HZ: dict[str, float] = {
    "Diaz": 3.11,
    "Speich": 2.79,
    "Vlugt": 3.83,
    "Fu": 2.80,
    "Tejado": 8.27,
}

# The models identified in Sec. IV-A of the fractional paper, angle per force, rad/N, as printed.
IDENTIFIED_MODELS: dict[str, CommensurateTF] = {
    # Eq. (27), integer, alpha = 1.
    "27": third_order_tf(8.75e-6, 7.81e-4, 0.034, 5.32e-7, 1.86e-5, 0.005, "(27)", "rad/N"),
    # Eq. (28), alpha = 1.4.
    "28": CommensurateTF(
        b=np.array([0.0037, 6.375e-6]),
        a=np.array([1.0, 0.0103, 3.121e-5]),
        alpha=1.4,
        name="(28)",
        units="rad/N",
    ),
    # Eq. (29), alpha = 1.1.
    "29": CommensurateTF(
        b=np.array([0.0035]), a=np.array([1.0, 0.0184, 3.296e-4]), alpha=1.1, name="(29)", units="rad/N"
    ),
}


@dataclass(frozen=True, kw_only=True)
class FiveElement:
    """Five-element arm model of Sec. IV-B: grasp (``k1, d1``) in series with arm (``M, k2, d2``).

    The hand displacement per hand force is ``1/(d1 s + k1) + 1/(M s² + d2 s + k2)``, which is
    Eq. (31) with the coefficients (32)-(37).

    Attributes:
        M: kg, arm mass.
        k1: N/m, grasp stiffness.
        k2: N/m, arm stiffness.
        d1: N·s/m, grasp damping.
        d2: N·s/m, arm damping.
    """

    M: float
    k1: float
    k2: float
    d1: float
    d2: float

    def __post_init__(self) -> None:
        for name in ("M", "k1", "k2", "d1", "d2"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"five-element parameter {name} must be a positive number, got {v!r}")

    def to_tf(self) -> CommensurateTF:
        """Eqs. (31)-(37): the third-order transfer function, m/N."""
        M, k1, k2, d1, d2 = self.M, self.k1, self.k2, self.d1, self.d2
        P = k1 * k2
        return third_order_tf(
            a3=d1 * M / P,
            a2=(d1 * d2 + k1 * M) / P,
            a1=(k1 * d2 + k2 * d1) / P,
            b2=M / P,
            b1=(d1 + d2) / P,
            b0=(k1 + k2) / P,
            name="five-element",
            units="m/N",
        )


@dataclass(frozen=True, kw_only=True)
class FiveElementFit:
    """Five-element parameters read out of a third-order model.

    Attributes:
        element: the parameters.
        mismatch: largest relative difference between the six given coefficients and those of
            :attr:`element` (Eq. (31) has 6 coefficients for 5 parameters); 0 for a consistent model.
    """

    element: FiveElement
    mismatch: float


def five_element_from_tf(tf: CommensurateTF) -> FiveElementFit:
    """Invert Eqs. (32)-(37): ``(M, k1, k2, d1, d2)`` from a third-order integer model.

    The grasp term ``1/(d1 s + k1)`` is the partial fraction of a real pole ``p = -k1/d1`` with
    residue ``1/d1``; what remains, ``L(s)/Q(s)``, is ``1/(M s² + d2 s + k2)`` when ``L`` is a
    constant. Every negative real pole is tried and the one whose parameters reproduce the given
    coefficients best is kept, so an identified (not exactly consistent) model gets the nearest
    five-element reading.

    Args:
        tf: integer (``alpha = 1``) model with at most 3 numerator and exactly 4 denominator
            coefficients (``a_3 != 0``), in m/N (multiply an angle-per-force model by the link
            length to get m/N).

    Returns:
        The :class:`FiveElementFit`.
    """
    if tf.alpha != 1.0 or tf.a.size != 4 or tf.a[3] == 0 or tf.b.size > 3:
        raise EstimationError(
            "five_element_from_tf needs an integer (alpha = 1) model with numerator order <= 2 and "
            f"denominator order 3; got alpha={tf.alpha:g}, m={tf.b.size - 1}, n={tf.a.size - 1}"
        )
    A = tf.a[::-1]  # descending powers of s
    B = np.pad(tf.b, (0, 3 - tf.b.size))[::-1]
    given = np.concatenate([np.pad(tf.b, (0, 3 - tf.b.size)), tf.a[1:]])
    best: FiveElementFit | None = None
    for p in np.roots(A):
        if abs(p.imag) > 1e-9 * abs(p) or p.real >= 0:
            continue
        p = float(p.real)
        Q = [float(q) for q in np.polydiv(A, [1.0, -p])[0]]  # a3 s² + q1 s + q0
        r = np.polyval(B, p) / np.polyval(Q, p)  # residue 1/d1
        L = np.polydiv(B - r * np.asarray(Q), [1.0, -p])[0]  # l1 s + l0; l1 = 0 when consistent
        if r <= 0 or L[-1] <= 0 or min(Q) <= 0:
            continue
        l0, r = float(L[-1]), float(r)
        el = FiveElement(M=Q[0] / l0, k1=-p / r, k2=Q[2] / l0, d1=1.0 / r, d2=Q[1] / l0)
        back = el.to_tf()
        coef = np.concatenate([back.b, back.a[1:]])
        with np.errstate(divide="ignore"):
            mismatch = float(np.max(np.abs(coef - given) / np.abs(given)))
        if best is None or mismatch < best.mismatch:
            best = FiveElementFit(element=el, mismatch=mismatch)
    if best is None:
        raise EstimationError(
            "no five-element reading: the model needs a negative real pole whose partial fraction "
            "leaves positive M, k1, k2, d1, d2"
        )
    return best

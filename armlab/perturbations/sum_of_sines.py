"""Joint references made of a sum of sinusoids (virtual-force-sensor paper, seeds/003).

Sec. II-C-1: "each of the robot's two joints was set to track a reference position comprising
the sum of ten sinusoids with frequencies from 0 to 2 Hz", moving each joint through 10° (40° for
the robot identification of the Appendix). Here the frequencies are evenly spaced up to the top of
the band, each joint gets its own random phases, and the sum is scaled so that its peak-to-peak
excursion over one period equals the range. A raised-cosine fade-in before t = 0 lets the
reference start from rest (that span is simulated but not recorded).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from armlab.errors import ConfigError

__all__ = ["SumOfSines", "sum_of_sines"]

_GRID_PER_PERIOD = 20000  # fewest samples of one period used to measure the peak-to-peak range
_GRID_PER_CYCLE = 1000  # fewest samples per cycle of the highest component (peak error < 5e-6)
_MAX_DENOMINATOR = 1000  # frequencies are read as fractions p/q Hz with q <= this


def _common_period(freqs_hz: np.ndarray) -> float:
    """s, the period of a sum of sines: 1 / gcd of the frequencies as fractions."""
    fr = [Fraction(float(f)).limit_denominator(_MAX_DENOMINATOR) for f in freqs_hz]
    den = math.lcm(*(f.denominator for f in fr))
    num = math.gcd(*(f.numerator * (den // f.denominator) for f in fr))
    return den / num


@dataclass(frozen=True, eq=False)
class SumOfSines:
    """``r_j(t) = w(t) sum_i a_j sin(2 pi f_i t + phi_ji)`` per joint ``j`` (rad).

    Attributes:
        freqs_hz: (n_sines,) Hz.
        amplitude: (n_joints,) rad, the common amplitude of each joint's components.
        phases: (n_joints, n_sines) rad.
        fade_s: s, raised-cosine fade-in over ``[-fade_s, 0]``; 0 = none (the sum starts at t = 0
            without fading, and is zero before).
    """

    freqs_hz: np.ndarray
    amplitude: np.ndarray
    phases: np.ndarray
    fade_s: float = 0.0

    def _fade(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.fade_s <= 0:
            w = (t >= 0).astype(float)
            return w, np.zeros_like(t)
        u = np.clip((t + self.fade_s) / self.fade_s, 0.0, 1.0)
        w = 0.5 - 0.5 * np.cos(np.pi * u)
        inside = (u > 0) & (u < 1)
        dw = np.where(inside, 0.5 * np.pi / self.fade_s * np.sin(np.pi * u), 0.0)
        return w, dw

    def _parts(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        omega = 2 * np.pi * self.freqs_hz
        arg = omega * t[:, None, None] + self.phases[None]  # (n, joints, sines)
        s = self.amplitude[None, :] * np.sin(arg).sum(-1)
        ds = self.amplitude[None, :] * (omega * np.cos(arg)).sum(-1)
        return s, ds

    def value(self, t: np.ndarray) -> np.ndarray:
        """(n, n_joints) rad at times ``t`` (n,) s."""
        return self.value_and_derivative(t)[0]

    def derivative(self, t: np.ndarray) -> np.ndarray:
        """(n, n_joints) rad/s at times ``t`` (n,) s."""
        return self.value_and_derivative(t)[1]

    def value_and_derivative(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Both (n, n_joints), rad and rad/s, at times ``t`` (n,) s, from one evaluation of the
        sines (a servo's feed-forward needs both: half the work of two calls)."""
        t = np.asarray(t, float)
        w, dw = self._fade(t)
        s, ds = self._parts(t)
        return w[:, None] * s, dw[:, None] * s + w[:, None] * ds


def sum_of_sines(
    rng: np.random.Generator,
    *,
    n_sines: int,
    band_hz: tuple[float, float],
    range_rad: float,
    n_joints: int = 2,
    fade_s: float = 0.0,
) -> SumOfSines:
    """Draw one reference (module docstring).

    Args:
        rng: source of the phases.
        n_sines: number of components, at ``linspace(band_hz[0], band_hz[1], n_sines)``.
        band_hz: (lowest, highest) component frequency, Hz.
        range_rad: peak-to-peak excursion of each joint, rad.
        n_joints: independent references drawn.
        fade_s: raised-cosine fade-in before t = 0, s.

    Raises:
        ConfigError: a bad count, band or range.
    """
    lo, hi = (float(b) for b in band_hz)
    if not (isinstance(n_sines, int) and n_sines >= 1):
        raise ConfigError(f"n_sines must be an integer >= 1, got {n_sines!r}")
    if not (0 < lo <= hi and math.isfinite(hi)):
        raise ConfigError(f"band_hz must be (low, high) Hz with 0 < low <= high, got {band_hz!r}")
    if not (range_rad > 0 and math.isfinite(range_rad)):
        raise ConfigError(f"range_rad must be a finite angle > 0 rad, got {range_rad!r}")
    freqs = np.linspace(lo, hi, n_sines)
    phases = rng.uniform(0.0, 2 * np.pi, size=(n_joints, n_sines))
    unit = SumOfSines(freqs, np.ones(n_joints), phases)
    # the sum repeats with the common period of its frequencies, 1 / gcd(f_i) (frequencies read as
    # fractions of at most _MAX_DENOMINATOR); measure its range over one period, with at least
    # _GRID_PER_CYCLE samples per cycle of the highest component
    period = _common_period(freqs)
    t = np.linspace(0.0, period, max(_GRID_PER_PERIOD, int(_GRID_PER_CYCLE * hi * period)), endpoint=False)
    v = unit.value(t)
    ptp = v.max(axis=0) - v.min(axis=0)
    return SumOfSines(freqs, range_rad / ptp, phases, fade_s)

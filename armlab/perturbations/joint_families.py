"""Position-perturbation families of the second (ODE) joint referee: steps, multisine, PRBS.

Each family returns a smooth reference angle sampled at ``fs_hz`` that starts and ends at rest at
0 rad (a raised-cosine fade of ``_FADE_S`` at each end), so a servo started at rest follows it
without a start-up transient. They differ from the first referee's PRBS
(:func:`armlab.perturbations.prbs.prbs_position`: ±0.025 rad, 0.125 s switching interval, 45 Hz
critically damped smoothing) in spectrum and amplitude distribution:

- ``steps``: smoothed random steps: levels uniform in [-A, A], held for exponentially distributed
  times (mean ``hold_s``), each transition a raised cosine of ``ramp_s`` (a half-cosine of
  duration T has its energy below ~1/T Hz);
- ``multisine``: a sum of cosines on the record's frequency grid between 0.2 Hz and ``fmax_hz``,
  equal amplitudes, Schroeder phases (Schroeder 1970, IEEE Trans. Inf. Theory 16:85: the low
  crest factor), scaled to peak A;
- ``prbs``: a PRBS of switching interval ``switch_s`` (other rates than the first referee's), the
  ±A square wave smoothed by the same raised-cosine transitions.

Amplitudes: the REKLAB ankle pulses reach ~0.022 rad (``prbs.py``); the referee draws A over
0.015-0.05 rad around it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.errors import ConfigError

__all__ = [
    "PERTURBATION_FAMILIES",
    "JointPerturbation",
    "perturbation_signal",
]

PERTURBATION_FAMILIES = ("steps", "multisine", "prbs")
_FADE_S = 0.5  # s, raised-cosine fade-in and fade-out at the record's ends


@dataclass(frozen=True, kw_only=True)
class JointPerturbation:
    """One family's parameters (all finite, > 0 except the family name).

    Attributes:
        family: ``steps``, ``multisine`` or ``prbs``.
        amplitude_rad: rad, A (the largest level; the multisine's peak).
        hold_s: s, mean hold time between steps (``steps``).
        ramp_s: s, duration of each raised-cosine transition (``steps``, ``prbs``).
        fmax_hz: Hz, highest multisine component (``multisine``).
        switch_s: s, PRBS switching interval (``prbs``).
    """

    family: Literal["steps", "multisine", "prbs"]
    amplitude_rad: float
    hold_s: float = 0.4
    ramp_s: float = 0.03
    fmax_hz: float = 20.0
    switch_s: float = 0.2

    def __post_init__(self) -> None:
        if self.family not in PERTURBATION_FAMILIES:
            valid = list(PERTURBATION_FAMILIES)
            raise ConfigError(f"perturbation family {self.family!r} unknown; valid: {valid}")
        for name in ("amplitude_rad", "hold_s", "ramp_s", "fmax_hz", "switch_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"perturbation {name} must be finite and > 0, got {v!r}")


def _cos_steps(times: np.ndarray, levels: np.ndarray, ramp_s: float, t: np.ndarray) -> np.ndarray:
    """Piecewise-constant levels (levels[k] from times[k]) joined by raised-cosine ramps of ramp_s."""
    x = np.full_like(t, levels[0])
    for t0, jump in zip(times[1:], np.diff(levels), strict=True):  # one vectorised pass per step
        u = np.clip((t - t0) / ramp_s, 0.0, 1.0)
        x += jump * 0.5 * (1.0 - np.cos(np.pi * u))
    return x


def perturbation_signal(p: JointPerturbation, n: int, fs_hz: float, rng: np.random.Generator) -> np.ndarray:
    """Sample one reference of family ``p.family``: (n,) rad at ``fs_hz``, 0 with zero slope at both ends.

    Randomness (levels, hold times, switch signs) comes only from ``rng``; the multisine draws none
    (Schroeder phases are deterministic).
    """
    t = np.arange(n) / fs_hz
    dur = n / fs_hz
    if dur <= 4 * _FADE_S:
        raise ConfigError(f"a perturbation needs more than {4 * _FADE_S:g} s, got {dur:g} s")
    a = p.amplitude_rad
    if p.family == "multisine":
        df = 1.0 / dur
        k = np.arange(max(1, int(np.ceil(0.2 / df))), int(p.fmax_hz / df) + 1)
        m = k.size
        phase = -np.pi * np.arange(1, m + 1) * np.arange(m) / m  # Schroeder 1970, Eq. (11)
        spectrum = np.zeros(n // 2 + 1, dtype=complex)
        spectrum[k[k < spectrum.size]] = np.exp(1j * phase[k < spectrum.size])
        x = np.fft.irfft(spectrum, n)  # the cosines on the record's grid, summed exactly
        x *= a / np.max(np.abs(x))
    elif p.family == "steps":
        n_max = int(3 * dur / p.hold_s) + 3
        times = np.concatenate([[0.0], np.cumsum(rng.exponential(p.hold_s, n_max))])
        times = times[times < dur]
        levels = rng.uniform(-a, a, times.size)
        x = _cos_steps(times, levels, p.ramp_s, t)
    else:
        times = np.arange(0.0, dur, p.switch_s)
        levels = a * rng.choice([-1.0, 1.0], times.size)
        keep = np.concatenate([[True], np.diff(levels) != 0])  # only the switches are transitions
        x = _cos_steps(times[keep], levels[keep], p.ramp_s, t)
    fade = np.ones(n)
    nf = int(round(_FADE_S * fs_hz))
    ramp = 0.5 * (1.0 - np.cos(np.pi * np.arange(nf) / nf))
    fade[:nf], fade[n - nf :] = ramp, ramp[::-1]
    return x * fade

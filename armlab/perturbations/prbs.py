"""REKLAB-style pseudo-random binary position perturbations for the 1-DoF joint protocol.

The classic stochastic perturbation of ankle-stiffness studies (Kearney & Hunter 1990; the
REKLAB recordings in ``shared/data/reklab_ankle``): the actuator jumps between two positions
about the operating angle at random multiples of a switching interval, each jump smoothed by the
actuator's own bandwidth, so the signal is broad-band but its amplitude is bounded.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from armlab.errors import ConfigError

__all__ = [
    "prbs_position",
]


def _positive(name: str, value: float) -> None:
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0):
        raise ConfigError(f"prbs_position: {name} must be a finite number > 0, got {value!r}")


def prbs_position(
    n_samples: int,
    fs_hz: float,
    *,
    amplitude_rad: float = 0.025,
    switch_interval_s: float = 0.125,
    smooth_hz: float = 45.0,
    rng: np.random.Generator,
) -> np.ndarray:
    """A smoothed pseudo-random binary position sequence: (n_samples,) rad.

    Construction: the level ±amplitude_rad is held for ``switch_interval_s`` and at the end of
    each interval switches with probability 1/2 (i.e. each interval's sign is a fair coin, drawn
    from ``rng``; the mean time between switches is 2·switch_interval_s); the square wave passes
    a critically damped 2nd-order low-pass (two real poles at ``smooth_hz``, unit DC gain, no
    overshoot, so ``|x| <= amplitude_rad``; causal, started at the first level) standing for the
    actuator's bandwidth; a raised-cosine fade of one switching interval at each end makes the
    sequence start and end at exactly 0 with zero slope.

    Defaults matched to the REKLAB recording ``z_df.csv`` (60 s at 1 kHz; z_pf, z_df2 agree):

    - amplitude: its pulses reach 0.022 ± 0.004 rad (max 0.028 rad) from the operating angle,
      so ±0.025 rad spans the same range;
    - switching rate: it switches every 0.20–0.30 s (mean 0.25 s, 4 switches/s); a switching
      interval of 0.125 s with switch probability 1/2 gives the same 4 switches/s on average;
    - transition shape: its jumps rise 10–90 % in 12 ms with 1.7 % overshoot, which a
      critically damped 2nd-order low-pass at 45 Hz reproduces (10–90 % rise 3.36/ωn = 12 ms).

    What differs: the REKLAB sequence returns to the operating angle between pulses of random
    sign (levels 0 and ±0.022 rad), this one is binary, so its jumps are 2·amplitude and its rms
    is ~amplitude (0.025 rad; z_df: 0.015 rad).

    Args:
        n_samples: samples (an int > 2·switch_interval_s·fs_hz, room for both fades).
        fs_hz: Hz, sample rate.
        amplitude_rad: rad, the two levels are ±amplitude_rad.
        switch_interval_s: s, the clock of the switches (at least one sample).
        smooth_hz: Hz, the poles of the smoothing low-pass (below Nyquist).
        rng: the only source of randomness: one ``rng.integers`` call for the signs.

    Returns:
        (n_samples,) rad, starting and ending at 0.

    Raises:
        ConfigError: a non-positive or non-finite argument, smooth_hz not below Nyquist, an
            interval under one sample, or a record too short for the two fades.
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)):
        raise ConfigError(f"prbs_position: n_samples must be an int, got {n_samples!r}")
    for name, value in (
        ("fs_hz", fs_hz),
        ("amplitude_rad", amplitude_rad),
        ("switch_interval_s", switch_interval_s),
        ("smooth_hz", smooth_hz),
    ):
        _positive(name, value)
    if not smooth_hz < fs_hz / 2:
        raise ConfigError(f"prbs_position: smooth_hz = {smooth_hz} Hz must be below Nyquist ({fs_hz / 2} Hz)")
    interval = switch_interval_s * fs_hz  # samples per switching interval (may be fractional)
    if interval < 1:
        raise ConfigError(
            f"prbs_position: switch_interval_s = {switch_interval_s} s is under one sample at {fs_hz} Hz"
        )
    n_fade = int(round(interval))
    if n_samples <= 2 * n_fade:
        raise ConfigError(
            f"prbs_position: n_samples = {n_samples} leaves no room for the two fades of "
            f"{n_fade} samples each; need n_samples > {2 * n_fade}"
        )
    idx = np.floor(np.arange(n_samples) / interval).astype(int)
    signs = 2 * rng.integers(0, 2, size=idx[-1] + 1) - 1
    square = amplitude_rad * signs[idx].astype(float)
    # two real poles at smooth_hz (matched z-transform, exact DC gain 1): no overshoot
    p = math.exp(-2 * math.pi * smooth_hz / fs_hz)
    b, a = np.array([(1 - p) ** 2]), np.array([1.0, -2 * p, p * p])
    x = signal.lfilter(b, a, square, zi=signal.lfilter_zi(b, a) * square[0])[0]
    fade = 0.5 - 0.5 * np.cos(np.pi * np.arange(n_fade) / n_fade)  # 0 -> 1, raised cosine
    window = np.ones(n_samples)
    window[:n_fade] = fade
    window[n_samples - n_fade :] = fade[::-1]
    window[-1] = 0.0
    return x * window

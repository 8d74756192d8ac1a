"""Multi-segment fifth-order waveforms: the designed excitation's shape (issue 23).

A waveform is a chain of the conditioning paper's point-to-point quintics, Eq. (16): it starts at
0, passes through ``knots`` (normalised, |w| <= 1) at equal segment times, with zero velocity and
acceleration at every knot, and holds the last knot after ``T``. Because each segment is monotone
between its knots, |w(t)| <= max |knots| everywhere, so a direction of per-joint amplitude A never
displaces a joint by more than A (the paper's 0.05 rad bound, section IV-B, holds by construction).
The waveform may run over only a ``fraction`` of the duration it is given and hold after: the
paper's own quintic with its 70 ms of hold (T_obs = T_k + 70 ms) is the one-segment waveform
``knots = (1,)``, ``fraction = T_k / T_obs``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.perturbations.quintic import quintic_profile

__all__ = [
    "QUINTIC_PEAK_ACC",
    "QUINTIC_PEAK_VEL",
    "SegmentWaveform",
]

#: Peak |s'| of Eq. (16) on a unit step over unit time: 30 tau^2 (1 - tau)^2 at tau = 1/2.
QUINTIC_PEAK_VEL = 1.875
#: Peak |s''| of Eq. (16) on a unit step over unit time: 60 tau (1 - tau)(1 - 2 tau) at
#: tau = 1/2 -+ sqrt(3)/6, i.e. 10 / sqrt(3).
QUINTIC_PEAK_ACC = 10.0 / np.sqrt(3.0)


@dataclass(frozen=True, kw_only=True)
class SegmentWaveform:
    """A chain of quintic segments through normalised knots over a duration scaled per trial.

    Attributes:
        knots: (m,) values reached at the ends of the m equal segments (the start is 0), each in
            [-1, 1]; the last one is held after the waveform ends.
        fraction: the part of the given duration the segments fill, in (0, 1]; then the hold.
    """

    knots: tuple[float, ...]
    fraction: float = 1.0

    def __post_init__(self) -> None:
        k = np.asarray(self.knots, float)
        if k.ndim != 1 or k.size == 0 or not np.all(np.isfinite(k)) or np.any(np.abs(k) > 1.0):
            raise ConfigError(
                f"waveform knots must be 1 to n finite values in [-1, 1] (normalised displacement), "
                f"got {self.knots!r}"
            )
        if not (np.isfinite(self.fraction) and 0 < self.fraction <= 1):
            raise ConfigError(
                f"waveform fraction must lie in (0, 1] (of the duration), got {self.fraction!r}"
            )

    @property
    def s_range(self) -> tuple[float, float]:
        """The range of w(t) (it includes 0, the start): the path a direction needs solved."""
        k = np.asarray(self.knots, float)
        return float(min(0.0, k.min())), float(max(0.0, k.max()))

    def evaluate(self, t: np.ndarray, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """w, w', w'' at times ``t`` (s from the onset) for a waveform lasting ``duration`` s.

        Each segment is Eq. (16) of the conditioning paper from one knot to the next over
        ``fraction * duration / m``; before 0 the waveform is 0, after ``fraction * duration`` the
        last knot.

        Returns:
            ``(w, wd, wdd)`` shaped like ``t``: 1, 1/s, 1/s².
        """
        if not (np.isfinite(duration) and duration > 0):
            raise ConfigError(f"duration must be a positive finite number of seconds, got {duration!r}")
        t = np.asarray(t, float)
        knots = np.asarray(self.knots, float)
        steps = np.diff(np.concatenate([[0.0], knots]))  # (m,)
        seg = self.fraction * duration / knots.size
        starts = np.arange(knots.size) * seg
        # every segment's quintic is held at 0 before and 1 after it: their weighted sum is w
        s, sd, sdd = quintic_profile(t[..., None] - starts, seg)
        return s @ steps, sd @ steps, sdd @ steps

    def peaks(self, duration: float) -> tuple[float, float]:
        """Peak |w'| (1/s) and |w''| (1/s²) over the waveform, exactly (segments do not overlap)."""
        seg = self.fraction * duration / len(self.knots)
        step = float(np.max(np.abs(np.diff(np.concatenate([[0.0], self.knots])))))
        return QUINTIC_PEAK_VEL * step / seg, QUINTIC_PEAK_ACC * step / seg**2

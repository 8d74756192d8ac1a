"""Triangular and trapezoidal position perturbations of paper 002 (thesis §3.1.1, Fig. 3.1.2).

Both are piecewise-constant *velocity* profiles, so the displacement is piecewise linear:

- triangular: 0.008 m peak over 0.4 s, i.e. +0.04 m/s for 0.2 s then −0.04 m/s for 0.2 s;
- trapezoidal: +0.14 m/s for 0.05 s (7 mm), 0 m/s for 0.2 s, −0.07 m/s for 0.1 s (back to 0).

The thesis's waveforms have velocity steps, i.e. infinite acceleration at the corners: harmless in
its inertia-free model, not on a real robot. ``corner_s > 0`` replaces every velocity step by a
quintic smoothstep (``10u³ − 15u⁴ + 6u⁵``) centred on the corner and lasting ``corner_s``; the
blend is symmetric about each corner, so the net displacement stays zero and the plateau values
are kept; the waveform then starts ``corner_s/2`` earlier and is shifted by that amount so that it
still starts at t = 0 and lasts ``duration + corner_s``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.errors import ConfigError
from armlab.perturbations.quintic import quintic_profile

__all__ = [
    "MIN_SAMPLES_PER_SEGMENT",
    "Shape",
    "RampWaveform",
    "TRIANGULAR",
    "TRAPEZOIDAL",
    "ramp_waveform",
]

Shape = Literal["triangular", "trapezoidal"]
#: fewest samples per constant-velocity segment a sampled waveform accepts (so each ramp's
#: velocity is resolved; the thesis's 50 ms trapezoid ramp at 1 kHz has 50)
MIN_SAMPLES_PER_SEGMENT = 10
_SHAPES = ("triangular", "trapezoidal")


@dataclass(frozen=True, kw_only=True)
class RampWaveform:
    """A 1-D displacement made of constant-velocity segments, optionally with blended corners.

    Attributes:
        velocities: (n,) m/s, the velocity of each segment.
        durations: (n,) s, the length of each segment (> 0).
        corner_s: s, width of the quintic blend at each velocity change (0: sharp corners, the
            thesis); at most the shortest segment.
        name: label for reports.
    """

    velocities: tuple[float, ...]
    durations: tuple[float, ...]
    corner_s: float = 0.0
    name: str = "ramp"

    def __post_init__(self) -> None:
        v, d = np.asarray(self.velocities, float), np.asarray(self.durations, float)
        if v.ndim != 1 or v.shape != d.shape or v.size == 0:
            raise ConfigError(f"velocities and durations must be equal-length 1-D, got {v.shape}, {d.shape}")
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(d)) and np.all(d > 0)):
            raise ConfigError(
                f"segment velocities must be finite and durations positive, got {self.durations!r}"
            )
        if not (np.isfinite(self.corner_s) and 0 <= self.corner_s <= d.min()):
            raise ConfigError(
                f"corner_s must lie in [0, {d.min():g}] s (the shortest segment), got {self.corner_s!r}"
            )

    @property
    def duration(self) -> float:
        """s, total length including the corner blends."""
        return float(np.sum(self.durations)) + self.corner_s

    @property
    def peak(self) -> float:
        """m, the largest absolute displacement."""
        edges = np.concatenate([[0.0], np.cumsum(np.multiply(self.velocities, self.durations))])
        return float(np.max(np.abs(edges)))

    @property
    def net_displacement(self) -> float:
        """m, displacement at the end (0 for both thesis waveforms)."""
        return float(np.dot(self.velocities, self.durations))

    @property
    def min_fs_hz(self) -> float:
        """Hz, the lowest rate :meth:`sample` accepts: ``MIN_SAMPLES_PER_SEGMENT`` per shortest segment."""
        return MIN_SAMPLES_PER_SEGMENT / min(self.durations)

    def smoothed(self, corner_s: float) -> RampWaveform:
        """The same segments with corners blended over ``corner_s`` seconds."""
        return RampWaveform(
            velocities=self.velocities, durations=self.durations, corner_s=corner_s, name=self.name
        )

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement, velocity and acceleration at times ``t`` from the waveform's start.

        The velocity is ``Σ_i Δv_i·S((t − t_i)/c + ½)`` over the corners ``t_i`` (including the
        start and the end), with ``S`` a unit step (c = 0) or the quintic smoothstep; the
        displacement is its exact integral. Outside ``[0, duration]`` the velocity is 0 and the
        displacement holds its end value.

        Args:
            t: (...) s.

        Returns:
            ``(p, v, a)`` shaped like ``t``: m, m/s, m/s² (``a`` is 0 away from blended corners and
            undefined, reported as 0, at sharp ones).
        """
        t = np.asarray(t, dtype=float)
        v_seg = np.asarray(self.velocities, float)
        dv = np.diff(np.concatenate([[0.0], v_seg, [0.0]]))  # (n + 1,) velocity jumps at each corner
        c = self.corner_s
        corners = np.concatenate([[0.0], np.cumsum(self.durations)]) + c / 2  # shifted: starts at t = 0
        tt = t[..., None] - corners  # (..., n + 1) time since each corner's centre
        if c == 0.0:
            step = (tt >= 0).astype(float)
            ramp = np.maximum(tt, 0.0)
            bump = np.zeros_like(tt)
        else:
            # the blend S and its rate: the quintic point-to-point profile over c, from tt = −c/2
            step, bump, _ = quintic_profile(tt + c / 2, c)
            u = np.clip(tt / c + 0.5, 0.0, 1.0)
            # ∫ S over time: c·(2.5u⁴ − 3u⁵ + u⁶) inside the blend, then c/2 + (t − t_i − c/2) after it
            inside = c * u**4 * (2.5 - 3 * u + u * u)
            ramp = np.where(tt > c / 2, tt, inside)
        p = ramp @ dv
        v = step @ dv
        a = bump @ dv
        return p, v, a

    def sample(self, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The waveform sampled at ``fs`` from t = 0 for ``round(duration·fs)`` samples.

        Args:
            fs: Hz, sample rate (>= :attr:`min_fs_hz`).

        Returns:
            ``(t, p, v)``: (n,) s, (n,) m, (n,) m/s. For the thesis's 0.4 s triangle at 1 kHz,
            n = 400 (t = 0 … 0.399 s).
        """
        if not (np.isfinite(fs) and fs > 0):
            raise ConfigError(f"fs must be a positive sample rate in Hz, got {fs!r}")
        if fs < self.min_fs_hz:
            raise ConfigError(
                f"fs = {fs:g} Hz gives fewer than {MIN_SAMPLES_PER_SEGMENT} samples in the shortest segment "
                f"({min(self.durations):g} s); use fs >= {self.min_fs_hz:g} Hz"
            )
        t = np.arange(int(round(self.duration * fs))) / fs
        p, v, _ = self.evaluate(t)
        return t, p, v


#: Thesis §3.1.1: amplitude 0.008 m, duration 0.4 s (symmetric, ±0.04 m/s).
TRIANGULAR = RampWaveform(velocities=(0.04, -0.04), durations=(0.2, 0.2), name="triangular")
#: Thesis §3.1.1: +0.14 m/s for 0.05 s, 0 for 0.2 s, −0.07 m/s for 0.1 s (peak 7 mm, 0.35 s).
TRAPEZOIDAL = RampWaveform(velocities=(0.14, 0.0, -0.07), durations=(0.05, 0.2, 0.1), name="trapezoidal")


def ramp_waveform(shape: Shape, corner_s: float = 0.0) -> RampWaveform:
    """The thesis waveform named ``shape`` (§3.1.1), with corners blended over ``corner_s`` s.

    Raises:
        ConfigError: for an unknown shape (valid: ``triangular``, ``trapezoidal``).
    """
    if shape not in _SHAPES:
        raise ConfigError(f"unknown perturbation shape {shape!r}; valid: {', '.join(_SHAPES)}")
    base = TRIANGULAR if shape == "triangular" else TRAPEZOIDAL
    return base.smoothed(corner_s) if corner_s else base

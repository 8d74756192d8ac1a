"""One 1-DoF joint trial as imported, and the checks every source applies to it.

Shared by the CSV reader (:mod:`armlab.data.joint_import`) and the ``.mat`` reader
(:mod:`armlab.data.mat_import`); layouts and errors: ``docs/data_import.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armlab.errors import DataError

__all__ = [
    "JointRecord",
]

# A sampling interval may deviate from the median interval by _UNIFORM_RTOL * step + _UNIFORM_ATOL_S:
# files that print time with 1 ms resolution leave ~1e-12 s of parsing error; 1e-6 is a gap.
_UNIFORM_RTOL = 1e-6
_UNIFORM_ATOL_S = 1e-9
# Sample rates of the files of one folder must agree to this relative tolerance.
_RATE_RTOL = 1e-6


@dataclass(frozen=True, kw_only=True, eq=False)
class JointRecord:
    """One 1-DoF joint-perturbation trial: position imposed by the actuator, torque measured.

    Attributes:
        name: the file stem, or ``"<stem>/<variable>"`` for a ``.mat`` holding several trials.
        t_s: (n,) s, sample times as recorded (starting at the first sample's time).
        position: (n,) rad, joint angle imposed by the actuator (the input); for a time-varying
            trial the perturbation about :attr:`operating_point`.
        torque: (n,) N·m, measured joint torque (the output), sign as recorded.
        fs_hz: Hz, sample rate, ``(n - 1) / (t_s[-1] - t_s[0])`` (``1 / domainIncr`` for nldat).
        path: the file read.
        operating_point: (n,) rad, slow joint angle about which a time-varying trial is perturbed
            (``ankle_position_rad``, the nldat scheduling variable); None for stationary trials.
    """

    name: str
    t_s: np.ndarray
    position: np.ndarray
    torque: np.ndarray
    fs_hz: float
    path: Path
    operating_point: np.ndarray | None = None

    def __post_init__(self) -> None:
        arrays = {"t_s": self.t_s, "position": self.position, "torque": self.torque}
        if self.operating_point is not None:
            arrays["operating_point"] = self.operating_point
        shapes = {k: np.shape(v) for k, v in arrays.items()}
        if len(set(shapes.values())) != 1 or len(shapes["t_s"]) != 1:
            raise DataError(f"JointRecord {self.name!r}: arrays must be 1-D of one length, got {shapes}")
        if not (math.isfinite(self.fs_hz) and self.fs_hz > 0):
            raise DataError(
                f"JointRecord {self.name!r}: fs_hz must be a finite rate > 0 Hz, got {self.fs_hz}"
            )

    @property
    def n_samples(self) -> int:
        """Number of samples n."""
        return int(self.t_s.size)

    @property
    def duration_s(self) -> float:
        """s, ``n_samples / fs_hz``."""
        return self.n_samples / self.fs_hz


def _check_samples(where: str, t: np.ndarray, signals: dict[str, np.ndarray], unit: str = "row") -> float:
    """Validate one trial and return its sample rate in Hz.

    Args:
        where: prefix of every message (the file, and the variable for ``.mat``).
        t: (n,) s, sample times.
        signals: name -> (n,) values, checked finite with ``t``.
        unit: what a sample is called in messages (``"row"``: data rows of a CSV, counted from 1
            below the header; ``"sample"``: samples of a ``.mat`` variable, counted from 1).
    """
    n = t.size
    if n == 0:
        raise DataError(f"{where}: has no data {unit}s; a trial needs at least 2 (time must define a rate)")
    if n == 1:
        raise DataError(f"{where}: has 1 data {unit}; a trial needs at least 2 to define a sample rate")
    columns = {"t_s": t, **signals}
    stacked = np.column_stack(list(columns.values()))
    bad = ~np.isfinite(stacked)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise DataError(
            f"{where}: {int(bad.sum())} NaN or inf value(s); the first in column "
            f"{list(columns)[col]!r} at {unit} {row + 1} (values must be finite numbers)"
        )
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        raise DataError(
            f"{where}: time is not strictly increasing at {unit} {i + 2}: t_s = {t[i + 1]:.9g} s after "
            f"{t[i]:.9g} s at {unit} {i + 1} (each time must exceed the one before)"
        )
    step = float(np.median(dt))
    tol = _UNIFORM_RTOL * step + _UNIFORM_ATOL_S
    off = np.abs(dt - step) > tol
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise DataError(
            f"{where}: non-uniform sampling: the interval {dt[i]:.9g} s between {unit}s {i + 1} and "
            f"{i + 2} differs from the median interval {step:.9g} s by more than {tol:.3g} s (time must "
            f"increase by a constant step; tolerance {_UNIFORM_RTOL:g} x step + {_UNIFORM_ATOL_S:g} s)"
        )
    return (n - 1) / float(t[-1] - t[0])

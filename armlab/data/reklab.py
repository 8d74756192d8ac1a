"""Importer for the real ankle recordings of the REKLAB (McGill) public data set.

The files live outside the repository, in ``shared/data/reklab_ankle/`` next to it (see that
folder's README): CSV with header ``t_s,position_rad,torque_Nm`` sampled at 1 kHz, one file per
trial (``z_df*`` dorsiflexor and ``z_pf*`` plantarflexor contractions under stochastic position
perturbation); ``tv_pilot.csv`` has ``t_s,position_perturbation_rad,torque_perturbation_Nm,
ankle_position_rad`` (perturbation about a slowly moving operating point).

Signs are as recorded. In the stationary trials the torque is in antiphase with the position at
low frequency (the torque/position phase is near ±180 deg below ~2 Hz), so an impedance
``I s² + B s + K`` with positive parameters is ``-torque / position``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armlab.errors import DataError

__all__ = [
    "DEFAULT_REKLAB_ROOT",
    "AnkleTrial",
    "list_ankle_trials",
    "load_ankle_trial",
]

#: ``<repo>/../shared/data/reklab_ankle``, anchored on this file (not the working directory).
DEFAULT_REKLAB_ROOT: Path = Path(__file__).resolve().parents[3] / "shared" / "data" / "reklab_ankle"

_STATIONARY = ("t_s", "position_rad", "torque_Nm")
_TIME_VARYING = ("t_s", "position_perturbation_rad", "torque_perturbation_Nm", "ankle_position_rad")
# Largest relative deviation of a sampling interval from the median interval: the files print
# time with 1 ms resolution, so float parsing leaves ~1e-12 s; anything near 1e-6 is a gap.
_UNIFORM_RTOL = 1e-6


@dataclass(frozen=True, kw_only=True, eq=False)
class AnkleTrial:
    """One ankle recording.

    Attributes:
        t_s: (n,) s, time from the start of the record.
        position: (n,) rad, ankle angle (perturbation, for ``tv_pilot``).
        torque: (n,) N·m, ankle torque as recorded (perturbation part, for ``tv_pilot``).
        fs_hz: Hz, sample rate (1 kHz for the REKLAB files).
        name: trial name, the file stem (e.g. ``"z_df"``).
        path: the file read.
        operating_point: (n,) rad, slow ankle angle about which ``tv_pilot`` is perturbed; None
            for the stationary trials.
    """

    t_s: np.ndarray
    position: np.ndarray
    torque: np.ndarray
    fs_hz: float
    name: str
    path: Path
    operating_point: np.ndarray | None = None

    @property
    def n_samples(self) -> int:
        return int(self.t_s.size)

    @property
    def duration_s(self) -> float:
        """s, ``n_samples / fs_hz``."""
        return self.n_samples / self.fs_hz


def list_ankle_trials(root: Path | str = DEFAULT_REKLAB_ROOT) -> tuple[str, ...]:
    """Names (file stems) of the CSV trials in ``root``, sorted; empty if ``root`` is absent."""
    root = Path(root)
    if not root.is_dir():
        return ()
    return tuple(sorted(p.stem for p in root.glob("*.csv")))


def load_ankle_trial(name: str, root: Path | str = DEFAULT_REKLAB_ROOT) -> AnkleTrial:
    """Read one trial, e.g. ``load_ankle_trial("z_df")``.

    Args:
        name: file stem, one of :func:`list_ankle_trials`.
        root: folder of the CSV files.

    Returns:
        The :class:`AnkleTrial`.
    """
    path = Path(root) / f"{name}.csv"
    if not path.is_file():
        have = list_ankle_trials(root)
        raise DataError(f"no ankle trial {name!r}: {path} does not exist; available: {list(have) or 'none'}")
    with path.open() as fh:
        header = tuple(h.strip() for h in fh.readline().split(","))
    expected = _TIME_VARYING if "ankle_position_rad" in header else _STATIONARY
    missing = [c for c in expected if c not in header]
    if missing:
        raise DataError(
            f"{path.name}: missing column(s) {missing}; expected {list(expected)}, got {list(header)}"
        )
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as err:
        raise DataError(f"{path.name}: could not parse the numbers: {err}") from None
    if data.shape[1] != len(header) or data.shape[0] < 2:
        raise DataError(f"{path.name}: expected >= 2 rows of {len(header)} columns, got shape {data.shape}")
    if not np.all(np.isfinite(data)):
        raise DataError(f"{path.name}: {int(np.sum(~np.isfinite(data)))} non-finite value(s)")
    col = {h: data[:, i] for i, h in enumerate(header)}
    t = col["t_s"]
    dt = np.diff(t)
    step = float(np.median(dt))
    if step <= 0 or np.max(np.abs(dt - step)) > _UNIFORM_RTOL * step + 1e-9:
        bad = int(np.argmax(np.abs(dt - step)))
        raise DataError(
            f"{path.name}: non-uniform sampling; interval {dt[bad]:g} s at row {bad + 1} differs from "
            f"the median {step:g} s (time must increase by a constant step)"
        )
    tv = expected is _TIME_VARYING
    return AnkleTrial(
        t_s=t,
        position=col[expected[1]],
        torque=col[expected[2]],
        fs_hz=(t.size - 1) / float(t[-1] - t[0]),
        name=name,
        path=path,
        operating_point=col["ankle_position_rad"] if tv else None,
    )

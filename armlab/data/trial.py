"""The trial container: every recorded channel of every trial of one run.

This is the contract between simulation (or a real lab's importer) and estimation. All trials of
a set share one sample rate and one record length; each trial has its own perturbation onset.

Channel arrays have shape ``(n_trials, n_samples, n_axes)``. Channel names used by the
conditioning-window protocol (units in :attr:`TrialSet.units`):

- ``hand_pos`` (2) m: hand position in the arm's shoulder frame (x lateral, y anterior),
  computed from the robot's encoders by forward kinematics — what the estimator reads.
- ``hand_force`` (2) N: force the robot applies *on the hand*, shoulder frame (from the F/T
  sensor rotated by the flange orientation from the encoders).
- ``robot_q`` (7) rad, ``robot_tau`` (7) N·m: robot encoders and joint torque sensors.
- ``ft_force`` (3) N, ``ft_torque`` (3) N·m: raw F/T sensor readings in the sensor frame.
- ``true_*``: noiseless simulation truth (e.g. ``true_arm_q``), absent in real data.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armlab.errors import DataError

__all__ = ["TrialSet"]


@dataclass(frozen=True, kw_only=True, eq=False)
class TrialSet:
    """All trials of one run.

    Attributes:
        fs_hz: sample rate, Hz.
        onset_index: (n_trials,) int, sample index of perturbation onset in each trial.
        channels: name -> (n_trials, n_samples, n_axes) float array.
        units: name -> unit string, one per channel.
        trial_meta: name -> (n_trials,) array of per-trial metadata (e.g. ``group``,
            ``direction``, ``T_k_s``, ``wait_s``, ``validate``).
        attrs: run-level metadata (protocol name, seed, config YAML, arm segment lengths, ground
            truth ``K_true``/``D_true``/``xi_true`` where known). JSON-serialisable values.
    """

    fs_hz: float
    onset_index: np.ndarray
    channels: Mapping[str, np.ndarray]
    units: Mapping[str, str]
    trial_meta: Mapping[str, np.ndarray] = field(default_factory=dict)
    attrs: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.fs_hz) and self.fs_hz > 0):
            raise DataError(f"fs_hz must be a positive number, got {self.fs_hz!r}")
        if not self.channels:
            raise DataError("a TrialSet needs at least one channel")
        shapes = {name: np.shape(a) for name, a in self.channels.items()}
        bad = {n: s for n, s in shapes.items() if len(s) != 3}
        if bad:
            raise DataError(f"channels must be (n_trials, n_samples, n_axes); got {bad}")
        lead = {s[:2] for s in shapes.values()}
        if len(lead) != 1:
            raise DataError(f"all channels must share (n_trials, n_samples); got {shapes}")
        missing = sorted(set(self.channels) - set(self.units))
        if missing:
            raise DataError(f"channels without a unit: {missing}")
        n_trials, n_samples = lead.pop()
        onset = np.asarray(self.onset_index)
        if onset.shape != (n_trials,):
            raise DataError(f"onset_index must have shape ({n_trials},), got {onset.shape}")
        if np.any(onset < 1) or np.any(onset >= n_samples):
            raise DataError(f"onset_index must lie in [1, {n_samples - 1}], got {onset.min()}..{onset.max()}")
        for name, a in self.trial_meta.items():
            if np.shape(a) != (n_trials,):
                raise DataError(f"trial_meta[{name!r}] must have shape ({n_trials},), got {np.shape(a)}")

    @property
    def n_trials(self) -> int:
        return int(np.asarray(self.onset_index).shape[0])

    @property
    def n_samples(self) -> int:
        return int(next(iter(self.channels.values())).shape[1])

    @property
    def t(self) -> np.ndarray:
        """(n_samples,) s, time from the start of each record."""
        return np.arange(self.n_samples) / self.fs_hz

    def channel(self, name: str) -> np.ndarray:
        """Return one channel, with an error that lists the available names."""
        try:
            return self.channels[name]
        except KeyError:
            raise DataError(f"no channel {name!r}; available: {sorted(self.channels)}") from None

    def select(self, mask: np.ndarray) -> TrialSet:
        """Return the subset of trials where ``mask`` (bool or index array) selects."""
        idx = np.arange(self.n_trials)[mask]
        return TrialSet(
            fs_hz=self.fs_hz,
            onset_index=np.asarray(self.onset_index)[idx],
            channels={k: v[idx] for k, v in self.channels.items()},
            units=dict(self.units),
            trial_meta={k: np.asarray(v)[idx] for k, v in self.trial_meta.items()},
            attrs=dict(self.attrs),
        )

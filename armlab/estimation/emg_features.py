"""The EMG maps' windows and features (seed paper 001, Sec. 4.1; the phi of Eq. (20)).

"Each map was constructed from 50 sets of 8x400 data points. We preprocessed the EMG data with a
full wave rectification and split the data into time windows of length 70 afterwards. For phi we
picked the maximum along each of the signals followed by two layers of unsupervised feature
extraction using the approach of [9]" (Ngiam et al., sparse filtering). This module cuts the
windows (:func:`emg_windows`) and takes the per-channel maximum (:func:`max_features`); the
sparse-filtering layers are :mod:`armlab.estimation.sparse_filtering` (optional in the protocol:
the paper gives neither their sizes nor their training, see ``docs/stiffness_5dof_emg.md``), and
the features are standardised on the training set (:class:`Standardiser`), a preprocessing the
paper leaves open.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError

__all__ = [
    "MAP_SAMPLES",
    "WINDOW_SAMPLES",
    "Standardiser",
    "emg_windows",
    "max_features",
]

MAP_SAMPLES = 400  # samples per channel per disturbance (paper Sec. 4.1: "50 sets of 8x400")
WINDOW_SAMPLES = 70  # samples per window (paper Sec. 4.1: "time windows of length 70")


def emg_windows(
    emg: np.ndarray, start: int, n_map: int = MAP_SAMPLES, window: int = WINDOW_SAMPLES
) -> np.ndarray:
    """Full-wave rectified, non-overlapping windows of each disturbance's map samples.

    Args:
        emg: (n_trials, n_samples, n_channels) raw EMG (any unit).
        start: the first sample of the map's stretch in every trial.
        n_map: samples of the stretch (400: 200 ms at 2 kHz); window: samples per window (70).

    Returns:
        (n_trials, n_map // window, window, n_channels) |emg|: the stretch cut into whole windows
        (400 // 70 = 5 windows; the last 50 samples of the stretch are left over).

    Raises:
        DataError: ``emg`` not 3-D, the stretch outside the record, or shorter than one window.
    """
    x = np.asarray(emg, dtype=float)
    if x.ndim != 3:
        raise DataError(f"emg must be (n_trials, n_samples, n_channels), got shape {x.shape}")
    if not (0 <= start and start + n_map <= x.shape[1]):
        raise DataError(
            f"the EMG map's stretch [{start}, {start + n_map}) samples lies outside the record of "
            f"{x.shape[1]} samples"
        )
    if not 1 <= window <= n_map:
        raise DataError(f"the window ({window} samples) must lie in [1, {n_map}] (the map's stretch)")
    n_win = n_map // window
    seg = np.abs(x[:, start : start + n_win * window])
    return seg.reshape(x.shape[0], n_win, window, x.shape[2])


def max_features(windows: np.ndarray) -> np.ndarray:
    """phi of Eq. (20): the maximum of each rectified channel over its window, (..., n_channels)
    from (..., window, n_channels)."""
    return np.asarray(windows).max(axis=-2)


@dataclass(frozen=True, kw_only=True)
class Standardiser:
    """Features shifted and scaled to zero mean and unit std on the training set.

    Attributes:
        mean, std: (n_features,) of the training features (std of a constant feature taken as 1).
    """

    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, X: np.ndarray) -> Standardiser:
        """From training features (n, n_features)."""
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape[0] < 2:
            raise DataError(f"features must be (n >= 2, n_features), got shape {X.shape}")
        std = X.std(axis=0)
        return cls(mean=X.mean(axis=0), std=np.where(std > 0, std, 1.0))

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """(n, n_features) standardised."""
        return (np.asarray(X, dtype=float) - self.mean) / self.std

"""Leave-block-out local estimates: what a sample's neighbours, not the sample, say about slow changes.

Two subject effects change the recorded torque slowly and carry no covariate the position
predicts: a stiffness that drifts with the subject's co-contraction while the net tonic torque
stays put (agonist and antagonist rise together), and a slow voluntary torque. A time basis
fitted on the first two thirds of a trial cannot extrapolate to the held-out third, so their
surrogates are *cross-fitted in time* instead (block cross-validation, as in a Box-Jenkins
disturbance model's prediction error, Ljung 1999 *System Identification* §7.3):

- every trial is cut into blocks of :data:`BLOCK_S`; alternate blocks form two folds;
- a sample's local estimate is a Gaussian-kernel weighted estimate over the *other fold's*
  samples only: its own block, hence its own noise, never enters its prediction; the kernel's
  width ``σ`` sets the slowest change resolved (gain ``exp(−(2πfσ)²/2)`` at frequency ``f``);
- the surrogate's columns are built from these estimates of the nominal's residual, and its
  linear gain is fitted on the training part like every other column, so the held-out gap is the
  error of a prediction whose parameters and whose local estimates never saw that sample.

A stationary joint's local estimates scatter around zero independently of the sample they predict,
so their fitted gain stays near zero and nothing shrinks (tested on clean recordings).

:func:`local_gains` is the local least-squares regression of the residual on the angle and the
velocity (``ΔK(t)``, ``ΔB(t)``: the slowly time-varying stiffness and damping);
:func:`local_level` is the local mean of the residual (the slow voluntary torque).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

__all__ = [
    "BLOCK_S",
    "GAIN_SIGMA_S",
    "LEVEL_SIGMA_S",
    "crossfit_mean",
    "local_gains",
    "local_level",
]

BLOCK_S = 0.04  # s, fold block: 10 samples at 250 Hz, several times the 40 Hz band's correlation
# time (1/80 s), so a neighbour block's noise is nearly independent of the block it predicts
GAIN_SIGMA_S = 0.4  # s, kernel of the local stiffness: passes exp(-(2π·0.2·0.4)²/2) = 0.88 of a
# 0.2 Hz modulation (the fastest the issue names: 0.05-0.2 Hz) while averaging ~1 s of data
LEVEL_SIGMA_S = 0.25  # s, kernel of the local torque level: half power at 0.53 Hz, the core of
# the voluntary band (< 1-2 Hz, issue 18). A narrower kernel (0.1 s, half power at 1.3 Hz) also
# followed the slow part of a missing reflex's residual (the rectified velocity's envelope) and
# took 73 % of z_df's excess ahead of the reflex (measured); at 0.25 s the reflex comes first there
_DETREND_S = 2.0  # s, Gaussian smooth removed from the regressors before the local gains
# (a high-pass near 0.08 Hz): the slow tonic torque and slow angle would otherwise bias ΔK(t)
_RIDGE = 1e-6  # 1, of the mean local Gram diagonal: keeps the 2x2 solves finite at rest


def _folds(n: int, block: int) -> np.ndarray:
    """(n,) bool, True on the even blocks of ``block`` samples."""
    return (np.arange(n) // max(block, 1)) % 2 == 0


def crossfit_mean(
    z: np.ndarray, fs_hz: float, sigma_s: float, *, weight: np.ndarray | None = None
) -> np.ndarray:
    """Gaussian-kernel local mean of ``z`` at every sample from the other fold's samples only.

    Args:
        z: (n,) or (n, k) signal(s).
        fs_hz: Hz, sample rate.
        sigma_s: s, the kernel's standard deviation.
        weight: (n,) optional sample weights (e.g. the training/scored mask), default ones.

    Returns:
        (n,) or (n, k): ``Σ w(t−s)·z(s) / Σ w(t−s)`` over samples ``s`` of the fold opposite ``t``'s
        (kernel sums, so the cost is a few Gaussian filters, not a loop).
    """
    z = np.asarray(z, float)
    n = z.shape[0]
    sigma = sigma_s * fs_hz
    even = _folds(n, int(round(BLOCK_S * fs_hz)))
    w = np.ones(n) if weight is None else np.asarray(weight, float)
    out = np.empty_like(z)
    for use in (even, ~even):  # the estimate on one fold is made from the other
        m = (use * w).reshape((n,) + (1,) * (z.ndim - 1))
        num = gaussian_filter1d(z * m, sigma, axis=0, mode="nearest")
        den = gaussian_filter1d(m, sigma, axis=0, mode="nearest")
        target = ~use
        out[target] = (num / np.maximum(den, 1e-12))[target]
    return out


def local_gains(r: np.ndarray, x: np.ndarray, v: np.ndarray, fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Cross-fitted local regression ``r ≈ ΔK(t)·x + ΔB(t)·v`` (kernel :data:`GAIN_SIGMA_S`).

    Args:
        r: (n,) N·m, the nominal model's residual torque.
        x, v: (n,) rad, rad/s, the angle and velocity.
        fs_hz: Hz, sample rate.

    Returns:
        (ΔK, ΔB): (n,) N·m/rad and N·m·s/rad, the local stiffness and damping change at every
        sample, each from the other fold's samples (module docstring).
    """
    r, x, v = (
        z - gaussian_filter1d(z, _DETREND_S * fs_hz, mode="nearest") for z in map(np.asarray, (r, x, v))
    )
    prods = np.stack([x * x, x * v, v * v, r * x, r * v], axis=1)
    sxx, sxv, svv, srx, srv = crossfit_mean(prods, fs_hz, GAIN_SIGMA_S).T
    sxx = sxx + _RIDGE * float(np.mean(sxx))
    svv = svv + _RIDGE * float(np.mean(svv))
    det = sxx * svv - sxv * sxv
    return (svv * srx - sxv * srv) / det, (sxx * srv - sxv * srx) / det


def local_level(r: np.ndarray, fs_hz: float) -> np.ndarray:
    """Cross-fitted local mean of the residual torque (kernel :data:`LEVEL_SIGMA_S`): (n,) N·m."""
    return crossfit_mean(np.asarray(r, float), fs_hz, LEVEL_SIGMA_S)

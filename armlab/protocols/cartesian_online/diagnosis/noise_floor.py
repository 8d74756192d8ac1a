"""The noise floor of ``cartesian_online``: what no model of the held-out trials can predict.

Two parts of it are read from the force (the position sensor's share: :mod:`.position_noise`):

- **White noise** (:func:`white_noise_var`): the second differences of a raw signal (Rice 1984:
  ``E[(Δ²z)²] = 6σ²`` for white noise of variance ``σ²``), by the mean of the lowest
  :data:`KEEP` of their squares over that mean for a χ² with one degree of freedom
  (:data:`TRIMMED_CHI2_MEAN`), so the few samples at the triangle's corners, where the force
  itself bends, do not count. Not the median: on a quantised sensor (the JR3's 0.0122 N steps)
  the second differences lie on the step's grid, so the median of their squares is one of
  ``k²·step²`` (1.065 × the truth for every seed of the JR3 model), whereas a trimmed mean is
  continuous; it recovers the white noise plus ``step²/12`` (Sheppard).
- **Per-trial offsets** (:func:`trial_offset_var`): an F/T sensor tared before each trial keeps
  a residual offset that is constant within the trial and independent between trials (cuff
  preload, hysteresis; the JR3 model's ``bias_std``). The thesis logs only during the
  perturbations (Ch. 3, §3.2.2), so there is no still interval to read it from, and a held-out
  trial's offset cannot be predicted from the other trials: for a held-out score it is noise,
  like the white part. Second differences of the force cannot see it (it is constant). It is
  read from the trial means of the nominal field's residual instead, perturbation by
  perturbation: what an unmodelled effect leaves there varies smoothly with the stop's position
  and with time (a hand's inertia, a delay, a field of another shape, a bias common to all
  trials, a drift over the run), so the means are fitted by least squares on the cubic monomials
  of the stop's position (on a circle: the angle's harmonics up to the third) and a linear trend
  in time, and the offsets' variance is the residual variance over the residual degrees of
  freedom, less the white noise's share of each mean (``σ_i²/n_i`` per trial, the force's and the
  position's through the field, weighted by the fit's leverages as the residual keeps it). With
  the thesis's 20 stops on the circle that leaves 12 degrees of freedom per perturbation, 36 per
  axis; a bias common to all trials or a drift lies in the basis and leaves the estimate where it
  was (3e-7 relative, round-off of the nominal fit it moves; tested), so it stays the
  candidate ``force_sensor_drift``'s. Anything else that is constant within a trial and
  changes at random from trial to trial is counted too (a subject's trial-to-trial change of
  co-contraction shows partly so): it is as unpredictable on a held-out trial, and the report
  gives its size (``gap.trial_offset_N``). Second differences of the means along the stops, tried
  first, do not cancel a field's second harmonic at 18° spacing, and read a common drift as
  ~0.1 N of offsets.
"""

from __future__ import annotations

import numpy as np

from armlab.dsp import butterworth, zero_phase

__all__ = [
    "KEEP",
    "TRIMMED_CHI2_MEAN",
    "band_noise_gain",
    "trial_offset_var",
    "white_noise_var",
]

KEEP = 0.9  # share of the smallest squared second differences kept (the corners are < 1 %)
#: mean of the smallest 90 % of a χ²₁ variable: E[Z²·1{Z² < q}] / 0.9 = P(χ²₃ < q) / 0.9 with
#: q = 2.7055, χ²₁'s 90 % quantile (E[Z²·1{Z² < q}] = P(χ²₃ < q) for a standard normal Z)
TRIMMED_CHI2_MEAN = 0.6230155


def white_noise_var(z: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """(k,) white-noise variance per axis of (m, n, k) signals from the second differences of
    their logged samples (module docstring)."""
    d2 = np.diff(np.where(valid[..., None], z, np.nan), 2, axis=1)
    d2 = np.sort(d2[np.all(np.isfinite(d2), axis=-1)] ** 2, axis=0)
    kept = d2[: max(1, int(KEEP * len(d2)))]
    return kept.mean(axis=0) / (6.0 * TRIMMED_CHI2_MEAN)


def band_noise_gain(fs_hz: float, band_hz: float) -> float:
    """Variance of white unit noise after the band's zero-phase low-pass (sum of h²)."""
    n = 4001
    impulse = np.zeros(n)
    impulse[n // 2] = 1.0
    h = zero_phase(butterworth(band_hz, fs_hz, 4), impulse, padtype="even")
    return float(np.sum(h**2))


def _smooth_basis(w: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(m, 11): the cubic monomials of the scaled stop positions ``w`` (m, 2) and the time ``t``
    (m,) scaled to [0, 1] (on a circle: the harmonics of the angle up to the third, and a trend)."""
    u, v = w[:, 0], w[:, 1]
    span = float(np.ptp(t)) or 1.0
    return np.stack(
        [np.ones_like(u), u, v, u * u, u * v, v * v, u**3, u * u * v, u * v * v, v**3, (t - t.min()) / span],
        axis=1,
    )


def trial_offset_var(
    resid: np.ndarray,
    valid: np.ndarray,
    phase: np.ndarray,
    stop_pos: np.ndarray,
    t_start: np.ndarray,
    white_var: np.ndarray,
) -> np.ndarray:
    """(k,) variance of per-trial offsets (module docstring), 0 where none shows or where too few
    trials are left over the smooth basis to tell.

    Args:
        resid: (m, n, k) a nominal model's residual, unfiltered.
        valid: (m, n) logged samples (a trial without any is left out).
        phase: (m,) the perturbation within its sequence (one regression per perturbation).
        stop_pos: (m, 2) the stop of each trial, scaled (about O(1) around the path).
        t_start: (m,) s, each trial's start.
        white_var: (m, k) the white noise's variance per sample in each trial's residual (the
            force's, and the position's through the field); its share of each trial mean,
            ``white_var / n``, is subtracted as the least-squares residual keeps it.
    """
    n = valid.sum(axis=1)
    kept = n > 0
    means = np.where(valid[..., None], resid, 0.0).sum(axis=1) / np.maximum(n, 1)[:, None]  # (m, k)
    share = white_var / np.maximum(n, 1)[:, None]  # (m, k) the white noise's variance of each mean
    rss, white, dof = np.zeros(resid.shape[-1]), np.zeros(resid.shape[-1]), 0
    for ph in dict.fromkeys(phase[kept]):
        idx = np.flatnonzero(kept & (phase == ph))
        basis = _smooth_basis(stop_pos[idx], t_start[idx])
        u, sv, _ = np.linalg.svd(basis, full_matrices=False)
        rank = int(np.sum(sv > 1e-9 * sv[0]))
        if len(idx) <= rank:
            continue
        u = u[:, :rank]
        e = means[idx] - u @ (u.T @ means[idx])  # residual of the least-squares fit on the basis
        rss += np.sum(e**2, axis=0)
        white += (1.0 - np.sum(u**2, axis=1)) @ share[idx]  # E[RSS] of the white part: Σ(1 - h_ii)·w_i
        dof += len(idx) - rank
    if dof == 0:
        return np.zeros(resid.shape[-1])
    return np.maximum((rss - white) / dof, 0.0)

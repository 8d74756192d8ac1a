"""Below the scoring band: a torque-sensor drift, told from a slow subject torque by where its power lies.

The diagnosis scores the gap in ``[highpass_hz, band_hz]`` (:mod:`.data`): a torque-sensor bias
drift (a ramp, thermal settling, a wander slower than ~0.02 Hz) lies below it and leaves the
scored gap at the floor. This module looks at what the scoring band leaves out, on the nominal
model's residual (the part of the slow torque that the position does not predict):

1. ``r = y − (I·θ̈ + B·θ̇ + K·θ)`` with the nominal's per-trial parameters (fitted in the scoring
   band; the joint's static stiffness then also accounts for the perturbation's own slow
   content), low-passed by the complement of the scoring high-pass (``r − hp(r)``: the
   zero-phase 2nd-order Butterworth low-pass at ``highpass_hz``), over the scored samples (the
   2 s ends excluded), less its mean (a constant offset of the torque channel is not
   identifiable: the sensor's zero);
2. the **drift surrogate**: per trial, the cosine (DCT-II) basis of time ``cos(πk(t+½)/N)``,
   ``k = 1…K`` with ``K = max(2, ⌊2·T·DRIFT_HZ⌋)`` (its frequencies ``k/2T`` up to
   :data:`DRIFT_HZ`: at least a trend and a bend), linear gains;
3. its **detection** against the noise in its own band: with white torque noise of one-sided
   density ``S`` (from the noise floor: its band variance over the scoring band's noise
   bandwidth), each orthonormal coefficient of a slow basis carries ``S·fs/2`` of noise power
   (``fs`` the fitting rate), so the captured power over the ``ΣK`` coefficients is
   ``S·fs/2·χ²(ΣK)`` on a joint without drift; the drift is detected where the captured power
   exceeds the χ² quantile of :data:`FALSE_ALARM` (a rule fixed by the noise model, not fitted
   to any referee);
4. its **share of the slow excess** (where the power lies): the captured power less the noise's,
   over the low band's power less the noise's (``S·∫|LP|⁴``). A drift puts nearly all its slow
   power in those few components; a slow voluntary torque (0.05-2 Hz) or a tonic co-contraction
   (0.02-0.3 Hz) spreads it over the rest of the low band, most of which the cosines below
   0.05 Hz do not reach. The drift is named where its share is at least ``min_explained`` (the
   same rule as the effects in the scoring band);
5. its **shrink**, cross-fitted in time (as :mod:`.local` is): every block of :data:`FOLD_S`
   predicted by the basis' gains fitted on the trial's other blocks, so the reported share of the
   slow excess it removes is that of a prediction that never saw the samples it scores (it
   includes the fit's own noise: ~1/ENR² of the drift's power).

:func:`low_band_check` returns the section ``results["low_band"]`` (docs/diagnosis_schema.md);
the diagnosis names ``force_sensor_drift`` from it only where the scoring band's verdict is
``none`` (an effect in the band, e.g. a co-contraction with its tonic torque, explains the slow
torque otherwise; the section is reported either way).
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from armlab.dsp import zero_phase
from armlab.protocols.joint_1dof.diagnosis.data import band_power_gain

__all__ = [
    "DRIFT_HZ",
    "FALSE_ALARM",
    "FOLD_S",
    "drift_basis",
    "low_band_check",
    "white_density",
]

DRIFT_HZ = 0.05  # Hz, top of the drift surrogate's band: the bottom of the band from which the
# referees measure a voluntary torque's ENR (docs/joint_1dof_referees.md), so the two do not share it
FALSE_ALARM = 0.01  # 1, probability that pure noise passes the detection (χ² quantile): set from
# the noise model and issue 18's target (≤ 5 % false alarms on "none"), not from any dataset; a
# drift at ENR 1 doubles the expected captured power, which 1e-3 (quantile 2.27x the mean at 20
# cosines, 3.3x at 8) would miss more often than not
FOLD_S = 2.0  # s, cross-fitting block: longer than the low band's correlation time (1/(2·0.3 Hz)),
# so a block's noise is nearly independent of the samples that predict it


def drift_basis(n: int, fs_hz: float) -> np.ndarray:
    """(n, K) orthonormal DCT-II columns ``k = 1…K`` over ``n`` samples (module docstring, step 2)."""
    k_max = max(2, int(np.floor(2.0 * (n / fs_hz) * DRIFT_HZ)))
    i = np.arange(n)[:, None] + 0.5
    q = np.cos(np.pi * np.arange(1, k_max + 1)[None, :] * i / n)
    return q * np.sqrt(2.0 / n)


def white_density(noise, *, fs_hz: float, raw_fs_hz: float, band_hz: float, hp: np.ndarray) -> float:
    """N·m²/Hz: the one-sided density of white torque noise whose variance in the scoring band is
    ``noise.variance_Nm2`` (the anti-alias low-pass at the recorded rate and the scoring high-pass,
    both zero-phase, as in :func:`.data.noise_floor`)."""
    f = np.linspace(0.0, fs_hz / 2, 4097)
    gain = band_power_gain(f, fs_hz=fs_hz, raw_fs_hz=raw_fs_hz, band_hz=band_hz, hp=hp)
    return float(noise.variance_Nm2 / np.trapezoid(gain, f))


def _lowpass_gain(highpass_hz: float) -> float:
    """Hz: ``∫|LP|⁴ df`` of the scoring high-pass' complement (2nd-order Butterworth, zero-phase):
    ``∫ (1 + (f/fc)⁴)⁻² df = fc·3π/(8√2)``."""
    return highpass_hz * 3.0 * np.pi / (8.0 * np.sqrt(2.0))


def _crossfit(r: np.ndarray, q: np.ndarray, fs_hz: float) -> np.ndarray:
    """r's prediction by ``[1, q]``, each block of :data:`FOLD_S` from a fit on all the others
    (leave one block out: the fit's own error stays that of the whole trial's, ~1/N_blocks more)."""
    n = r.size
    block = np.arange(n) // max(int(round(FOLD_S * fs_hz)), 1)
    basis = np.column_stack([np.ones(n), q])
    gram, rhs = basis.T @ basis, basis.T @ r
    out = np.empty(n)
    for b in range(int(block[-1]) + 1):
        m = block == b
        coef = np.linalg.solve(gram - basis[m].T @ basis[m], rhs - basis[m].T @ r[m])
        out[m] = basis[m] @ coef
    return out


def low_band_check(
    trials, nominal, noise, hp, *, highpass_hz: float, band_hz: float, min_share: float
) -> dict:
    """The torque below the scoring band and the drift surrogate's detection, share and shrink.

    Args:
        trials: prepared trials (:class:`.data.PreparedTrial`).
        nominal: the fitted nominal model (``beta[j][:3]`` = I, B, K of trial j, torque sign as
            recorded).
        noise: the :class:`.data.NoiseFloor` of the scoring band.
        hp: the scoring high-pass' second-order sections.
        highpass_hz, band_hz: Hz, the scoring band.
        min_share: the share of the slow excess the drift must hold to be named (``min_explained``).

    Returns:
        The ``results["low_band"]`` dict (docs/diagnosis_schema.md).
    """
    fs = trials[0].fs_hz
    density = white_density(noise, fs_hz=fs, raw_fs_hz=trials[0].raw_fs_hz, band_hz=band_hz, hp=hp)
    coef_var = density * fs / 2.0  # N·m², noise power per orthonormal coefficient of a slow basis
    n_tot, k_tot = 0, 0
    power, captured, left = 0.0, 0.0, 0.0
    per_trial = []
    for tr, beta in zip(trials, nominal.beta, strict=True):
        r = tr.y - np.column_stack([tr.a, tr.v, tr.x]) @ np.asarray(beta[:3], float)
        r_low = (r - zero_phase(hp, r))[tr.train | tr.held]
        r_low = r_low - r_low.mean()
        q = drift_basis(r_low.size, fs)
        cap = float(np.sum((q.T @ r_low) ** 2))
        rest = float(np.sum((r_low - _crossfit(r_low, q, fs)) ** 2))
        p = float(np.sum(r_low**2))
        per_trial.append(
            {
                "trial": tr.name,
                "components": q.shape[1],
                "residual_power_Nm2": p / r_low.size,
                "drift_rms_Nm": float(np.sqrt(max(cap - q.shape[1] * coef_var, 0.0) / r_low.size)),
            }
        )
        n_tot += r_low.size
        k_tot += q.shape[1]
        power, captured, left = power + p, captured + cap, left + rest
    noise_low = density * _lowpass_gain(highpass_hz) * n_tot  # N·m² summed over the samples
    noise_cap = coef_var * k_tot
    threshold = coef_var * float(chi2.isf(FALSE_ALARM, k_tot))
    excess = power - noise_low
    drift_excess = captured - noise_cap
    share = drift_excess / excess if excess > 0 else 0.0
    detected = bool(captured > threshold)
    return {
        "band_hz": [0.0, highpass_hz],
        "noise_density_Nm2_per_Hz": density,
        "residual_power_Nm2": power / n_tot,
        "noise_power_Nm2": float(noise_low / n_tot),
        "force_sensor_drift": {
            "band_hz": [0.0, DRIFT_HZ],
            "components": k_tot,
            "captured_power_Nm2": captured / n_tot,
            "noise_power_Nm2": noise_cap / n_tot,
            "threshold_power_Nm2": threshold / n_tot,
            # a floor of exactly 0 (a noiseless torque off any grid): any drift is infinitely clear
            "enr": float(np.sqrt(max(drift_excess, 0.0) / noise_cap))
            if noise_cap > 0
            else (float("inf") if drift_excess > 0 else 0.0),
            "detected": detected,
            "share_of_excess": float(share),
            "shrink": float((power - left) / excess) if excess > 0 else float("nan"),
            "per_trial": per_trial,
        },
        "named": bool(detected and share >= min_share),
    }

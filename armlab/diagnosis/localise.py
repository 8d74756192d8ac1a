"""Where the gap lies: held-out residual broken down by band, time after onset, trial; residual tests.

All figures compare the held-out residual (measured minus model torque in the scoring band) with
the noise floor, as a fraction of the measured power in the same slice (so 0.05 = 5 % of the
measured variance there is unexplained; ``floor`` is what noise alone would leave).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from armlab.estimation.frf import estimate_frf
from armlab.estimation.levy import LevyStructure, levy_fit

__all__ = [
    "BANDS_HZ",
    "WINDOWS_MS",
    "band_breakdown",
    "frf_parameters",
    "masked_gap",
    "onsets",
    "residual_tests",
    "trial_band_breakdown",
    "window_breakdown",
]

#: Hz, frequency bands of the breakdown (issue 5).
BANDS_HZ = ((0.0, 2.0), (2.0, 8.0), (8.0, 20.0), (20.0, 40.0))
#: ms, windows after perturbation onset (issue 5).
WINDOWS_MS = ((0, 20), (20, 60), (60, 120), (120, 250), (250, 400))
_IMPEDANCE = LevyStructure(num_powers=(0, 1, 2), den_powers=(), name="I s² + B s + K")


def _held(trials, arrays):
    return [z[tr.held] for z, tr in zip(arrays, trials, strict=True)]


def band_breakdown(trials, y_band, residuals, noise) -> list[dict]:
    """Residual, measured and noise power per band (held-out parts, Welch PSDs)."""
    fs = trials[0].fs_hz
    held_y, held_r = _held(trials, y_band), _held(trials, residuals)
    nper = min(512, min(z.size for z in held_y))
    f, py = signal.welch(np.concatenate(held_y), fs=fs, nperseg=nper)
    _, pr = signal.welch(np.concatenate(held_r), fs=fs, nperseg=nper)
    pn = np.interp(f, noise.f_hz, noise.psd)
    out = []
    for lo, hi in BANDS_HZ:
        sel = (f >= lo) & (f < hi)

        def power(p, sel=sel):
            return float(np.trapezoid(p[sel], f[sel])) if sel.sum() > 1 else float(np.sum(p[sel]))

        meas, res, nse = power(py), power(pr), power(pn)
        out.append(
            {
                "band_hz": [lo, hi],
                "gap": res / meas if meas > 0 else float("nan"),
                "floor": nse / meas if meas > 0 else float("nan"),
                "residual_power": res,
                "measured_power": meas,
            }
        )
    return out


def onsets(trial, *, level: float = 0.5, refractory_s: float = 0.05) -> np.ndarray:
    """Sample indices where the joint speed rises through ``level`` × its 99th percentile."""
    speed = np.abs(trial.v)
    thr = level * np.percentile(speed, 99)
    up = np.flatnonzero((speed[1:] >= thr) & (speed[:-1] < thr)) + 1
    keep, last = [], -np.inf
    gap = refractory_s * trial.fs_hz
    for i in up:
        if i - last >= gap:
            keep.append(i)
            last = i
    return np.asarray(keep, dtype=int)


def window_breakdown(trials, y_band, residuals, noise_var: float) -> list[dict]:
    """Residual and measured mean square by time since the last perturbation onset (held out)."""
    since_all, r_all, y_all = [], [], []
    for tr, y, r in zip(trials, y_band, residuals, strict=True):
        on = onsets(tr)
        idx = np.arange(tr.t_s.size)
        since = np.full(idx.size, np.inf)  # ms; no onset at all (a still trial): never "after" one
        if on.size:
            pos = np.searchsorted(on, idx, side="right") - 1
            since = np.where(pos >= 0, (idx - on[np.clip(pos, 0, None)]) / tr.fs_hz * 1e3, np.inf)
        held = tr.held
        since_all.append(since[held])
        r_all.append(r[held])
        y_all.append(y[held])
    since, r, y = (np.concatenate(z) for z in (since_all, r_all, y_all))
    out = []
    for lo, hi in WINDOWS_MS:
        sel = (since >= lo) & (since < hi)
        if not sel.any():
            out.append({"window_ms": [lo, hi], "gap": None, "floor": None, "samples": 0})
            continue
        ms_y = float(np.mean(y[sel] ** 2))
        out.append(
            {
                "window_ms": [lo, hi],
                "gap": float(np.mean(r[sel] ** 2)) / ms_y,
                "floor": noise_var / ms_y,
                "samples": int(sel.sum()),
            }
        )
    return out


def residual_tests(trials, residuals, *, max_lag_s: float = 0.25, min_lag_s: float = -0.05) -> dict:
    """Residual whiteness and residual–input (joint velocity) cross-correlation against lag.

    Returns a dict with ``lags_s``, ``autocorrelation`` (lags >= 0), ``cross_correlation``
    (residual at t vs velocity at t - lag), the 95 % bound ``±1.96/sqrt(n)`` for a white residual,
    the fraction of autocorrelation lags (> 0) outside the bound, and the lag and value of the
    largest cross-correlation.
    """
    fs = trials[0].fs_hz
    lags = np.arange(int(round(min_lag_s * fs)), int(round(max_lag_s * fs)) + 1)
    acf = np.zeros(lags.size)
    ccf = np.zeros(lags.size)
    n_total = 0
    for tr, r in zip(trials, residuals, strict=True):
        e = r[tr.held] - r[tr.held].mean()
        u = tr.v[tr.held] - tr.v[tr.held].mean()
        n = e.size
        n_total += n
        # full correlations: entry n-1+k is sum_t e[t]·z[t-k]
        idx = n - 1 + lags
        acf += signal.correlate(e, e, method="fft")[idx] / np.sum(e * e) * n
        ccf += signal.correlate(e, u, method="fft")[idx] / np.sqrt(np.sum(e * e) * np.sum(u * u)) * n
    acf /= n_total
    ccf /= n_total
    bound = 1.96 / np.sqrt(n_total)
    pos = lags > 0
    j = int(np.argmax(np.abs(ccf)))
    return {
        "lags_s": (lags / fs).tolist(),
        "autocorrelation": np.where(lags >= 0, acf, np.nan).tolist(),
        "cross_correlation": ccf.tolist(),
        "bound": bound,
        "whiteness_fraction_outside": float(np.mean(np.abs(acf[pos]) > bound)),
        "peak_cross_lag_s": float(lags[j] / fs),
        "peak_cross_value": float(ccf[j]),
    }


def frf_parameters(trial, torque: np.ndarray, *, band_hz=(1.0, 20.0), nperseg: int = 1024) -> dict:
    """I, B, K from the position→torque frequency response in a band (the protocol's own FRF fit).

    The impedance ``Z = -torque/position`` (torque resists the motion) by the project's Welch
    estimate (:func:`armlab.estimation.frf.estimate_frf`, half-overlapping segments), then Levy's
    least squares of ``K + B·s + I·s²`` over the band, the integer fit of ``armlab fit-joint``
    (:mod:`armlab.protocols.joint_1dof.frf`). Run on measured and on simulated torque, the difference
    is the bias a model error leaves in the identified parameters.
    """
    z = estimate_frf(
        trial.x, -np.asarray(torque, float), trial.fs_hz, window_len=min(nperseg, trial.x.size), overlap=0.5
    ).band(*band_hz)
    b = levy_fit(z.f_hz, z.G, _IMPEDANCE, 1.0).model.b  # ascending powers of s: K, B, I
    return {"I": float(b[2]), "B": float(b[1]), "K": float(b[0])}


def masked_gap(resid: np.ndarray, y: np.ndarray, noise_var: np.ndarray, mask: np.ndarray) -> dict:
    """Held-out gap and noise floor of the scoring rows in ``mask`` (1-D arrays of rows: residual,
    measured, each row's noise variance), with the number of rows; None where the slice has no
    measured power."""
    tss = float(np.sum(y[mask] ** 2))
    if tss == 0:
        return {"held_out_gap": None, "noise_floor": None, "n_rows": int(mask.sum())}
    return {
        "held_out_gap": float(np.sum(resid[mask] ** 2)) / tss,
        "noise_floor": float(np.sum(noise_var[mask])) / tss,
        "n_rows": int(mask.sum()),
    }


def trial_band_breakdown(resid: np.ndarray, y: np.ndarray, fs_hz: float) -> list[dict]:
    """Residual share and held-out gap per :data:`BANDS_HZ` band of short held-out trials.

    Args:
        resid, y: (n_trials, n_samples, n_channels) residual and measured signal of each trial's
            scored stretch; their Hann-windowed spectra are summed over trials and channels.
        fs_hz: Hz, sample rate.
    """
    n = resid.shape[1]
    win = np.hanning(n)[None, :, None]
    f = np.fft.rfftfreq(n, 1.0 / fs_hz)
    pr = np.sum(np.abs(np.fft.rfft(resid * win, axis=1)) ** 2, axis=(0, 2))
    py = np.sum(np.abs(np.fft.rfft(y * win, axis=1)) ** 2, axis=(0, 2))
    bands = []
    for lo, hi in BANDS_HZ:
        sel = (f >= lo) & (f < hi)
        bands.append(
            {
                "band_hz": [lo, hi],
                "residual_share": float(pr[sel].sum() / pr.sum()) if pr.sum() > 0 else 0.0,
                "held_out_gap": float(pr[sel].sum() / py[sel].sum()) if py[sel].sum() > 0 else None,
            }
        )
    return bands

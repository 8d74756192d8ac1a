"""Position-sensor noise in the regressors of ``cartesian_online``: a smoothing differentiator and
the noise's share of the floor (errors in variables).

The nominal model (:mod:`.models`) regresses the force on the measured position ``p`` (stiffness)
and velocity ``v`` (damping). A position sensor's own noise ``e`` (the LWR's 0.01° encoder steps
through the robot's kinematics: ~40 µm rms at the cuff, white up to 500 Hz, measured) enters both:

- **Velocity.** Differentiating multiplies ``e``'s spectrum by ``(2πf)²``: central differences of
  the encoders give ~30 mm/s of noise against ~10 mm/s of velocity. The least-squares damping
  is attenuated by the noise's share of the velocity's variance *left after the stiffness
  columns*. That share is large on the thesis's triangles, where ``v`` and ``p`` are nearly
  collinear. Measured on the default level-B run: δ 1.01 → 0.09.
- **Position.** ``K·e`` is a force the model cannot predict. It is an irreducible floor like the
  F/T noise. The stiffness itself is barely attenuated (the excursion is ~20 × ``e``).

**Rule for the velocity (a zero-phase low-pass differentiator of data-chosen bandwidth).** Read
the position noise from the data: its white variance ``σ_e²`` per axis from the second
differences of the measured position. This is the same trimmed-mean estimator as the force's
floor (:func:`.data.white_noise_var`); quantisation with dither is white, with variance about
``step²/12``. Compare it with the perturbation's spectrum: the Hann-windowed periodogram of
``p = q - q_ref``, averaged over the trials. The cut-off ``f_c`` is the lowest frequency above
the spectrum's peak where the periodogram falls to twice the white level ``2σ_e²/fs``, i.e.
where the position's signal-to-noise ratio falls to 1. Above ``f_c`` the measured position is
mostly noise, so its derivative is too. The velocity (the file's, or the position's central
differences) is then low-passed at ``f_c`` (4th-order Butterworth, forward-backward, so there
is no phase lag). The acceleration is the central difference of that velocity.

Where ``f_c`` lies at or above the scoring band (``diagnosis.band_hz``), nothing is smoothed.
The band's own zero-phase filter, which every column and the force pass through, already removes
what lies above it. This is the case for noise-free data (level A, ideal sensors: ``σ_e`` is
round-off and the crossing lies at > 100 Hz).

The rule reads only the data, never a constant tuned on a run. On the default level-B run it
gives 24-28 Hz; the triangles' content ends at ~20-30 Hz. The rule is also why the band stays as
configured and only the velocity is smoothed. Low-passing the position, or narrowing the band
for the force and every column, removes as much of ``K·e`` as of the signal, and the noise in
the velocity's band remains (measured: a 26 Hz band leaves δ at 0.1).

**Floor.** The position noise adds, per row, ``σ_e,a²·(K̂_a(q)²·g_band + δ_a²K̂_a(q)·g_v,a)`` to the
force's white-noise floor. ``g_band`` is the band filter's white-noise gain. ``g_v,a`` is that
gain for the band ∘ smoothing ∘ central difference. The cross term vanishes because one impulse
response is even and the other odd. The nominal field ``K̂, δ`` is fitted on the smoothed
velocity, so δ is not attenuated.
"""

from __future__ import annotations

import numpy as np

from armlab.dsp import butterworth, lowpass_zero_phase, zero_phase

__all__ = [
    "EDGE_ENERGY",
    "SNR_CROSSING",
    "differentiated_gain",
    "edge_guard_samples",
    "smooth_velocity",
    "snr_cutoff_hz",
]

#: the periodogram's level, in units of the white noise's, where the position's SNR is 1
#: (signal + noise = 2 × noise)
SNR_CROSSING = 2.0
_ORDER = 4  # one-way Butterworth order of the smoothing low-pass (the band's, data.band)
_IMPULSE_N = 4001  # samples of the impulse responses whose squared sums give the gains
#: share of the smoothed differentiator's impulse-response energy the edge guard spans
EDGE_ENERGY = 0.99


def snr_cutoff_hz(p: np.ndarray, valid: np.ndarray, noise_var: np.ndarray, fs_hz: float) -> np.ndarray:
    """(2,) Hz, per axis: where the perturbation's spectrum falls to the position noise's
    (module docstring; ``inf`` where it never does below fs/2).

    Args:
        p: (m, n, 2) m, measured perturbation ``q - q_ref`` per trial.
        valid: (m, n) bool, logged samples (the periodogram uses the shortest trial's length).
        noise_var: (2,) m², white position-noise variance per axis.
        fs_hz: Hz, sample rate.
    """
    n = int(valid.sum(axis=1).min())
    seg = p[:, :n] - p[:, :n].mean(axis=1, keepdims=True)
    win = np.hanning(n)
    spec = np.abs(np.fft.rfft(seg * win[None, :, None], axis=1)) ** 2
    psd = spec.mean(axis=0) * 2.0 / (fs_hz * np.sum(win**2))  # (n//2 + 1, 2) m²/Hz, one-sided
    f = np.fft.rfftfreq(n, 1.0 / fs_hz)
    out = np.full(2, np.inf)
    for j in range(2):
        level = SNR_CROSSING * 2.0 * noise_var[j] / fs_hz
        above_peak = np.arange(len(f)) > np.argmax(psd[:, j])
        crossed = np.flatnonzero(above_peak & (psd[:, j] <= level))
        if crossed.size and f[crossed[0]] < 0.5 * fs_hz:
            out[j] = float(f[crossed[0]])
    return out


def smooth_velocity(v: np.ndarray, fs_hz: float, cutoff_hz: np.ndarray, band_hz: float) -> np.ndarray:
    """(m, n, 2) m/s: each axis of ``v`` low-passed (zero phase) at its cut-off where that lies
    below ``band_hz``, else unchanged (module docstring)."""
    out = np.array(v, dtype=float, copy=True)
    for j, fc in enumerate(cutoff_hz):
        if fc < band_hz:
            out[..., j] = lowpass_zero_phase(v[..., j], fs_hz, float(fc), _ORDER, axis=1, padtype="even")
    return out


def differentiated_gain(fs_hz: float, band_hz: float, cutoff_hz: float) -> float:
    """(m/s)² per m²: white-noise variance gain of the band ∘ smoothing (where ``cutoff_hz <
    band_hz``) ∘ central difference, i.e. the sum of its squared impulse response."""
    impulse = np.zeros(_IMPULSE_N)
    impulse[_IMPULSE_N // 2] = 1.0
    h = np.gradient(impulse, 1.0 / fs_hz)
    if cutoff_hz < band_hz:
        h = zero_phase(butterworth(cutoff_hz, fs_hz, _ORDER), h, padtype="even")
    h = zero_phase(butterworth(band_hz, fs_hz, 4), h, padtype="even")
    return float(np.sum(h**2))


def edge_guard_samples(fs_hz: float, cutoff_hz: np.ndarray, band_hz: float) -> int:
    """Samples at each end of a trial that are not scored where the velocity is smoothed: the
    half-width of the smoothed differentiator's impulse response (the acceleration column's
    filter: smoothing ∘ central difference) that holds :data:`EDGE_ENERGY` of its energy, at the
    lowest cut-off below the band; 0 where nothing is smoothed.

    Within it of a trial's ends the smoothing's even extension stands in for samples the record
    does not have, so the smoothed velocity and its derivative there are not the hand's: on the
    thesis's triangles the record ends while the hand is still decelerating, and the missing end
    of ``m·a`` left ~40 % of what the hand's inertia did not explain in the last 20 ms (default
    lab). The scoring band's own filter, shared by the force and every column, needs no guard.
    """
    smoothed = [float(fc) for fc in cutoff_hz if fc < band_hz]
    if not smoothed:
        return 0
    impulse = np.zeros(_IMPULSE_N)
    impulse[_IMPULSE_N // 2] = 1.0
    h = np.gradient(zero_phase(butterworth(min(smoothed), fs_hz, _ORDER), impulse, padtype="even"))
    energy = h**2
    outside = 2.0 * np.cumsum(energy[::-1])[::-1][_IMPULSE_N // 2 + 1 :]  # beyond ±k, k = 0, 1, ...
    return int(np.argmax(outside < (1.0 - EDGE_ENERGY) * energy.sum()))

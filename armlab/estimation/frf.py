"""Frequency-response estimation of Sec. III-B of the fractional-elbow paper.

Before spectral analysis the measured output is low-pass filtered by an equiripple FIR, applied
forward and backward (zero phase); the paper's design has its pass-band edge at 15 Hz, stop-band
edge at 18 Hz, 1 dB pass-band ripple and 80 dB stop-band attenuation. The frequency response
``G = P_uy / P_uu`` (the H1 estimator, output over input cross-spectrum) and the coherence are
then estimated by Welch's method with Blackman-Harris windows of 5000 samples and 25 % overlap.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import signal

from armlab.errors import ConfigError, DataError

__all__ = [
    "FirLowpass",
    "FirLowpassSpec",
    "FrequencyResponse",
    "average_responses",
    "design_fir_lowpass",
    "estimate_frf",
]

# Taps tried past the Kaiser/Herrmann estimate before giving up, as a fraction of the estimate.
_MAX_GROWTH = 0.5


@dataclass(frozen=True, kw_only=True)
class FirLowpassSpec:
    """Specification of a linear-phase low-pass FIR (defaults: Sec. III-B of the fractional paper).

    Attributes:
        pass_hz: Hz, pass-band edge (paper: 15 Hz).
        stop_hz: Hz, stop-band edge, ``pass_hz < stop_hz < fs_hz / 2`` (paper: 18 Hz).
        ripple_db: dB, largest peak-to-peak pass-band ripple, > 0 (paper: 1 dB).
        attenuation_db: dB, least stop-band attenuation below unit gain, > 0 (paper: 80 dB).
        fs_hz: Hz, sample rate (paper: 2 kHz).
    """

    pass_hz: float = 15.0
    stop_hz: float = 18.0
    ripple_db: float = 1.0
    attenuation_db: float = 80.0
    fs_hz: float = 2000.0

    def __post_init__(self) -> None:
        vals = (self.pass_hz, self.stop_hz, self.ripple_db, self.attenuation_db, self.fs_hz)
        if not all(np.isfinite(v) and v > 0 for v in vals):
            raise ConfigError(f"every FIR specification value must be a positive number, got {self!r}")
        if not (self.pass_hz < self.stop_hz < 0.5 * self.fs_hz):
            raise ConfigError(
                f"need 0 < pass_hz < stop_hz < fs_hz / 2 = {0.5 * self.fs_hz:g} Hz; "
                f"got pass_hz={self.pass_hz:g}, stop_hz={self.stop_hz:g}"
            )

    @property
    def deltas(self) -> tuple[float, float]:
        """Pass-band and stop-band deviations ``(delta_p, delta_s)`` as amplitude fractions."""
        g = 10.0 ** (self.ripple_db / 20.0)
        return (g - 1.0) / (g + 1.0), 10.0 ** (-self.attenuation_db / 20.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class FirLowpass:
    """A designed equiripple low-pass and the response it achieves (one pass).

    Attributes:
        taps: (n_taps,) symmetric impulse response (linear phase, delay ``(n_taps - 1) / 2``).
        spec: the specification it was designed for.
        ripple_db: dB, achieved peak-to-peak pass-band ripple (<= ``spec.ripple_db``).
        attenuation_db: dB, achieved least stop-band attenuation (>= ``spec.attenuation_db``).
    """

    taps: np.ndarray
    spec: FirLowpassSpec
    ripple_db: float
    attenuation_db: float

    def apply(self, x: np.ndarray, axis: int = -1) -> np.ndarray:
        """Zero-phase (forward and backward) filtering along ``axis``, as MATLAB's ``filtfilt``.

        The two passes square the magnitude: the ripple at most doubles in dB, the attenuation
        doubles. Edges are padded by odd reflection over ``min(3 n_taps, n - 1)`` samples.

        Args:
            x: (..., n, ...) finite signal.
            axis: time axis.

        Returns:
            Filtered array, same shape.
        """
        x = _finite(x, "x")
        n = x.shape[axis]
        if n < 2:
            raise DataError(f"need at least 2 samples along axis {axis} to filter, got {n}")
        return signal.filtfilt(self.taps, [1.0], x, axis=axis, padlen=min(3 * self.taps.size, n - 1))

    def response(self, f_hz: np.ndarray) -> np.ndarray:
        """One-pass complex response at ``f_hz`` (Hz), same shape."""
        f = np.asarray(f_hz, dtype=float)
        return signal.freqz(self.taps, worN=f.reshape(-1), fs=self.spec.fs_hz)[1].reshape(f.shape)


def _achieved(taps: np.ndarray, spec: FirLowpassSpec) -> tuple[float, float]:
    """Peak-to-peak pass-band ripple and least stop-band attenuation (dB) on a dense grid."""
    fp = np.linspace(0.0, spec.pass_hz, 2001)
    fs = np.linspace(spec.stop_hz, 0.5 * spec.fs_hz, 20001)
    hp = np.abs(signal.freqz(taps, worN=fp, fs=spec.fs_hz)[1])
    hs = np.abs(signal.freqz(taps, worN=fs, fs=spec.fs_hz)[1])
    return float(20 * np.log10(hp.max() / hp.min())), float(-20 * np.log10(hs.max()))


def design_fir_lowpass(spec: FirLowpassSpec | None = None) -> FirLowpass:
    """Equiripple (Parks-McClellan) low-pass meeting ``spec`` (Sec. III-B of the fractional paper).

    Starts from Kaiser's length estimate for equiripple filters,
    ``N = (-20 log10(sqrt(delta_p delta_s)) - 13) / (14.6 (f_s - f_p) / fs) + 1``, weights the
    bands by ``1/delta``, and lengthens the filter by about 2 % until the response measured on a
    dense grid meets the specification.

    Args:
        spec: the specification; the paper's when None.

    Returns:
        The :class:`FirLowpass`.
    """
    spec = FirLowpassSpec() if spec is None else spec
    dp, ds = spec.deltas
    df = (spec.stop_hz - spec.pass_hz) / spec.fs_hz
    n0 = int(np.ceil((-20.0 * np.log10(np.sqrt(dp * ds)) - 13.0) / (14.6 * df))) + 1
    n = n0 | 1  # odd length: a type-I filter, no forced zero at Nyquist
    bands = [0.0, spec.pass_hz, spec.stop_hz, 0.5 * spec.fs_hz]
    while n <= n0 * (1 + _MAX_GROWTH):
        try:
            taps = signal.remez(n, bands, [1.0, 0.0], weight=[1.0, dp / ds], fs=spec.fs_hz, maxiter=100)
        except ValueError:
            taps = None
        if taps is not None:
            ripple, atten = _achieved(taps, spec)
            if ripple <= spec.ripple_db and atten >= spec.attenuation_db:
                return FirLowpass(taps=taps, spec=spec, ripple_db=ripple, attenuation_db=atten)
        n = (n + max(2, int(0.02 * n))) | 1
    raise ConfigError(
        f"no equiripple filter up to {n} taps meets {spec!r}; widen the transition band or relax "
        "the ripple or attenuation"
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class FrequencyResponse:
    """Welch estimate of a frequency response (Sec. III-B of the fractional paper).

    Attributes:
        f_hz: (n_f,) Hz, frequencies.
        G: (n_f,) complex, output per input (e.g. rad/N), H1 estimate ``P_uy / P_uu``.
        coherence: (n_f,) magnitude-squared coherence in [0, 1].
        fs_hz: Hz, sample rate of the signals.
        window_len: samples per Blackman-Harris segment.
        overlap: fraction of a segment shared with the next, in [0, 1).
        nfft: FFT length (>= ``window_len``; longer zero-pads).
        n_segments: number of averaged segments (per record; summed by :func:`average_responses`).
    """

    f_hz: np.ndarray
    G: np.ndarray
    coherence: np.ndarray
    fs_hz: float
    window_len: int
    overlap: float
    nfft: int
    n_segments: int

    def band(self, f_lo_hz: float, f_hi_hz: float) -> FrequencyResponse:
        """The response restricted to ``f_lo_hz <= f <= f_hi_hz`` (paper: 0.12-15 Hz)."""
        nyq = 0.5 * self.fs_hz
        if not (np.isfinite(f_lo_hz) and np.isfinite(f_hi_hz) and 0 <= f_lo_hz < f_hi_hz <= nyq):
            raise ConfigError(
                f"band [{f_lo_hz:g}, {f_hi_hz:g}] Hz is invalid: need 0 <= f_lo < f_hi <= the Nyquist "
                f"frequency {nyq:g} Hz"
            )
        keep = (self.f_hz >= f_lo_hz) & (self.f_hz <= f_hi_hz)
        if not np.any(keep):
            raise ConfigError(
                f"band [{f_lo_hz:g}, {f_hi_hz:g}] Hz holds no frequency of the estimate "
                f"(resolution {self.fs_hz / self.nfft:g} Hz)"
            )
        return replace(self, f_hz=self.f_hz[keep], G=self.G[keep], coherence=self.coherence[keep])

    @property
    def magnitude_db(self) -> np.ndarray:
        """(n_f,) dB re one unit of G, ``20 log10 |G|``."""
        return 20.0 * np.log10(np.abs(self.G))

    @property
    def phase_deg(self) -> np.ndarray:
        """(n_f,) deg, unwrapped phase of G."""
        return np.degrees(np.unwrap(np.angle(self.G)))


def _finite(x, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(x)):
        raise DataError(f"{name} contains {int(np.sum(~np.isfinite(x)))} non-finite value(s) (NaN or inf)")
    return x


def estimate_frf(
    u: np.ndarray,
    y: np.ndarray,
    fs_hz: float,
    window_len: int = 5000,
    overlap: float = 0.25,
    nfft: int | None = None,
) -> FrequencyResponse:
    """H1 frequency response ``y/u`` and coherence by Welch's method (Sec. III-B, MATLAB ``tfestimate``).

    Segments carry a symmetric Blackman-Harris window and the mean of each is removed.

    Args:
        u: (n,) input (e.g. measured force, N).
        y: (n,) output (e.g. elbow angle, rad), same length.
        fs_hz: Hz, sample rate.
        window_len: samples per segment (paper: 5000), 8 <= window_len <= n.
        overlap: fraction of overlap between segments, in [0, 1) (paper: 0.25).
        nfft: FFT length >= window_len; defaults to ``window_len``.

    Returns:
        The :class:`FrequencyResponse` from 0 Hz to Nyquist; ``G`` is NaN at 0 Hz (the segment
        means are removed), so fit on a :meth:`FrequencyResponse.band` above it.
    """
    u, y = _finite(u, "u"), _finite(y, "y")
    if u.ndim != 1 or u.shape != y.shape:
        raise DataError(f"u and y must be 1-D signals of equal length, got {u.shape} and {y.shape}")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ConfigError(f"fs_hz must be a positive number, got {fs_hz!r}")
    if isinstance(window_len, bool) or int(window_len) != window_len or window_len < 8:
        raise ConfigError(f"window_len must be an integer >= 8 samples, got {window_len!r}")
    if window_len > u.size:
        raise DataError(
            f"window of {int(window_len)} samples is longer than the signal ({u.size} samples, "
            f"{u.size / fs_hz:g} s); use window_len <= {u.size}"
        )
    if not (np.isfinite(overlap) and 0 <= overlap < 1):
        raise ConfigError(f"overlap must be a fraction in [0, 1), got {overlap!r}")
    nfft = int(window_len) if nfft is None else nfft
    if isinstance(nfft, bool) or int(nfft) != nfft or nfft < window_len:
        raise ConfigError(f"nfft must be an integer >= window_len = {int(window_len)}, got {nfft!r}")
    if np.ptp(u) == 0:
        raise DataError("the input u is constant: the frequency response is undefined")
    win = signal.windows.blackmanharris(int(window_len), sym=True)
    nover = int(round(overlap * window_len))
    kw = dict(fs=fs_hz, window=win, noverlap=nover, nfft=int(nfft), detrend="constant")
    f, Puu = signal.welch(u, **kw)
    _, Pyy = signal.welch(y, **kw)
    _, Puy = signal.csd(u, y, **kw)  # E[conj(U) Y]
    with np.errstate(divide="ignore", invalid="ignore"):
        G = Puy / Puu
        coh = np.clip(np.abs(Puy) ** 2 / (Puu * Pyy), 0.0, 1.0)
    G[0], coh[0] = np.nan, 0.0  # segment means are removed: nothing is known at 0 Hz
    return FrequencyResponse(
        f_hz=f,
        G=G,
        coherence=np.nan_to_num(coh),
        fs_hz=float(fs_hz),
        window_len=int(window_len),
        overlap=float(overlap),
        nfft=int(nfft),
        n_segments=(u.size - int(window_len)) // (int(window_len) - nover) + 1,
    )


def average_responses(responses: Sequence[FrequencyResponse]) -> FrequencyResponse:
    """Mean of several estimates on one grid (the paper fits the subjects' mean response).

    ``G`` and the coherence are averaged arithmetically; ``n_segments`` is summed.
    """
    if not responses:
        raise DataError("need at least one FrequencyResponse to average")
    first = responses[0]
    for r in responses[1:]:
        if r.f_hz.shape != first.f_hz.shape or not np.allclose(r.f_hz, first.f_hz, rtol=1e-12, atol=0):
            raise DataError("responses to average must share one frequency grid (same fs, nfft, band)")
    return replace(
        first,
        G=np.mean([r.G for r in responses], axis=0),
        coherence=np.mean([r.coherence for r in responses], axis=0),
        n_segments=int(sum(r.n_segments for r in responses)),
    )

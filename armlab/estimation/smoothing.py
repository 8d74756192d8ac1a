"""Smoothing and differentiation filters of Sec. III-A and Fig. 3 of the virtual-sensor paper.

Every measured signal is smoothed by a Savitzky-Golay (SG) filter, a least-squares polynomial of
order ``N`` fitted to a centred window of ``W`` samples and evaluated at the window's centre; the
polynomial's derivative there gives the signal's first time derivative. Both outputs then pass a
zero-phase (forward-backward) Butterworth low-pass. The paper calls SG smoothing + Butterworth the
*smoothing filter* and SG differentiation + Butterworth the *differentiation filter*; with its
``N = 6``, ``W = 151`` at 1 kHz and a 5th-order 4.5 Hz low-pass the first has near-unit gain and the
second the gain of an ideal differentiator over the 0-2 Hz band of the perturbation, and both
fall to zero above ~4.5 Hz. Near the record's ends the SG stage evaluates the polynomial fitted to
the first/last full window (``mode="interp"``, as MATLAB's ``sgolayfilt``) and ``sosfiltfilt``
pads by odd extension (18 samples for the paper's low-pass), so the first and last second carry
edge transients: with the paper's settings a 0.1-2 Hz signal's derivative errs by up to a quarter
of its peak at the very ends, and by no more than in the interior from ~0.75 s in.

``scipy.signal.savgol_coeffs`` solves an unscaled Vandermonde system (condition ~1e11 for
``W = 151``, ``N = 6``): its smoothing taps sum to 1 + 6.1e-6, a DC gain error far below
measurement noise; :func:`filter_response` uses the same taps and so reproduces it.

The SG and Butterworth stages are :mod:`armlab.dsp`'s (:func:`~armlab.dsp.savgol`,
:func:`~armlab.dsp.butterworth`, :func:`~armlab.dsp.zero_phase`); this module holds the paper's
settings and the two filters composed from them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from armlab.dsp import butterworth, savgol, savgol_taps, sosfiltfilt_padlen, zero_phase
from armlab.errors import ConfigError, DataError

__all__ = [
    "lowpass",
    "SmoothingSpec",
    "differentiate",
    "filter_response",
    "smooth",
    "smooth_and_differentiate",
]

# Sec. III-A of the virtual-sensor paper ("a filter with N = 6 and W = 151 was found to yield
# optimal results"; "zero-phase 5th-order Butterworth low-pass filter ... 4.5 Hz cutoff").
PAPER_SG_ORDER = 6  # polynomial order N, dimensionless
PAPER_SG_WINDOW = 151  # window W, samples (151 ms at the paper's 1 kHz)
PAPER_LOWPASS_HZ = 4.5  # Hz, cut-off of the one-way Butterworth prototype
PAPER_LOWPASS_ORDER = 5  # order of the one-way Butterworth prototype


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


@dataclass(frozen=True, kw_only=True)
class SmoothingSpec:
    """Settings of the smoothing and differentiation filters (Sec. III-A of the virtual-sensor paper).

    Attributes:
        sg_order: Savitzky-Golay polynomial order ``N``, an integer >= 1 (the first derivative of a
            polynomial of order 0 is identically zero) and < ``sg_window``.
        sg_window: samples, Savitzky-Golay window ``W``: an odd integer > ``sg_order`` (odd so the
            window is centred on the sample it estimates).
        lowpass_hz: Hz, cut-off of the one-way Butterworth prototype applied forward and backward
            (``sosfiltfilt``), > 0 and below the Nyquist frequency of the data; ``None`` disables
            the Butterworth stage (SG only).
        lowpass_order: order of the one-way Butterworth prototype, an integer >= 1 (the
            forward-backward pass doubles the attenuation).
    """

    sg_order: int = PAPER_SG_ORDER
    sg_window: int = PAPER_SG_WINDOW
    lowpass_hz: float | None = PAPER_LOWPASS_HZ
    lowpass_order: int = PAPER_LOWPASS_ORDER

    def __post_init__(self) -> None:
        if not _is_int(self.sg_order) or self.sg_order < 1:
            raise ConfigError(
                f"sg_order must be an integer >= 1 (the first derivative needs order >= 1), "
                f"got {self.sg_order!r}"
            )
        if not _is_int(self.sg_window) or self.sg_window % 2 != 1 or self.sg_window <= self.sg_order:
            raise ConfigError(
                f"sg_window must be an odd integer number of samples > sg_order; got window "
                f"{self.sg_window!r} with order {self.sg_order} (try {_next_odd_above(self.sg_order)} "
                f"or larger; the paper uses {PAPER_SG_WINDOW} with order {PAPER_SG_ORDER})"
            )
        if self.lowpass_hz is not None and not (
            isinstance(self.lowpass_hz, (int, float, np.integer, np.floating))
            and not isinstance(self.lowpass_hz, (bool, np.bool_))
            and np.isfinite(self.lowpass_hz)
            and self.lowpass_hz > 0
        ):
            raise ConfigError(
                f"lowpass_hz must be None (no Butterworth stage) or a positive number of Hz, "
                f"got {self.lowpass_hz!r}"
            )
        if not _is_int(self.lowpass_order) or self.lowpass_order < 1:
            raise ConfigError(f"lowpass_order must be an integer >= 1, got {self.lowpass_order!r}")

    def check(self, fs_hz: float, n_samples: int) -> None:
        """Raise if this spec cannot filter ``n_samples`` samples taken at ``fs_hz``.

        Args:
            fs_hz: Hz, sample rate, > 0.
            n_samples: length of the signal along its time axis.

        Raises:
            DataError: ``fs_hz`` is not a positive number, or the signal is shorter than the SG
                window or than the padding ``sosfiltfilt`` needs.
            ConfigError: ``lowpass_hz`` is at or above the Nyquist frequency ``fs_hz / 2``.
        """
        sos = self._butter(fs_hz)
        needed = self.sg_window if sos is None else max(self.sg_window, sosfiltfilt_padlen(sos) + 1)
        if n_samples < needed:
            why = [f"{self.sg_window} for the SG window"]
            if sos is not None:
                why.append(
                    f"{sosfiltfilt_padlen(sos) + 1} to pad the zero-phase order-{self.lowpass_order} low-pass"
                )
            raise DataError(
                f"signal has {n_samples} samples along its time axis; need at least {needed} "
                f"({' and '.join(why)})"
            )

    def _butter(self, fs_hz: float) -> np.ndarray | None:
        """(n_sections, 6) Butterworth sections at ``fs_hz``, or None without a low-pass stage."""
        if isinstance(fs_hz, (bool, np.bool_)) or not (np.isfinite(fs_hz) and fs_hz > 0):
            raise DataError(f"fs_hz must be a positive number of Hz, got {fs_hz!r}")
        if self.lowpass_hz is None:
            return None
        nyquist = 0.5 * fs_hz
        if self.lowpass_hz >= nyquist:
            raise ConfigError(
                f"lowpass_hz = {self.lowpass_hz:g} Hz must lie below the Nyquist frequency "
                f"{nyquist:g} Hz (fs = {fs_hz:g} Hz), or be None for no low-pass"
            )
        return butterworth(self.lowpass_hz, fs_hz, self.lowpass_order)


def _next_odd_above(n: int) -> int:
    return n + 1 if n % 2 == 0 else n + 2


def _prepare(
    x: np.ndarray, fs_hz: float, spec: SmoothingSpec, axis: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """Validate the input; return it as float and the Butterworth sections (None: no low-pass)."""
    x = np.asarray(x, dtype=float)
    if not -x.ndim <= axis < x.ndim:
        raise DataError(
            f"axis {axis} is out of range for a signal of shape {x.shape}; valid: -{x.ndim}..{x.ndim - 1}"
        )
    if not np.all(np.isfinite(x)):
        raise DataError(f"signal contains {int(np.sum(~np.isfinite(x)))} non-finite value(s) (NaN or inf)")
    spec.check(fs_hz, x.shape[axis])
    return x, spec._butter(fs_hz)


def _filter(
    x: np.ndarray, fs_hz: float, spec: SmoothingSpec, axis: int, sos: np.ndarray | None, deriv: int
) -> np.ndarray:
    """SG estimate of derivative ``deriv`` (delta = 1/fs, so per second), then the low-pass if any."""
    y = savgol(x, fs_hz, spec.sg_window, spec.sg_order, deriv=deriv, axis=axis)
    return y if sos is None else zero_phase(sos, y, axis=axis)


def smooth(x: np.ndarray, fs_hz: float, spec: SmoothingSpec | None = None, axis: int = 0) -> np.ndarray:
    """The smoothing filter: SG smoothing, then the zero-phase Butterworth (Sec. III-A, Fig. 3).

    Args:
        x: (n_samples,), (n_samples, n_channels), (n_trials, n_samples, n_channels) or any shape,
            any unit; filtered along ``axis``.
        fs_hz: Hz, sample rate.
        spec: filter settings; the paper's (``SmoothingSpec()``) when None.
        axis: time axis.

    Returns:
        The smoothed signal, same shape and unit as ``x``.

    Raises:
        DataError: ``x`` has NaN/inf, is too short (see :meth:`SmoothingSpec.check`) or ``axis``
            is out of range.
        ConfigError: the low-pass cut-off is at or above Nyquist.
    """
    spec = SmoothingSpec() if spec is None else spec
    x, sos = _prepare(x, fs_hz, spec, axis)
    return _filter(x, fs_hz, spec, axis, sos, deriv=0)


def lowpass(x: np.ndarray, fs_hz: float, spec: SmoothingSpec | None = None, axis: int = 0) -> np.ndarray:
    """The zero-phase Butterworth stage alone (``x`` unchanged when ``spec.lowpass_hz`` is None).

    For signals computed from SG outputs through nonlinear maps (kinematics, Eq. (2), products in
    a regressor): filtering the final signals keeps both sides of a regression filtered alike.
    Same arguments and errors as :func:`smooth`.
    """
    spec = SmoothingSpec() if spec is None else spec
    x, sos = _prepare(x, fs_hz, spec, axis)
    return x if sos is None else zero_phase(sos, x, axis=axis)


def differentiate(
    x: np.ndarray, fs_hz: float, spec: SmoothingSpec | None = None, axis: int = 0
) -> np.ndarray:
    """The differentiation filter: SG first derivative, then the zero-phase Butterworth (Sec. III-A).

    Args:
        x: signal of any shape, filtered along ``axis`` (see :func:`smooth`).
        fs_hz: Hz, sample rate.
        spec: filter settings; the paper's (``SmoothingSpec()``) when None.
        axis: time axis.

    Returns:
        The time derivative, same shape as ``x``, in units of x per second.

    Raises:
        DataError, ConfigError: as :func:`smooth`.
    """
    spec = SmoothingSpec() if spec is None else spec
    x, sos = _prepare(x, fs_hz, spec, axis)
    return _filter(x, fs_hz, spec, axis, sos, deriv=1)


def smooth_and_differentiate(
    x: np.ndarray, fs_hz: float, spec: SmoothingSpec | None = None, axis: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Both outputs of the paper's SG stage, each low-passed: ``(smooth(x), differentiate(x))``.

    Args:
        x: signal of any shape, filtered along ``axis`` (see :func:`smooth`).
        fs_hz: Hz, sample rate.
        spec: filter settings; the paper's (``SmoothingSpec()``) when None.
        axis: time axis.

    Returns:
        ``(x_smooth, x_dot)`` shaped like ``x``, in units of x and x per second.
    """
    spec = SmoothingSpec() if spec is None else spec
    x, sos = _prepare(x, fs_hz, spec, axis)
    return _filter(x, fs_hz, spec, axis, sos, deriv=0), _filter(x, fs_hz, spec, axis, sos, deriv=1)


def filter_response(
    spec: SmoothingSpec | None, fs_hz: float, freqs_hz: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Frequency responses of the smoothing and differentiation filters (Fig. 3 of the virtual-sensor paper).

    The centred SG filter is the non-causal FIR ``y[n] = sum_k c[k] x[n - k]``, ``k = -M..M``,
    ``M = (W - 1) / 2``, with ``c`` from ``savgol_coeffs(..., use="conv")``; its response
    ``sum_k c[k] exp(-j w k)`` (``w = 2 pi f / fs``) is ``freqz`` of the causal taps times
    ``exp(j w M)``. The taps are symmetric for the smoothing filter (real response) and
    antisymmetric for the differentiator (imaginary response, ``~ j 2 pi f`` at low frequency).
    ``sosfiltfilt`` multiplies both by ``|H_butter|^2`` with zero phase. Interior samples of
    :func:`smooth` and :func:`differentiate` (away from the edge transients) follow these exactly.

    Args:
        spec: filter settings; the paper's (``SmoothingSpec()``) when None.
        fs_hz: Hz, sample rate.
        freqs_hz: (...) Hz, finite frequencies at which to evaluate.

    Returns:
        ``(h_smooth, h_diff)`` complex, shaped like ``freqs_hz``: the smoothing filter's response
        (dimensionless, real) and the differentiation filter's (1/s, purely imaginary; the ideal
        differentiator is ``j 2 pi f``).

    Raises:
        DataError: ``fs_hz`` is not a positive number, or ``freqs_hz`` has NaN/inf.
        ConfigError: the low-pass cut-off is at or above Nyquist.
    """
    spec = SmoothingSpec() if spec is None else spec
    freqs = np.asarray(freqs_hz, dtype=float)
    if not np.all(np.isfinite(freqs)):
        raise DataError(f"freqs_hz must be finite numbers of Hz; {int(np.sum(~np.isfinite(freqs)))} are not")
    sos = spec._butter(fs_hz)
    f = freqs.ravel()
    half = (spec.sg_window - 1) // 2
    # undo the causal realisation's delay of `half` samples: the centred SG filter has zero phase
    advance = np.exp(1j * 2.0 * np.pi * f / fs_hz * half)
    out = []
    for deriv in (0, 1):
        taps = savgol_taps(fs_hz, spec.sg_window, spec.sg_order, deriv=deriv)
        _, h = signal.freqz(taps, worN=f, fs=fs_hz)
        h = h * advance
        # drop the round-off part: the symmetric (antisymmetric) taps give a real (imaginary) response
        out.append(h.real + 0j if deriv == 0 else 1j * h.imag)
    if sos is not None:
        _, hb = signal.sosfreqz(sos, worN=f, fs=fs_hz)
        gain = np.abs(hb) ** 2  # forward-backward: squared magnitude, zero phase
        out = [h * gain for h in out]
    return out[0].reshape(freqs.shape), out[1].reshape(freqs.shape)

"""Signal processing shared by the whole package: low-pass filters and numerical derivatives.

One place for every filter armlab designs or applies to a sampled signal:

- Butterworth design (:func:`butterworth`, low- or high-pass, sections or ``(b, a)``), applied
  without phase lag (:func:`zero_phase`, :func:`lowpass_zero_phase`) or causally as a sensor
  does (:func:`lowpass_causal`);
- the second-order low-pass ``wn² / (s² + 2 ζ wn s + wn²)`` of muscle activation and reflex
  dynamics (:func:`second_order_ba` for a stateful closed-loop user, :func:`second_order_lowpass`
  to filter a whole record);
- Savitzky-Golay smoothing and derivatives (:func:`savgol`, :func:`savgol_taps`);
- five-point central differences for first and second derivatives
  (:func:`five_point_derivatives`);
- the step of the grid a quantised recording lies on (:func:`grid_step`).

Every function is a thin, documented layer over ``scipy.signal`` or NumPy: the exact call
sequence is part of the contract (armlab's recorded results are reproduced bit for bit), so a
change here changes every protocol's numbers. This module sits at the bottom of the package: it
imports only NumPy, SciPy and :mod:`armlab.errors`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from typing import Literal

import numpy as np
from scipy import signal

from armlab.cpus import usable_cpus
from armlab.errors import ConfigError, DataError

__all__ = [
    "bilinear",
    "by_row_halves",
    "butterworth",
    "five_point_derivatives",
    "grid_step",
    "lowpass_causal",
    "lowpass_zero_phase",
    "savgol",
    "savgol_taps",
    "second_order_ba",
    "second_order_lowpass",
    "sosfiltfilt_padlen",
    "zero_phase",
]

_STARTS = ("rest", "steady", "deviation")


def butterworth(
    cutoff_hz: float | tuple[float, float],
    fs_hz: float,
    order: int,
    *,
    btype: Literal["low", "high", "bandpass"] = "low",
    output: Literal["sos", "ba"] = "sos",
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Digital Butterworth filter by the bilinear transform with pre-warping (``scipy.signal.butter``).

    The gain is exactly -3 dB (1/sqrt 2) at ``cutoff_hz``. Designs are remembered. No range
    check: the callers phrase their own (``cutoff_hz`` must lie in (0, fs_hz / 2), else scipy
    raises ``ValueError``).

    Args:
        cutoff_hz: Hz, -3 dB frequency; ``(low, high)`` for a band-pass.
        fs_hz: Hz, sample rate.
        order: filter order, >= 1 (a band-pass has twice as many poles).
        btype: ``"low"`` (low-pass), ``"high"`` (high-pass) or ``"bandpass"``.
        output: ``"sos"`` for (n_sections, 6) second-order sections, ``"ba"`` for the transfer
            function's ``(b, a)`` coefficient vectors (order + 1,) each.

    Returns:
        The sections, or ``(b, a)``.
    """
    # a hashable key for the remembered design; a pair (band-pass) as list, tuple or array
    cutoff = tuple(map(float, np.ravel(cutoff_hz))) if np.ndim(cutoff_hz) else float(cutoff_hz)
    out = _butter(int(order), cutoff, btype, float(fs_hz), output)
    return tuple(a.copy() for a in out) if isinstance(out, tuple) else out.copy()


@lru_cache(maxsize=1024)
def _butter(order: int, cutoff, btype: str, fs_hz: float, output: str):
    """:func:`butterworth`'s design, remembered (callers get copies): a fit filters with the same
    few designs thousands of times, and SciPy's design (~3 ms) costs more than filtering a trial."""
    return signal.butter(order, cutoff, btype=btype, fs=fs_hz, output=output)


def sosfiltfilt_padlen(sos: np.ndarray) -> int:
    """``sosfiltfilt``'s default odd-extension length; a signal must be longer than this.

    Same rule as ``scipy.signal.sosfiltfilt`` (scipy/signal/_signaltools.py): 3 x the number of
    taps ``2 n_sections + 1``, less the trailing zero coefficients of first-order sections.

    Args:
        sos: (n_sections, 6) second-order sections.

    Returns:
        Samples of padding at each end.
    """
    ntaps = 2 * sos.shape[0] + 1 - min(int(np.sum(sos[:, 2] == 0)), int(np.sum(sos[:, 5] == 0)))
    return 3 * ntaps


def zero_phase(sos: np.ndarray, x: np.ndarray, axis: int = -1, padtype: str = "odd") -> np.ndarray:
    """Forward-backward filtering by ``sos`` (``scipy.signal.sosfiltfilt``): gain ``|H|²``, no phase.

    Args:
        sos: (n_sections, 6) second-order sections (e.g. from :func:`butterworth`).
        x: signal of any shape and unit, filtered along ``axis`` (longer than
            :func:`sosfiltfilt_padlen` samples).
        axis: time axis.
        padtype: edge extension before filtering: ``"odd"`` (scipy's default) pins the end samples
            to their raw values; ``"even"`` mirrors them, so an end sample's noise is band-limited
            like the others'.

    Returns:
        Filtered array, same shape and unit as ``x``.
    """
    sos = np.asarray(sos)
    x = np.asarray(x)
    if padtype not in ("odd", "even") or sos.dtype != np.float64 or x.dtype != np.float64 or x.ndim == 0:
        return signal.sosfiltfilt(sos, x, axis=axis, padtype=padtype)
    # scipy.signal.sosfiltfilt's steps, one by one (so the same numbers to the bit), with the
    # filter's step-response state remembered per design: SciPy builds it afresh on each call
    # (a companion matrix and a solve per section), a quarter of a 15 000-sample column's cost,
    # and a diagnosis filters ~10^4 columns with the same few designs
    edge = sosfiltfilt_padlen(sos)
    axis = axis % x.ndim
    if x.shape[axis] <= edge:
        raise ValueError(f"The length of the input vector x must be greater than padlen, which is {edge}.")

    def cut(z, start=None, stop=None, step=None):
        index = [slice(None)] * z.ndim
        index[axis] = slice(start, stop, step)
        return z[tuple(index)]

    left, right = cut(x, edge, 0, -1), cut(x, -2, -(edge + 2), -1)
    if padtype == "odd":
        left, right = 2 * cut(x, 0, 1) - left, 2 * cut(x, -1) - right
    ext = np.concatenate((left, x, right), axis=axis)
    shape = [1] * x.ndim
    shape[axis] = 2
    zi = _sos_zi(sos.tobytes(), sos.shape[0]).reshape([sos.shape[0]] + shape)
    y, _ = signal.sosfilt(sos, ext, axis=axis, zi=zi * cut(ext, stop=1))
    y, _ = signal.sosfilt(sos, cut(y, step=-1), axis=axis, zi=zi * cut(y, start=-1))
    return cut(cut(y, step=-1), edge, -edge)


@lru_cache(maxsize=256)
def _sos_zi(key: bytes, n_sections: int) -> np.ndarray:
    """``scipy.signal.sosfilt_zi`` of the sections stored in ``key`` (read-only, remembered)."""
    zi = signal.sosfilt_zi(np.frombuffer(key).reshape(n_sections, 6))
    zi.flags.writeable = False
    return zi


def lowpass_zero_phase(
    x: np.ndarray, fs_hz: float, cutoff_hz: float | None, order: int = 4, axis: int = -2, padtype: str = "odd"
) -> np.ndarray:
    """Phase-free Butterworth low-pass (``sosfiltfilt``), Sec. IV-C of the conditioning paper.

    Args:
        x: (..., n_samples, n_axes) signal; filtered along ``axis``.
        fs_hz: Hz, sample rate.
        cutoff_hz: Hz, -3 dB frequency of the one-way filter, in (0, fs_hz / 2); ``None`` returns a
            copy of ``x`` unchanged.
        order: Butterworth order of the one-way filter (the forward-backward pass doubles the
            attenuation: the two-way gain at ``cutoff_hz`` is -6 dB).
        axis: time axis.
        padtype: ``sosfiltfilt``'s edge extension: ``"odd"`` pins the end samples to their raw
            values; ``"even"`` mirrors them, so an end sample's noise is band-limited like the
            others' (the diagnosis's torque).

    Returns:
        Filtered array, same shape as ``x``.

    Raises:
        ConfigError: ``cutoff_hz`` outside (0, fs_hz / 2).
        DataError: ``x`` too short along ``axis`` for the filter's edge padding.
    """
    x = np.asarray(x, dtype=float)
    if cutoff_hz is None:
        return x.copy()
    nyquist = 0.5 * fs_hz
    if not (0 < cutoff_hz < nyquist):
        raise ConfigError(
            f"cutoff_hz must lie in (0, {nyquist:g}) Hz (below Nyquist at fs={fs_hz:g} Hz), got {cutoff_hz!r}"
        )
    sos = butterworth(cutoff_hz, fs_hz, order)
    try:
        return zero_phase(sos, x, axis=axis, padtype=padtype)
    except ValueError as err:
        raise DataError(
            f"signal too short for an order-{order} zero-phase filter along axis {axis} "
            f"(shape {x.shape}): {err}"
        ) from None


def lowpass_causal(
    x: np.ndarray,
    fs_hz: float,
    cutoff_hz: float,
    order: int = 2,
    axis: int = -1,
    start: Literal["rest", "steady", "deviation"] = "rest",
) -> np.ndarray:
    """Causal Butterworth low-pass (``scipy.signal.lfilter`` of the ``(b, a)`` design), as a sensor filters.

    Three ways to start the filter at the record's first sample ``x0``:

    - ``"rest"``: zero state (a signal that was zero before the record);
    - ``"steady"``: the state the filter reaches under a constant input ``x0``
      (``lfilter_zi(b, a) * x0``), for a sensor that ran long before the record: a constant passes
      unchanged and no start-up transient appears;
    - ``"deviation"``: ``lfilter(b, a, x - x0) + x0``, the same steady start written as filtering
      the deviation from ``x0`` from rest. It equals ``"steady"`` up to round-off (both are exact
      for a filter of unit DC gain); both are kept because the simulated sensor (``"steady"``)
      and the diagnosis's sensor surrogate (``"deviation"``) have recorded results to reproduce.

    Args:
        x: signal of any shape and unit, filtered along ``axis``.
        fs_hz: Hz, sample rate.
        cutoff_hz: Hz, -3 dB frequency, in (0, fs_hz / 2) (the caller checks it).
        order: Butterworth order, >= 1.
        axis: time axis.
        start: initial state, one of ``"rest"``, ``"steady"``, ``"deviation"`` (above).

    Returns:
        Filtered array, same shape and unit as ``x``.

    Raises:
        ConfigError: unknown ``start``.
    """
    if start not in _STARTS:
        raise ConfigError(f"start must be one of {_STARTS}, got {start!r}")
    b, a = butterworth(cutoff_hz, fs_hz, order, output="ba")
    if start == "rest":
        return signal.lfilter(b, a, x, axis=axis)
    x0 = np.take(x, [0], axis=axis)  # first sample, kept as a length-1 time axis
    if start == "deviation":
        return signal.lfilter(b, a, x - x0, axis=axis) + x0
    shape = [1] * np.ndim(x)
    shape[axis] = -1
    zi = signal.lfilter_zi(b, a).reshape(shape) * x0  # (order,) along the time axis, scaled per channel
    y, _ = signal.lfilter(b, a, x, axis=axis, zi=zi)
    return y


@lru_cache(maxsize=4096)
def _bilinear(num: tuple[float, ...], den: tuple[float, ...], fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    return signal.bilinear(num, den, fs_hz)


def bilinear(num, den, fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.signal.bilinear(num, den, fs_hz)``, remembered for repeated coefficients.

    A fit evaluates the same analogue filter for every trial and again at every revisited
    parameter; SciPy's polynomial algebra costs ~1 ms a call, far more than filtering the data.
    Returns copies (callers may keep or change them).
    """
    b, a = _bilinear(tuple(float(x) for x in num), tuple(float(x) for x in den), float(fs_hz))
    return b.copy(), a.copy()


def second_order_ba(natural_hz: float, damping_ratio: float, fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of ``wn² / (s² + 2 ζ wn s + wn²)``, ``wn = 2 pi natural_hz``, by the bilinear transform.

    The second-order activation (and reflex) dynamics of muscle: unit DC gain, and for
    ``damping_ratio`` < 1 a step response overshooting by ``exp(-pi ζ / sqrt(1 - ζ²))``. The
    bilinear map is not pre-warped, so the digital filter matches the analogue one for
    ``natural_hz`` well below ``fs_hz / 2``. A stateful user (a closed loop filtering one chunk
    at a time) passes these to ``lfilter`` with its own ``zi``.

    Args:
        natural_hz: Hz, undamped natural frequency ``wn / 2 pi``, > 0.
        damping_ratio: 1, ``ζ`` > 0.
        fs_hz: Hz, sample rate.

    Returns:
        ``(b, a)``, (3,) each.
    """
    w = 2.0 * math.pi * natural_hz  # rad/s
    return bilinear([w * w], [1.0, 2.0 * damping_ratio * w, w * w], fs_hz)


def second_order_lowpass(
    x: np.ndarray, fs_hz: float, natural_hz: float, damping_ratio: float, axis: int = -1
) -> np.ndarray:
    """``x`` through :func:`second_order_ba`'s filter, causal and started at rest, along ``axis``.

    Args:
        x: signal of any shape and unit.
        fs_hz: Hz, sample rate.
        natural_hz: Hz, natural frequency.
        damping_ratio: 1, damping ratio.
        axis: time axis.

    Returns:
        Filtered array, same shape and unit as ``x``.
    """
    b, a = second_order_ba(natural_hz, damping_ratio, fs_hz)
    return signal.lfilter(b, a, x, axis=axis)


def savgol(
    x: np.ndarray, fs_hz: float, window: int, order: int, deriv: int = 0, axis: int = -1
) -> np.ndarray:
    """Savitzky-Golay estimate of ``x`` (``deriv = 0``) or of its ``deriv``-th time derivative.

    A least-squares polynomial of ``order`` fitted to a centred window of ``window`` samples and
    evaluated (or differentiated) at the window's centre; near the ends the polynomial of the
    first/last full window is used (``mode="interp"``, as MATLAB's ``sgolayfilt``).

    Args:
        x: signal of any shape and unit, filtered along ``axis`` (at least ``window`` samples).
        fs_hz: Hz, sample rate (the derivative is per second).
        window: samples, odd, > ``order``.
        order: polynomial order.
        deriv: derivative order, 0 for smoothing.
        axis: time axis.

    Returns:
        Same shape as ``x``, in units of x per s^deriv.
    """
    return signal.savgol_filter(x, window, order, deriv=deriv, delta=1.0 / fs_hz, axis=axis, mode="interp")


def savgol_taps(fs_hz: float, window: int, order: int, deriv: int = 0) -> np.ndarray:
    """(window,) convolution taps of the centred Savitzky-Golay filter of :func:`savgol` (interior).

    ``scipy.signal.savgol_coeffs`` solves an unscaled Vandermonde system (condition ~1e11 for
    ``window = 151``, ``order = 6``): its smoothing taps then sum to 1 + 6.1e-6, and
    :func:`savgol` uses the same taps.

    Args:
        fs_hz: Hz, sample rate.
        window: samples, odd, > ``order``.
        order: polynomial order.
        deriv: derivative order.

    Returns:
        Taps ``c`` with ``y[n] = sum_k c[k] x[n - k + (window - 1) / 2]``, per s^deriv.
    """
    return signal.savgol_coeffs(window, order, deriv=deriv, delta=1.0 / fs_hz, use="conv")


def five_point_derivatives(x: np.ndarray, fs_hz: float, axis: int = -2) -> tuple[np.ndarray, np.ndarray]:
    """First and second time derivatives by fourth-order central differences (Sec. IV-C).

    Interior samples use the five-point stencils
    ``x' = (-x[+2] + 8 x[+1] - 8 x[-1] + x[-2]) / (12 dt)`` and
    ``x'' = (-x[+2] + 16 x[+1] - 30 x[0] + 16 x[-1] - x[-2]) / (12 dt²)`` (truncation
    ``O(dt⁴)``); the two samples at each end use ``np.gradient`` (second order; the second
    derivative there is the gradient of the first). Fourth order matters for the conditioning
    paper's shortest windows: a 50 ms quintic sampled at 1 kHz has a ~0.8 % acceleration error
    with ``np.gradient`` applied twice (an effective 2 dt stencil), which the ill-conditioned
    11-parameter fit (cond(W) ~ 3e3) turns into a few % error in K.

    Args:
        x: (..., n_samples, n_axes) signal (n_samples >= 5 along ``axis``).
        fs_hz: Hz, sample rate.
        axis: time axis.

    Returns:
        ``(xd, xdd)`` shaped like ``x``, in units of x per s and per s².

    Raises:
        DataError: fewer than 5 samples along ``axis``.
    """
    x = np.asarray(x, dtype=float)
    if x.shape[axis] < 5:
        raise DataError(f"need at least 5 samples along axis {axis} to differentiate, got {x.shape[axis]}")
    dt = 1.0 / fs_hz
    xm = np.moveaxis(x, axis, 0)
    xd = np.gradient(xm, dt, axis=0, edge_order=2)
    xdd = np.gradient(xd, dt, axis=0, edge_order=2)
    xd[2:-2] = (-xm[4:] + 8.0 * xm[3:-1] - 8.0 * xm[1:-3] + xm[:-4]) / (12.0 * dt)
    xdd[2:-2] = (-xm[4:] + 16.0 * xm[3:-1] - 30.0 * xm[2:-2] + 16.0 * xm[1:-3] - xm[:-4]) / (12.0 * dt * dt)
    return np.moveaxis(xd, 0, axis), np.moveaxis(xdd, 0, axis)


_GRID_TOL = 0.01  # of a step: a change within this of a whole number of steps is on the grid
_GRID_SHARE = 0.99  # of the changes that must be on the grid
_MIN_CHANGES = 20  # changes needed to read a grid at all
# changes below this fraction of the largest |value| are the file's rounding (CSV: %.9g keeps
# 5e-9 of a value), not the sensor's: they are taken as no change
_ROUNDING = 1e-8


def grid_step(x_raw: np.ndarray) -> float:
    """The step of the grid a recorded signal lies on (its unit: an encoder's angle, a converter's
    torque), or 0.0 if it lies on none.

    The smallest changes between samples are the step (their mean within 1.5 of the smallest);
    the signal is on that grid when at least ``_GRID_SHARE`` of all changes are whole multiples
    of it within ``_GRID_TOL`` of a step (a grid offset cancels in the differences).
    """
    x = np.asarray(x_raw, float)
    d = np.abs(np.diff(x))
    d = d[d > _ROUNDING * max(float(np.max(np.abs(x))), 1e-300)]
    if d.size < _MIN_CHANGES:
        return 0.0
    q0 = float(np.min(d))
    q = float(np.mean(d[d < 1.5 * q0]))
    r = d / q
    on = np.abs(r - np.round(r)) < _GRID_TOL
    return q if np.mean(on) >= _GRID_SHARE else 0.0


def by_row_halves(fill: Callable[[slice], None], n_rows: int) -> None:
    """Call ``fill(rows)`` for the first and the second half of ``n_rows`` rows on two threads
    (one call with every row when there are fewer than 2 rows or cores).

    For work that releases the GIL (NumPy/SciPy array loops, compiled nogil kernels) and computes
    each row alone: ``fill`` writes its rows of a preallocated output, so the result is
    bit-identical to one call over every row. An error in either half is raised.
    """
    if n_rows < 2 or usable_cpus() < 2:
        fill(slice(0, n_rows))
        return
    half = n_rows // 2
    with ThreadPoolExecutor(2) as pool:
        list(pool.map(fill, (slice(0, half), slice(half, None))))

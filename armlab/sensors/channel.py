"""One sensor channel: how a clean simulated signal becomes what an instrument records.

A :class:`ChannelSpec` describes the imperfections of one kind of sensor (white noise, the offset
left after taring, slow drift, quantisation, limited bandwidth, transport delay) and
:func:`apply_channel` applies them to a batch of clean trials in one vectorised pass.

Order of operations (each stage sees the output of the previous one)::

    clean -> low-pass (bandwidth) -> delay -> + bias + drift*(t + t0) + noise -> quantise

The low-pass models the sensor's own dynamics and anti-alias/DSP filtering, so it acts on the
physical signal only; the electrical noise, bias and drift are added after it, and quantisation by
the converter comes last, so every recorded value lies on the quantisation grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.dsp import lowpass_causal
from armlab.errors import ConfigError, DataError

__all__ = [
    "ChannelSpec",
    "apply_channel",
]

_FILTER_ORDERS = (1, 2)


def _check_nonneg(name: str, value: float) -> None:
    if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value) and value >= 0):
        raise ConfigError(f"ChannelSpec.{name} must be a finite number >= 0, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class ChannelSpec:
    """Imperfections of one sensor channel; all amplitudes in the channel's own unit.

    Attributes:
        noise_std: std of additive white Gaussian noise per sample, [unit]. 0 = none.
        bias_std: std of a constant per-trial, per-axis offset drawn from N(0, bias_std²), [unit];
            models the unknown residual offset after taring the sensor. 0 = none.
        drift_per_s: std of a per-trial, per-axis linear drift rate drawn from
            N(0, drift_per_s²), [unit/s]; the drift is zero at the tare instant. 0 = none.
        quant_step: quantisation step (resolution, one LSB), [unit]; values are rounded to the
            nearest multiple (mid-tread). 0 = no quantisation.
        bandwidth_hz: -3 dB cut-off of the sensor's causal low-pass, Hz; ``None`` = ideal
            (infinite bandwidth). Must lie below the Nyquist frequency of the record.
        filter_order: order of the Butterworth low-pass, 1 (first-order lag) or 2 (default; a
            2nd-order Butterworth, the usual anti-alias/DSP stage of strain-gauge electronics).
            Both are designed by the bilinear transform with pre-warping, so the digital gain is
            exactly -3 dB at ``bandwidth_hz``.
        delay_s: pure transport delay, s, rounded to whole samples at the record's rate.
    """

    noise_std: float = 0.0
    bias_std: float = 0.0
    drift_per_s: float = 0.0
    quant_step: float = 0.0
    bandwidth_hz: float | None = None
    filter_order: int = 2
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("noise_std", "bias_std", "drift_per_s", "quant_step", "delay_s"):
            _check_nonneg(name, getattr(self, name))
        if self.bandwidth_hz is not None:
            bw = self.bandwidth_hz
            if not (isinstance(bw, (int, float, np.floating, np.integer)) and math.isfinite(bw) and bw > 0):
                raise ConfigError(
                    f"ChannelSpec.bandwidth_hz must be None (ideal) or a finite number > 0 Hz, got {bw!r}"
                )
        if self.filter_order not in _FILTER_ORDERS:
            raise ConfigError(
                f"ChannelSpec.filter_order must be one of {_FILTER_ORDERS}, got {self.filter_order!r}"
            )

    @classmethod
    def ideal(cls) -> ChannelSpec:
        """A perfect sensor: the output equals the input, bit for bit."""
        return cls()

    @property
    def is_ideal(self) -> bool:
        """True when the channel changes nothing (no noise, offset, drift, filter, delay, grid)."""
        return (
            self.noise_std == 0
            and self.bias_std == 0
            and self.drift_per_s == 0
            and self.quant_step == 0
            and self.bandwidth_hz is None
            and self.delay_s == 0
        )

    def check_rate(self, fs_hz: float, n_samples: int, name: str = "") -> None:
        """Raise :class:`ConfigError` if this channel cannot be recorded at ``fs_hz`` for
        ``n_samples`` samples: its bandwidth not below Nyquist, or its delay not shorter than the
        record. Checked before any simulation (protocols' ``validate``) and by :func:`apply_channel`.

        Args:
            fs_hz: Hz, the record's sample rate (> 0).
            n_samples: the record's length in samples.
            name: the channel's name, prefixed to messages (e.g. ``"ft_force sensor: "``).
        """
        where = f"{name} sensor: " if name else ""
        nyquist = fs_hz / 2.0
        if self.bandwidth_hz is not None and not self.bandwidth_hz < nyquist:
            raise ConfigError(
                f"{where}bandwidth_hz = {self.bandwidth_hz} Hz must be below the Nyquist frequency "
                f"{nyquist} Hz (fs_hz = {fs_hz}); use None for an ideal sensor"
            )
        n_delay = self.delay_samples(fs_hz)
        if n_samples > 0 and n_delay >= n_samples:
            raise ConfigError(
                f"{where}delay_s = {self.delay_s} s is {n_delay} samples at {fs_hz} Hz; it must be shorter "
                f"than the record ({n_samples} samples, i.e. delay_s < {n_samples / fs_hz} s)"
            )

    def delay_samples(self, fs_hz: float) -> int:
        """The delay in whole samples at ``fs_hz`` (rounded to nearest)."""
        return int(round(self.delay_s * fs_hz))


def apply_channel(
    x: np.ndarray,
    fs_hz: float,
    spec: ChannelSpec,
    rng: np.random.Generator,
    t0_s: np.ndarray | None = None,
) -> np.ndarray:
    """Turn clean signals into what the sensor records.

    Random draws, in this fixed order: bias (n_trials, n_axes), drift rate (n_trials, n_axes), then
    noise (n_trials, n_samples, n_axes) only when ``spec.noise_std > 0``. The same generator state
    therefore always gives bit-identical output.

    Args:
        x: (n_trials, n_samples, n_axes) clean signal, [unit], sampled at ``fs_hz``.
        fs_hz: sample rate, Hz (> 0).
        spec: the channel's imperfections.
        rng: the only source of randomness; advanced by the draws above.
        t0_s: (n_trials,) s, time already elapsed since taring at each trial's first sample
            (e.g. the pre-onset wait), so drift accumulated before the record counts. Default 0.

    Returns:
        (n_trials, n_samples, n_axes) float64 measured signal, [unit]. A new array; ``x`` is not
        modified.

    Raises:
        ConfigError: ``fs_hz`` not positive, ``bandwidth_hz`` not below Nyquist, delay not shorter
            than the record, or ``t0_s`` of the wrong shape or negative.
        DataError: ``x`` not 3-D or not finite.
    """
    if not (isinstance(fs_hz, (int, float, np.floating, np.integer)) and math.isfinite(fs_hz) and fs_hz > 0):
        raise ConfigError(f"fs_hz must be a finite number > 0 Hz, got {fs_hz!r}")
    y = np.array(x, dtype=np.float64)  # copy
    if y.ndim != 3:
        raise DataError(f"x must have shape (n_trials, n_samples, n_axes), got {y.shape}")
    if not np.all(np.isfinite(y)):
        raise DataError("x contains NaN or inf; clean signals must be finite")
    n_trials, n_samples, n_axes = y.shape
    spec.check_rate(fs_hz, n_samples)
    n_delay = spec.delay_samples(fs_hz)
    if t0_s is None:
        t0 = np.zeros(n_trials)
    else:
        t0 = np.asarray(t0_s, dtype=np.float64)
        if t0.shape != (n_trials,):
            raise ConfigError(f"t0_s must have shape ({n_trials},) (one per trial), got {t0.shape}")
        if not np.all(np.isfinite(t0) & (t0 >= 0)):
            raise ConfigError("t0_s must be finite and >= 0 s (time since taring)")
    if n_samples == 0 or n_trials == 0:
        return y

    if spec.bandwidth_hz is not None:
        # the sensor ran long before the record: its filter starts in the steady state of each
        # trial's first sample, so a constant passes unchanged and no start-up transient appears
        y = lowpass_causal(y, fs_hz, spec.bandwidth_hz, spec.filter_order, axis=1, start="steady")
    if n_delay > 0:
        y[:, n_delay:, :] = y[:, :-n_delay, :].copy()
        y[:, :n_delay, :] = y[:, :1, :]  # hold the first sample: the signal was there before the record

    bias = rng.normal(0.0, spec.bias_std, size=(n_trials, n_axes))  # [unit]
    drift = rng.normal(0.0, spec.drift_per_s, size=(n_trials, n_axes))  # [unit/s]
    t = np.arange(n_samples) / fs_hz  # (n_samples,) s
    if spec.bias_std > 0:
        y += bias[:, None, :]
    if spec.drift_per_s > 0:
        y += drift[:, None, :] * (t[None, :, None] + t0[:, None, None])
    if spec.noise_std > 0:
        y += rng.normal(0.0, spec.noise_std, size=y.shape)
    if spec.quant_step > 0:
        y = spec.quant_step * np.round(y / spec.quant_step)
    return y

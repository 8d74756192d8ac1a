"""Tests of armlab.sensors.channel: each imperfection measured against its specification."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from armlab.errors import ConfigError, DataError
from armlab.sensors.channel import ChannelSpec, apply_channel

FS = 1000.0  # Hz


def _rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)


def _smooth(n_trials: int = 3, n_samples: int = 400, n_axes: int = 2, seed: int = 1) -> np.ndarray:
    t = np.arange(n_samples) / FS
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, size=(n_trials, 1, n_axes))
    return 3.0 * np.sin(2 * np.pi * 2.0 * t[None, :, None] + phase)


def _gain_db(spec: ChannelSpec, f_hz: float) -> float:
    """Steady-state gain of the channel at f_hz, by a least-squares sine fit to the second half."""
    n = 4000
    t = np.arange(n) / FS
    x = np.sin(2 * np.pi * f_hz * t)[None, :, None]
    y = apply_channel(x, FS, spec, _rng())[0, :, 0]
    half = slice(n // 2, n)
    basis = np.column_stack([np.sin(2 * np.pi * f_hz * t[half]), np.cos(2 * np.pi * f_hz * t[half])])
    coef, *_ = np.linalg.lstsq(basis, y[half], rcond=None)
    return 20 * np.log10(np.hypot(*coef))


def test_ideal_is_identity_and_leaves_input_untouched():
    x = _smooth()
    before = x.copy()
    y = apply_channel(x, FS, ChannelSpec.ideal(), _rng())
    assert ChannelSpec.ideal().is_ideal
    assert np.array_equal(y, x)
    assert y is not x
    assert np.array_equal(x, before)


def test_noise_std_matches_spec():
    sigma = 0.3
    n = 4 * 50_000
    y = apply_channel(np.zeros((4, 50_000, 1)), FS, ChannelSpec(noise_std=sigma), _rng())
    # The sample std of N Gaussian draws has relative standard error 1/sqrt(2N); allow 5 of them
    # (false-failure probability ~6e-7). The mean has standard error sigma/sqrt(N).
    assert abs(y.std() / sigma - 1) < 5 / np.sqrt(2 * n)
    assert abs(y.mean()) < 5 * sigma / np.sqrt(n)


def test_quantisation_error_bounded_by_half_step():
    step = 0.05
    x = _smooth()
    y = apply_channel(x, FS, ChannelSpec(quant_step=step), _rng())
    err = y - x
    assert np.max(np.abs(err)) <= step / 2 + 1e-12
    assert np.max(np.abs(err)) > step / 4  # it did quantise
    np.testing.assert_allclose(y / step, np.round(y / step), atol=1e-9)


def test_delay_shifts_step_by_whole_samples_and_holds_first_sample():
    x = np.full((2, 300, 1), 2.0)
    x[:, 100:, :] = 5.0
    spec = ChannelSpec(delay_s=0.0037)  # 3.7 ms at 1 kHz rounds to 4 samples
    assert spec.delay_samples(FS) == 4
    y = apply_channel(x, FS, spec, _rng())
    assert np.array_equal(y[:, :104], np.full((2, 104, 1), 2.0))
    assert np.array_equal(y[:, 104:], np.full((2, 196, 1), 5.0))
    ramp = np.arange(50.0)[None, :, None]
    yr = apply_channel(ramp, FS, spec, _rng())
    assert np.array_equal(yr[0, :4, 0], np.zeros(4))  # held first sample
    assert np.array_equal(yr[0, 4:, 0], ramp[0, :-4, 0])


@pytest.mark.parametrize("order", [1, 2])
def test_bandwidth_gain_is_minus_3db_at_cutoff(order):
    spec = ChannelSpec(bandwidth_hz=50.0, filter_order=order)
    # Bilinear design with pre-warping gives exactly -3.01 dB at the cut-off; 0.05 dB covers the
    # fit on a finite window.
    assert _gain_db(spec, 50.0) == pytest.approx(-3.0103, abs=0.05)
    assert _gain_db(spec, 2.0) == pytest.approx(0.0, abs=0.05)
    # Beyond the cut-off the roll-off is ~order*20 dB/decade: below -9 dB (order 1) / -20 dB (2) at 200 Hz.
    assert _gain_db(spec, 200.0) < (-9.0 if order == 1 else -20.0)


def test_lowpass_passes_a_constant_without_startup_transient():
    x = np.full((2, 200, 3), 7.5)
    y = apply_channel(x, FS, ChannelSpec(bandwidth_hz=20.0), _rng())
    np.testing.assert_allclose(y, x, rtol=0, atol=1e-10)


def test_bias_is_constant_per_trial_with_spec_std():
    n_trials = 4000
    y = apply_channel(np.zeros((n_trials, 20, 1)), FS, ChannelSpec(bias_std=0.5), _rng())
    assert np.array_equal(y, np.broadcast_to(y[:, :1], y.shape))
    # Relative standard error of a sample std over n_trials draws: 1/sqrt(2 n); allow 5.
    assert abs(y[:, 0, 0].std() / 0.5 - 1) < 5 / np.sqrt(2 * n_trials)


def test_drift_is_linear_and_counts_time_since_taring():
    n_trials, n = 50, 101
    t0 = np.linspace(0.5, 5.0, n_trials)
    y = apply_channel(np.zeros((n_trials, n, 2)), FS, ChannelSpec(drift_per_s=0.01), _rng(), t0_s=t0)
    slope = (y[:, -1] - y[:, 0]) / ((n - 1) / FS)  # (n_trials, 2) per s
    t = np.arange(n) / FS
    np.testing.assert_allclose(y, slope[:, None, :] * (t[None, :, None] + t0[:, None, None]), atol=1e-15)
    assert np.all(np.abs(y[:, 0]) > 0)  # drift accumulated before the record starts
    assert abs(slope.std() / 0.01 - 1) < 5 / np.sqrt(2 * slope.size)


def test_same_seed_bit_identical_different_seed_different():
    spec = ChannelSpec(noise_std=0.1, bias_std=0.2, drift_per_s=0.01, quant_step=0.01, bandwidth_hz=100.0)
    x = _smooth()
    a = apply_channel(x, FS, spec, _rng(7))
    b = apply_channel(x, FS, spec, _rng(7))
    c = apply_channel(x, FS, spec, _rng(8))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"noise_std": -1.0}, "noise_std must be a finite number >= 0"),
        ({"bias_std": float("nan")}, "bias_std"),
        ({"quant_step": float("inf")}, "quant_step"),
        ({"delay_s": -0.001}, "delay_s"),
        ({"bandwidth_hz": 0.0}, r"None \(ideal\) or a finite number > 0"),
        ({"filter_order": 3}, r"one of \(1, 2\)"),
    ],
)
def test_spec_validation_messages(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        ChannelSpec(**kwargs)


def test_spec_is_frozen_and_comparable():
    spec = ChannelSpec(noise_std=0.1)
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.noise_std = 0.2  # type: ignore[misc]
    assert spec == ChannelSpec(noise_std=0.1)
    assert "noise_std=0.1" in repr(spec)


def test_apply_channel_validation():
    x = np.zeros((2, 100, 1))
    with pytest.raises(ConfigError, match="fs_hz must be"):
        apply_channel(x, 0.0, ChannelSpec(), _rng())
    with pytest.raises(ConfigError, match="Nyquist frequency 500.0 Hz"):
        apply_channel(x, FS, ChannelSpec(bandwidth_hz=500.0), _rng())
    with pytest.raises(ConfigError, match="shorter than the record"):
        apply_channel(x, FS, ChannelSpec(delay_s=0.1), _rng())
    with pytest.raises(ConfigError, match=r"t0_s must have shape \(2,\)"):
        apply_channel(x, FS, ChannelSpec(), _rng(), t0_s=np.zeros(3))
    with pytest.raises(ConfigError, match=">= 0"):
        apply_channel(x, FS, ChannelSpec(), _rng(), t0_s=np.array([0.0, -1.0]))
    with pytest.raises(DataError, match="n_trials, n_samples, n_axes"):
        apply_channel(np.zeros((100, 1)), FS, ChannelSpec(), _rng())
    bad = x.copy()
    bad[1, 5, 0] = np.nan
    with pytest.raises(DataError, match="NaN"):
        apply_channel(bad, FS, ChannelSpec(), _rng())

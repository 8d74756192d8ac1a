"""Checks of the smoothing and differentiation filters of Sec. III-A / Fig. 3 of the virtual-sensor paper."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import signal

from armlab.errors import ConfigError, DataError
from armlab.estimation.smoothing import (
    SmoothingSpec,
    differentiate,
    filter_response,
    smooth,
    smooth_and_differentiate,
)

FS = 1000.0  # Hz, the paper's sample rate
FC = 4.5  # Hz, the paper's Butterworth cut-off
T_END = 50.0  # s, record length
EDGE = 2000  # samples (2 s) left out at each end: filtfilt transients decay as exp(-8.7 t/s) (slowest
# pole of the 4.5 Hz 5th-order Butterworth: 2 pi 4.5 sin(pi/10) = 8.7 /s), to ~1e-8 of their start
T = np.arange(round(T_END * FS)) / FS  # s
INNER = slice(EDGE, -EDGE)
# perturbation-band test signal: 0.1-2 Hz, the bandwidth of the paper's perturbations
FREQS = np.array([0.1, 0.37, 0.83, 1.3, 2.0])  # Hz
AMPS = np.array([1.0, 0.5, 0.3, 0.2, 0.1])  # arbitrary unit (say rad)
PHASES = np.array([0.3, 1.1, -0.7, 2.0, 0.5])  # rad


def _butter2(f: np.ndarray) -> np.ndarray:
    """Gain of the forward-backward 5th-order Butterworth, 1 / (1 + (f/fc)^10) (closed form)."""
    return 1.0 / (1.0 + (np.asarray(f) / FC) ** 10)


def _multisine() -> tuple[np.ndarray, np.ndarray]:
    arg = 2 * np.pi * FREQS * T[:, None] + PHASES
    x = np.sum(AMPS * np.sin(arg), axis=1)
    xd = np.sum(AMPS * 2 * np.pi * FREQS * np.cos(arg), axis=1)
    return x, xd


def _complex_gain(y: np.ndarray, f: float) -> complex:
    """Response H at ``f`` from the output ``y`` to ``cos(2 pi f T)``: y = Re(H e^{jwt}) = Hr cos - Hi sin."""
    w = 2 * np.pi * f * T[INNER]
    (a, b), *_ = np.linalg.lstsq(np.column_stack([np.cos(w), np.sin(w)]), y[INNER], rcond=None)
    return complex(a, -b)


def test_multisine_in_band_is_reproduced_and_differentiated():
    x, xd = _multisine()
    # tolerances from the Butterworth closed form, independent of the module: filtfilt's gain
    # 1/(1+(f/fc)^10) >= 1 - (f/fc)^10 (2.9e-4 at 2 Hz), plus 2e-5 for the SG stage (scipy's taps
    # carry a 6.1e-6 DC gain error; the N = 6, W = 151 fit droops < 1.2e-5 below 2 Hz).
    # Summing |error| over components bounds the worst sample.
    rel = (FREQS / FC) ** 10 + 2e-5
    xs, xds = smooth_and_differentiate(x, FS)
    assert np.max(np.abs(xs - x)[INNER]) <= np.sum(AMPS * rel)  # ~1.2e-4 of a ~2 peak
    assert np.max(np.abs(xds - xd)[INNER]) <= np.sum(AMPS * 2 * np.pi * FREQS * rel)
    assert_allclose(xs, smooth(x, FS), rtol=0, atol=0)
    assert_allclose(xds, differentiate(x, FS), rtol=0, atol=0)
    # edges: the SG end fits and filtfilt's short odd-extension padding err by up to ~25 % of the
    # peak derivative at the very ends, but the same bounds already hold 1 s in (measured: 0.75 s)
    one_s = slice(1000, -1000)
    assert np.max(np.abs(xs - x)[one_s]) <= np.sum(AMPS * rel)
    assert np.max(np.abs(xds - xd)[one_s]) <= np.sum(AMPS * 2 * np.pi * FREQS * rel)


def test_white_noise_is_attenuated_to_the_filters_bandwidth():
    rng = np.random.default_rng(12345)
    sigma = 0.01  # unit of x
    noise = sigma * rng.standard_normal((T.size, 8))  # 8 channels: more samples of the output std
    ys, yd = smooth_and_differentiate(noise, FS)
    ratio = np.std(ys[INNER]) / sigma
    # white noise spreads its variance evenly over 0..500 Hz; a filter passing ~4.5 Hz keeps about
    # 4.5/500 of it, i.e. a std ratio of sqrt(4.5/500) = 0.095 (the SG roll-off takes it to 0.091)
    rough = np.sqrt(FC / (FS / 2))
    assert 0.8 * rough < ratio < 1.1 * rough  # measured 0.091: the noise is cut ~11x
    # exactly: var ratio = mean |H|² over 0..Nyquist. The output has ~2 x 4.1 Hz x 46 s x 8 = 3000
    # independent samples, so its std is estimated to ~1/sqrt(2 x 3000) = 1.3 %: 5 % is 4 sigma.
    f = np.linspace(0.0, FS / 2, 100_001)
    hs, hd = filter_response(None, FS, f)
    assert_allclose(ratio, np.sqrt(np.mean(np.abs(hs) ** 2)), rtol=0.05)
    assert_allclose(np.std(yd[INNER]) / sigma, np.sqrt(np.mean(np.abs(hd) ** 2)), rtol=0.05)  # 1.40 /s


def test_ten_hz_is_suppressed():
    x = np.sin(2 * np.pi * 10.0 * T)
    y = smooth(x, FS)
    # filtfilt alone gives 1/(1+(10/4.5)^10) = 3.4e-4; the SG stage's gain there is <= 1
    assert np.max(np.abs(y[INNER])) < 1.05 * _butter2(10.0)


@pytest.mark.parametrize("f", [0.5, 2.0, 4.0, 10.0])
def test_filter_response_matches_measured_gain_of_sinusoids(f):
    x = np.cos(2 * np.pi * f * T)
    hs, hd = filter_response(SmoothingSpec(), FS, np.array(f))
    # away from the edges the SG stage is exactly its FIR and filtfilt's transients are ~1e-8 of the
    # amplitude, so the fitted gain agrees far better than the 1 % the paper's figure resolves
    assert abs(_complex_gain(smooth(x, FS), f) - hs) <= 1e-6 * max(abs(hs), 1e-3)
    assert abs(_complex_gain(differentiate(x, FS), f) - hd) <= 1e-6 * max(abs(hd), 1e-3 * 2 * np.pi * f)


@pytest.mark.parametrize(
    "spec", [SmoothingSpec(), SmoothingSpec(lowpass_hz=None), SmoothingSpec(sg_window=31)]
)
def test_filter_response_is_the_fourier_transform_of_the_impulse_response(spec):
    n, mid = 20_001, 10_000  # 20 s; the impulse responses die out well within +-10 s
    impulse = np.zeros(n)
    impulse[mid] = 1.0
    f = np.fft.rfftfreq(n, 1 / FS)
    shift = np.exp(2j * np.pi * f * mid / FS)  # centre the impulse at t = 0: zero phase
    hs, hd = filter_response(spec, FS, f)
    assert_allclose(np.fft.rfft(smooth(impulse, FS, spec)) * shift, hs, atol=1e-9)
    assert_allclose(np.fft.rfft(differentiate(impulse, FS, spec)) * shift, hd, atol=1e-9 * FS)
    assert np.max(np.abs(hs.imag)) == 0 and np.max(np.abs(hd.real)) == 0  # real / imaginary by symmetry


def test_response_matches_ideal_differentiator_in_band_and_decays_above():
    f = np.linspace(0.01, 2.0, 400)  # Hz
    hs, hd = filter_response(None, FS, f)
    # measured max 3.1e-4 at 2 Hz: filtfilt's 1-(2/4.5)^10 = 2.9e-4 plus the SG droop 1.2e-5;
    # 5e-4 keeps margin and is 40x tighter than the 2 % one reads off the paper's Fig. 3
    assert np.max(np.abs(hd / (2j * np.pi * f) - 1)) < 5e-4
    assert np.max(np.abs(hs - 1)) < 5e-4
    # at the cut-off the Butterworth pair is exactly 1/2, the SG stage within 1e-4 of 1
    hs_c, hd_c = filter_response(None, FS, np.array([FC]))
    assert_allclose(hs_c.real, 0.5, rtol=1e-3)
    assert_allclose(hd_c.imag / (2 * np.pi * FC), 0.5, rtol=2e-3)
    fh = np.linspace(6.0, FS / 2, 5000)
    hs_h, hd_h = filter_response(None, FS, fh)
    assert np.all(np.abs(hs_h) <= 1.01 * _butter2(fh))  # the SG stage only removes more
    assert np.all(np.abs(hd_h) <= 1.01 * 2 * np.pi * fh * _butter2(fh))
    assert np.max(np.abs(hd_h)) < 0.06 * 2 * np.pi * 6.0  # decays to zero: < 6 % of ideal from 6 Hz


def test_shape_is_preserved_and_frequency_grid_may_be_any_shape():
    hs, hd = filter_response(None, FS, np.ones((2, 3)))
    assert hs.shape == hd.shape == (2, 3)
    assert hs.dtype == hd.dtype == complex


def test_axis_handling_equals_per_trial_application():
    rng = np.random.default_rng(7)
    x = np.cumsum(rng.standard_normal((3, 1500, 2)), axis=1)  # (n_trials, n_samples, channels)
    per_trial_s = np.stack([smooth(xi, FS) for xi in x])
    per_trial_d = np.stack([differentiate(xi, FS) for xi in x])
    # the same scipy operations along another axis, equal to round-off: the SG end fits (lstsq)
    # round differently for other memory layouts, ~1e-13 of the signal's scale (measured 7e-14)
    tol = 1e-12 * np.max(np.abs(x))
    assert_allclose(smooth(x, FS, axis=1), per_trial_s, rtol=0, atol=tol)
    assert_allclose(differentiate(x, FS, axis=-2), per_trial_d, rtol=0, atol=tol * FS)
    xt = np.moveaxis(x, 1, -1)  # (n_trials, channels, n_samples)
    assert_allclose(np.moveaxis(smooth(xt, FS, axis=-1), -1, 1), per_trial_s, rtol=0, atol=tol)
    one = np.stack([smooth(x[0, :, c], FS) for c in range(2)], axis=1)
    assert_allclose(per_trial_s[0], one, rtol=0, atol=tol)


def test_without_lowpass_is_plain_savitzky_golay():
    x, _ = _multisine()
    spec = SmoothingSpec(lowpass_hz=None)
    assert_allclose(smooth(x, FS, spec), signal.savgol_filter(x, 151, 6), rtol=0, atol=0)
    assert_allclose(differentiate(x, FS, spec), signal.savgol_filter(x, 151, 6, deriv=1, delta=1 / FS))


def test_spec_defaults_are_the_papers_and_frozen():
    spec = SmoothingSpec()
    assert (spec.sg_order, spec.sg_window, spec.lowpass_hz, spec.lowpass_order) == (6, 151, 4.5, 5)
    assert spec == SmoothingSpec()
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.sg_window = 11  # type: ignore[misc]


def test_window_not_above_order_is_a_config_error_naming_both():
    with pytest.raises(ConfigError, match="window") as err:
        SmoothingSpec(sg_window=5, sg_order=6)
    assert "5" in str(err.value) and "order 6" in str(err.value) and "odd" in str(err.value)
    with pytest.raises(ConfigError, match="window"):
        SmoothingSpec(sg_window=7, sg_order=7)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"sg_window": 150}, "odd"),
        ({"sg_window": 151.0}, "odd integer"),
        ({"sg_order": 0}, "sg_order"),
        ({"sg_order": True}, "sg_order"),
        ({"lowpass_hz": 0.0}, "lowpass_hz"),
        ({"lowpass_hz": -4.5}, "lowpass_hz"),
        ({"lowpass_hz": float("nan")}, "lowpass_hz"),
        ({"lowpass_order": 0}, "lowpass_order"),
    ],
)
def test_invalid_spec_is_a_config_error(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        SmoothingSpec(**kwargs)


@pytest.mark.parametrize("cutoff", [500.0, 600.0])
def test_lowpass_at_or_above_nyquist_is_a_config_error(cutoff):
    spec = SmoothingSpec(lowpass_hz=cutoff)
    with pytest.raises(ConfigError, match="Nyquist frequency 500 Hz"):
        smooth(np.zeros(1000), FS, spec)
    with pytest.raises(ConfigError, match="Nyquist"):
        filter_response(spec, FS, np.array([1.0]))
    with pytest.raises(ConfigError, match="Nyquist"):
        spec.check(FS, 1000)


def test_too_short_signal_is_a_data_error_saying_how_many_are_needed():
    with pytest.raises(DataError, match="150 samples.*at least 151"):
        smooth(np.zeros(150), FS)
    smooth(np.zeros(151), FS)
    # a short window: sosfiltfilt's padding of the order-5 low-pass (3 x 6 taps = 18) decides
    spec = SmoothingSpec(sg_window=7, sg_order=2)
    with pytest.raises(DataError, match="at least 19"):
        differentiate(np.zeros((18, 2)), FS, spec)
    differentiate(np.zeros((19, 2)), FS, spec)
    SmoothingSpec(sg_window=7, sg_order=2, lowpass_hz=None).check(FS, 7)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_input_is_a_data_error(bad):
    x = np.zeros((500, 2))
    x[100, 1] = bad
    with pytest.raises(DataError, match="non-finite"):
        smooth(x, FS)
    with pytest.raises(DataError, match="non-finite"):
        differentiate(x, FS)


def test_bad_rate_axis_and_frequencies_are_data_errors():
    with pytest.raises(DataError, match="fs_hz"):
        smooth(np.zeros(500), 0.0)
    with pytest.raises(DataError, match="axis 2"):
        smooth(np.zeros((500, 2)), FS, axis=2)
    with pytest.raises(DataError, match="freqs_hz"):
        filter_response(None, FS, np.array([1.0, np.nan]))

"""Ground-truth checks of armlab.dsp: filter gains and phases, step responses, derivatives."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import signal

from armlab.dsp import (
    butterworth,
    five_point_derivatives,
    lowpass_causal,
    lowpass_zero_phase,
    savgol,
    savgol_taps,
    second_order_ba,
    second_order_lowpass,
    sosfiltfilt_padlen,
    zero_phase,
)
from armlab.errors import ConfigError, DataError

FS = 1000.0  # Hz
DT = 1.0 / FS  # s
T = np.arange(4000) * DT  # s, 4 s
EDGE = slice(1000, -1000)  # 1 s at each end: the slowest filter here (2nd order at 5 Hz, ζ 0.3)
# decays as exp(-ζ wn t) = exp(-9.4 t/s), to 1e-4 of its start within 1 s


def _phasor(y: np.ndarray, f: float) -> complex:
    """Complex amplitude H with y = Re(H exp(j 2 pi f t)) on the EDGE part, by least squares."""
    w = 2 * np.pi * f * T[EDGE]
    (a, b), *_ = np.linalg.lstsq(np.column_stack([np.cos(w), np.sin(w)]), y[EDGE], rcond=None)
    return complex(a, -b)


@pytest.mark.parametrize("order", [1, 2, 4, 5])
def test_butterworth_gain_is_minus_3_db_at_the_cutoff(order):
    fc = 40.0  # Hz
    _, h = signal.sosfreqz(butterworth(fc, FS, order), worN=[0.0, fc], fs=FS)
    # pre-warped bilinear transform: -3 dB lands exactly on fc; 1e-12 is round-off of the design
    assert_allclose(np.abs(h), [1.0, 1 / math.sqrt(2)], atol=1e-12)
    b, a = butterworth(fc, FS, order, output="ba")
    _, h_ba = signal.freqz(b, a, worN=[fc], fs=FS)
    assert_allclose(np.abs(h_ba), 1 / math.sqrt(2), atol=1e-12)
    _, h_hp = signal.sosfreqz(butterworth(fc, FS, order, btype="high"), worN=[fc, FS / 2], fs=FS)
    assert_allclose(np.abs(h_hp), [1 / math.sqrt(2), 1.0], atol=1e-12)


def test_causal_lowpass_passes_a_sine_at_the_cutoff_at_minus_3_db():
    fc = 40.0  # Hz
    y = lowpass_causal(np.cos(2 * np.pi * fc * T), FS, fc, order=2)
    # steady state after 1 s (the 40 Hz poles decay as exp(-178 t/s)): only the fit's round-off
    assert abs(_phasor(y, fc)) == pytest.approx(1 / math.sqrt(2), abs=1e-9)


def test_zero_phase_lowpass_has_no_lag_and_squares_the_gain():
    fc = 40.0  # Hz
    x = np.cos(2 * np.pi * 10.0 * T) + np.cos(2 * np.pi * fc * T)
    y = lowpass_zero_phase(x, FS, fc, order=4, axis=0)
    h10 = _phasor(y, 10.0)
    _, g10 = signal.sosfreqz(butterworth(fc, FS, 4), worN=[10.0], fs=FS)
    # forward-backward: |H|² and exactly zero phase; 1e-9 is the least-squares fit's round-off
    assert h10.real == pytest.approx(abs(g10[0]) ** 2, abs=1e-9)
    assert h10.imag == pytest.approx(0.0, abs=1e-9)
    assert _phasor(y, fc) == pytest.approx(0.5, abs=1e-9)  # (-3 dB)² = -6 dB at the cut-off, no lag
    # a causal filter of the same design lags: its phase at 10 Hz is far from zero
    assert abs(np.angle(_phasor(lowpass_causal(x, FS, fc, order=4), 10.0))) > 0.1


def test_zero_phase_padding_and_the_shortest_signal():
    sos = butterworth(40.0, FS, 4)
    n = sosfiltfilt_padlen(sos)
    zero_phase(sos, np.ones(n + 1))  # one more than the padding: accepted
    with pytest.raises(ValueError):
        zero_phase(sos, np.ones(n))  # the rule is scipy's own: exactly the padding is refused
    # even padding mirrors the ends: a constant stays constant either way
    assert_allclose(zero_phase(sos, np.full(100, 3.0), padtype="even"), 3.0, rtol=1e-12)
    assert_allclose(lowpass_zero_phase(np.ones((2, 50, 3)), FS, None), 1.0)  # None: no filter


def test_lowpass_zero_phase_errors():
    with pytest.raises(ConfigError, match=r"cutoff_hz must lie in \(0, 500\) Hz"):
        lowpass_zero_phase(np.zeros((100, 2)), FS, 500.0)
    with pytest.raises(DataError, match="too short for an order-4"):
        lowpass_zero_phase(np.zeros((10, 2)), FS, 40.0)


def test_causal_lowpass_starts():
    x = np.full((2, 300, 3), 2.5)
    x[1] = -1.0
    steady = lowpass_causal(x, FS, 30.0, order=2, axis=1, start="steady")
    deviation = lowpass_causal(x, FS, 30.0, order=2, axis=1, start="deviation")
    # both start where a constant input left the filter: the constant passes (round-off of the
    # lfilter_zi solve and of the unit DC gain only)
    assert_allclose(steady, x, rtol=1e-12)
    assert_allclose(deviation, x, rtol=0, atol=0)  # x - x0 is exactly zero here
    step = np.ones(300)
    rest = lowpass_causal(step, FS, 30.0, order=2, start="rest")
    assert rest[0] < 0.01 and rest[-1] == pytest.approx(1.0, abs=1e-9)  # from zero up to the step
    ramp = np.linspace(0.0, 1.0, 300)
    assert_allclose(
        lowpass_causal(ramp + 4.0, FS, 30.0, start="steady"),
        lowpass_causal(ramp + 4.0, FS, 30.0, start="deviation"),
        atol=1e-12,  # the two formulations of one steady start differ by round-off only
    )
    with pytest.raises(ConfigError, match=r"start must be one of \('rest', 'steady', 'deviation'\)"):
        lowpass_causal(step, FS, 30.0, start="zero")


@pytest.mark.parametrize("zeta", [0.3, 0.7, 1.0])
def test_second_order_step_response_matches_the_analytic_one(zeta):
    fn = 5.0  # Hz
    wn = 2 * np.pi * fn  # rad/s
    y = second_order_lowpass(np.ones(T.size), FS, fn, zeta)
    # The trapezoidal rule sees the sampled step as a ramp between samples -1 and 0, a step at
    # -dt/2; the analytic response of wn²/(s² + 2ζ wn s + wn²) is compared there.
    t = T + DT / 2
    if zeta < 1:
        wd = wn * math.sqrt(1 - zeta**2)
        exact = 1 - np.exp(-zeta * wn * t) / math.sqrt(1 - zeta**2) * np.sin(wd * t + math.acos(zeta))
    else:
        exact = 1 - (1 + wn * t) * np.exp(-wn * t)
    # Tustin maps wn to (2/dt) tan(wn dt/2) = wn (1 + (wn dt)²/12): a time-scale error of
    # 8e-5 on a response with max |t·y'(t)| < 1, plus the O((wn dt)²) error of the half-sample
    # shift; 2 (wn dt)²/12 = 1.6e-4 bounds both
    assert_allclose(y, exact, atol=2 * (wn * DT) ** 2 / 12)
    b, a = second_order_ba(fn, zeta, FS)
    assert np.sum(b) / np.sum(a) == pytest.approx(1.0, abs=1e-12)  # unit DC gain
    assert_allclose(signal.lfilter(b, a, np.ones(T.size)), y, rtol=0, atol=0)  # one filter, two entries


def test_second_order_overshoot_matches_the_damping_ratio():
    zeta = 0.3
    y = second_order_lowpass(np.ones(T.size), FS, 5.0, zeta)
    # peak of the step response 1 + exp(-pi ζ / sqrt(1 - ζ²)); the sampled peak misses the true
    # one by at most (wd dt)²/2 of the oscillation amplitude, and Tustin's warping by ~1e-4
    assert y.max() == pytest.approx(1 + math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), abs=2e-4)


def test_five_point_derivatives_of_a_sinusoid():
    f = 5.0  # Hz
    w = 2 * np.pi * f  # rad/s
    x = np.stack([np.sin(w * T), np.cos(w * T)], axis=1)  # (n, 2)
    xd, xdd = five_point_derivatives(x, FS, axis=0)
    xd_exact = w * np.stack([np.cos(w * T), -np.sin(w * T)], axis=1)
    # interior: the five-point stencils' truncation errors are dt⁴/30 |x⁽⁵⁾| = w (w dt)⁴/30 and
    # dt⁴/90 |x⁽⁶⁾| = w² (w dt)⁴/90 (3e-8 of the amplitude); 10 % margin for round-off
    assert_allclose(xd[2:-2], xd_exact[2:-2], rtol=0, atol=1.1 * w * (w * DT) ** 4 / 30)
    assert_allclose(xdd[2:-2], -(w**2) * x[2:-2], rtol=0, atol=1.1 * w**2 * (w * DT) ** 4 / 90)
    # ends: np.gradient's second-order one-sided stencil errs by dt²/3 |x'''| = w (w dt)²/3
    assert_allclose(xd[:2], xd_exact[:2], rtol=0, atol=1.1 * w * (w * DT) ** 2 / 3)
    assert_allclose(xd[-2:], xd_exact[-2:], rtol=0, atol=1.1 * w * (w * DT) ** 2 / 3)


def test_five_point_derivatives_are_exact_for_quartics_inside():
    t = np.arange(50) * 0.01  # s
    x = (t**4 - 2 * t**3 + t)[None, :, None]  # (1, 50, 1), along the default axis -2
    xd, xdd = five_point_derivatives(x, 100.0)
    # the stencils are exact up to degree 4: only round-off (x/dt ~ 1e2 times eps) remains
    assert_allclose(xd[0, 2:-2, 0], (4 * t**3 - 6 * t**2 + 1)[2:-2], atol=1e-11)
    assert_allclose(xdd[0, 2:-2, 0], (12 * t**2 - 12 * t)[2:-2], atol=1e-8)
    with pytest.raises(DataError, match="at least 5 samples"):
        five_point_derivatives(np.zeros((4, 2)), 100.0, axis=0)


def test_savgol_is_exact_for_polynomials_of_its_order():
    t = np.arange(200) * DT
    x = 3 * t**3 - t**2 + 0.5  # a cubic
    # a cubic least-squares fit reproduces a cubic everywhere (interior and the interp ends);
    # 1e-9 covers the Vandermonde solve's round-off
    assert_allclose(savgol(x, FS, 21, 3), x, atol=1e-9)
    assert_allclose(savgol(x, FS, 21, 3, deriv=1), 9 * t**2 - 2 * t, atol=1e-6)
    two = np.stack([x, 2 * x])  # (2, n): along the last axis by default
    assert_allclose(savgol(two, FS, 21, 3)[1], 2 * x, atol=2e-9)


def test_savgol_interior_is_the_convolution_with_its_taps():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(500)
    for deriv in (0, 1):
        taps = savgol_taps(FS, 31, 4, deriv=deriv)
        half = 15
        inner = np.convolve(x, taps, mode="valid")
        assert_allclose(savgol(x, FS, 31, 4, deriv=deriv)[half:-half], inner, atol=1e-9 * FS**deriv)
    assert np.sum(savgol_taps(FS, 31, 4)) == pytest.approx(1.0, abs=1e-9)  # unit DC gain
    assert np.sum(savgol_taps(FS, 31, 4, deriv=1)) == pytest.approx(0.0, abs=1e-6)  # kills constants


def test_the_remembered_designs_are_handed_out_as_copies():
    """dsp.butterworth and dsp.bilinear remember designs (a fit asks for the same few thousands of
    times): a caller changing its copy must not change what the next caller gets."""
    from armlab.dsp import bilinear, butterworth

    sos = butterworth(10.0, 1000.0, 2)
    sos[:] = 0.0
    assert np.any(butterworth(10.0, 1000.0, 2) != 0.0)
    b, a = bilinear([1.0], [0.05, 1.0], 1000.0)
    b[:] = 0.0
    assert np.any(bilinear([1.0], [0.05, 1.0], 1000.0)[0] != 0.0)


def test_a_remembered_spectrum_is_never_handed_out_for_a_changed_signal():
    """The padded-spectrum memory of the diagnosis's delay search: a signal changed in place (same
    object, same shape, same pad) must get its own spectrum, equal to one computed afresh."""
    from armlab.diagnosis.families import _padded_spectrum, padded_length

    rng = np.random.default_rng(0)
    z = rng.standard_normal(500)
    first = _padded_spectrum(z, 7).copy()
    z[100] += 1.0  # the same array, changed
    again = _padded_spectrum(z, 7)
    back = padded_length(500, 7) - 507
    fresh = np.fft.rfft(np.concatenate([np.full(7, z[0]), z, np.full(back, z[-1])]))
    np.testing.assert_array_equal(again, fresh)
    assert not np.array_equal(again, first)


@pytest.mark.parametrize("cores", [1, 2])
def test_lowpass_noise_in_row_blocks_equals_one_draw_filtered_at_once(monkeypatch, cores):
    # lowpass_noise draws and filters the rows in blocks (the next drawn while the last filters on
    # a second thread): bit-identical to one standard_normal call of the lengthened shape filtered
    # at once, on one core and on two
    from armlab.dsp import butterworth
    from armlab.noise import lowpass_noise

    monkeypatch.setattr("armlab.noise.usable_cpus", lambda: cores)  # where _filtered_noise asks
    fs, fc, periods, shape = 1000.0, 2.0, 4.0, (7, 300, 2)
    n_burn = int(math.ceil(periods * fs / fc))
    monkeypatch.setattr("armlab.noise._BLOCK_SIZE", 3 * (n_burn + shape[1]) * shape[2])  # 3 rows a block
    got = lowpass_noise(np.random.default_rng(4), shape, fs, fc, burn_in_periods=periods)
    sos = butterworth(fc, fs, 2)
    impulse = np.zeros(int(math.ceil(20.0 * fs / fc)))
    impulse[0] = 1.0
    gain = math.sqrt(float(np.sum(signal.sosfilt(sos, impulse) ** 2)))
    white = np.random.default_rng(4).standard_normal((shape[0], n_burn + shape[1], shape[2]))
    np.testing.assert_array_equal(got, signal.sosfilt(sos, white, axis=1)[:, n_burn:] / gain)


@pytest.mark.parametrize("n, pad", [(106000, 258), (60000, 258), (15000, 9), (500, 7)])
def test_the_padded_length_holds_the_pad_and_has_only_small_prime_factors(n, pad):
    """The spectral shift's and sensor response's padded length: at least the pad on both sides,
    lengthened to a 5-smooth length (106 s at 1 kHz padded by 258 was 4·31·859)."""
    from armlab.diagnosis.families import padded_length

    m = padded_length(n, pad)
    assert n + 2 * pad <= m <= 1.1 * (n + 2 * pad)
    for p in (2, 3, 5):
        while m % p == 0:
            m //= p
    assert m == 1


def test_a_delay_by_the_padded_spectrum_matches_a_shift_by_whole_samples_inside_the_record():
    """shift_columns by an integer number of samples moves a smooth record exactly (to rounding)
    away from its ends, whatever the padded length."""
    from armlab.diagnosis.families import shift_columns

    fs = 1000.0
    t = np.arange(15000) / fs
    z = np.sin(2 * np.pi * 1.3 * t) + 0.3 * np.cos(2 * np.pi * 4.1 * t)
    out = shift_columns(t, z, 0.012)
    np.testing.assert_allclose(out[500:-500], z[488:-512], atol=1e-9)


@pytest.mark.parametrize("padtype", ["odd", "even"])
@pytest.mark.parametrize("shape, axis", [((3000,), 0), ((3000, 3), 0), ((4, 900, 2), 1), ((3, 500), -1)])
def test_zero_phase_is_sosfiltfilt_to_the_bit(shape, axis, padtype):
    """zero_phase remembers the filter's initial state but otherwise takes SciPy's steps: the same
    numbers and the same memory layout as ``scipy.signal.sosfiltfilt`` (low, high, band-pass)."""
    from scipy import signal

    from armlab.dsp import butterworth, zero_phase

    x = np.random.default_rng(3).standard_normal(shape)
    for sos in (
        butterworth(20.0, 1000.0, 4),
        butterworth(0.3, 1000.0, 2, btype="high"),
        butterworth((1.0, 40.0), 1000.0, 3, btype="bandpass"),
    ):
        want = signal.sosfiltfilt(sos, x, axis=axis, padtype=padtype)
        got = zero_phase(sos, x, axis=axis, padtype=padtype)
        assert np.array_equal(got, want) and got.strides == want.strides

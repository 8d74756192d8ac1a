"""armlab.diagnosis.localise: band and window breakdowns, onsets, residual tests, FRF parameters."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import (
    JOINT_B,
    JOINT_FS_HZ,
    JOINT_I,
    JOINT_K,
    JointTrial,
    joint_trials,
    nominal_torque,
    prbs_steps,
    prepared,
    smooth,
)
from scipy import signal

from armlab.diagnosis.localise import (
    BANDS_HZ,
    WINDOWS_MS,
    band_breakdown,
    frf_parameters,
    onsets,
    residual_tests,
    window_breakdown,
)
from armlab.protocols.joint_1dof.diagnosis.data import noise_floor


@pytest.fixture(scope="module")
def data():
    """Two repeats of a 30 s smoothed PRBS, 0.15 N·m noise: (records, trials, hp, y_band, steps)."""
    rng = np.random.default_rng(7)
    steps = prbs_steps(rng, 30.0)
    records = joint_trials(smooth(steps), nominal_torque, rng, noise_std=0.15)
    trials, hp, y_band = prepared(records)
    return records, trials, hp, y_band, steps


def test_onsets_are_the_prbs_switch_times(data):
    _, trials, _, _, steps = data
    tr = trials[0]
    q = int(JOINT_FS_HZ / tr.fs_hz)
    switches = (np.flatnonzero(np.diff(steps)) + 1) / JOINT_FS_HZ  # s
    found = onsets(tr) / tr.fs_hz
    assert found.size == switches.size
    # the zero-phase smoothing centres each speed pulse on its switch; the half-peak crossing
    # comes its half-width before it (a step through a 2nd-order 15 Hz Butterworth run forward
    # and backward: 14-16 ms) and never later than the sample after it
    np.testing.assert_array_less(found - switches, q / JOINT_FS_HZ + 1e-9)
    np.testing.assert_array_less(switches - found, 0.02)


def test_residual_tests_find_a_delayed_copy_of_the_velocity(data):
    _, trials, _, _, _ = data
    lag = 10  # samples at 250 Hz: 40 ms
    rng = np.random.default_rng(0)
    residuals = [
        np.r_[np.zeros(lag), tr.v[:-lag]] + 0.1 * np.std(tr.v) * rng.normal(size=tr.v.size) for tr in trials
    ]
    rt = residual_tests(trials, residuals)
    assert rt["peak_cross_lag_s"] == pytest.approx(0.04)
    assert rt["peak_cross_value"] > 0.95  # 1/sqrt(1 + 0.1²) for the 10 % noise added
    lags = np.asarray(rt["lags_s"])
    assert lags[0] == pytest.approx(-0.05, abs=1 / 250) and lags[-1] == pytest.approx(0.25, abs=1 / 250)
    acf = np.asarray(rt["autocorrelation"])
    assert np.isnan(acf[lags < 0]).all() and acf[lags == 0] == pytest.approx(1.0)
    n_held = sum(int(tr.held.sum()) for tr in trials)
    assert rt["bound"] == pytest.approx(1.96 / np.sqrt(n_held))


def test_white_residual_passes_the_whiteness_test(data):
    _, trials, _, _, _ = data
    rng = np.random.default_rng(1)
    rt = residual_tests(trials, [rng.normal(size=tr.x.size) for tr in trials], max_lag_s=2.0)
    # 500 lags, each outside the 95 % bound with probability 0.05: the fraction is 0.05 ± 0.01
    # (binomial sd); 3 sd
    assert rt["whiteness_fraction_outside"] == pytest.approx(0.05, abs=0.03)
    assert abs(rt["peak_cross_value"]) < 3 * rt["bound"]
    coloured = [
        signal.sosfiltfilt(signal.butter(2, 5.0, fs=tr.fs_hz, output="sos"), r)
        for tr, r in zip(trials, [rng.normal(size=tr.x.size) for tr in trials], strict=True)
    ]
    assert residual_tests(trials, coloured, max_lag_s=2.0)["whiteness_fraction_outside"] > 0.2


def test_frf_parameters_recover_inertia_damping_stiffness():
    rng = np.random.default_rng(8)
    x = smooth(prbs_steps(rng, 20.0))
    trials, _, _ = prepared([JointTrial("a", x, nominal_torque(x))])
    p = frf_parameters(trials[0], trials[0].y)
    # noise-free, linear: only the Welch window's leakage over the 1-20 Hz fit: 3 %
    assert p["I"] == pytest.approx(JOINT_I, rel=0.03)
    assert p["B"] == pytest.approx(JOINT_B, rel=0.03)
    assert p["K"] == pytest.approx(JOINT_K, rel=0.03)


def test_band_breakdown_puts_a_band_limited_residual_in_its_band(data):
    records, trials, _, y_band, _ = data
    noise = noise_floor(records, trials, band_hz=40.0, highpass_hz=0.3)
    # the measured torque's 8-20 Hz content alone (brick-wall, by FFT)
    residuals = []
    for y, tr in zip(y_band, trials, strict=True):
        f = np.fft.rfftfreq(y.size, 1.0 / tr.fs_hz)
        residuals.append(np.fft.irfft(np.fft.rfft(y) * ((f >= 8.0) & (f < 20.0)), y.size))
    bands = band_breakdown(trials, y_band, residuals, noise)
    assert [b["band_hz"] for b in bands] == [list(b) for b in BANDS_HZ]
    gaps = [b["gap"] for b in bands]
    assert gaps[2] == pytest.approx(1.0, abs=0.05)  # 8-20 Hz: all of the measured power there (Welch leakage)
    assert max(gaps[0], gaps[1], gaps[3]) < 0.02
    # half the measured torque as the residual: a quarter of its power in every band
    half = band_breakdown(trials, y_band, [0.5 * y for y in y_band], noise)
    for b in half:
        assert b["gap"] == pytest.approx(0.25)
        assert b["residual_power"] == pytest.approx(0.25 * b["measured_power"])
        assert 0 < b["floor"] < 1  # noise is a small part of the measured torque in every band


def test_window_breakdown_puts_a_residual_after_onsets_in_its_windows(data):
    _, trials, _, y_band, _ = data
    residuals, since_held, y_held = [], [], []
    for tr, y in zip(trials, y_band, strict=True):
        since = np.full(tr.x.size, np.inf)  # ms since the last onset
        for i in onsets(tr):
            since[i:] = np.minimum(since[i:], np.arange(tr.x.size - i) / tr.fs_hz * 1e3)
        residuals.append(np.where(since < 60.0, y, 0.0))  # residual only in the first 60 ms
        since_held.append(since[tr.held])
        y_held.append(y[tr.held])
    windows = window_breakdown(trials, y_band, residuals, noise_var=1e-3)
    assert [w["window_ms"] for w in windows] == [list(w) for w in WINDOWS_MS]
    assert windows[0]["gap"] == pytest.approx(1.0) and windows[1]["gap"] == pytest.approx(1.0)
    assert windows[2]["gap"] == windows[3]["gap"] == 0.0
    since, y = np.concatenate(since_held), np.concatenate(y_held)
    for w, (lo_ms, hi_ms) in zip(windows, WINDOWS_MS, strict=True):
        sel = (since >= lo_ms) & (since < hi_ms)
        assert w["samples"] == sel.sum() > 0
        assert w["floor"] == pytest.approx(1e-3 / np.mean(y[sel] ** 2))


def test_window_breakdown_of_a_trial_without_onsets_is_empty():
    rng = np.random.default_rng(2)
    x = np.zeros(int(10 * JOINT_FS_HZ))  # the joint held still: no perturbation onset
    trials, _, y_band = prepared([JointTrial("still", x, rng.normal(0.0, 0.1, x.size))])
    assert onsets(trials[0]).size == 0
    windows = window_breakdown(trials, y_band, y_band, noise_var=1e-3)
    assert [w["samples"] for w in windows] == [0] * len(WINDOWS_MS)
    assert all(w["gap"] is None and w["floor"] is None for w in windows)

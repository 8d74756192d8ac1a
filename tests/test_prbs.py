"""Tests for armlab.perturbations.prbs: levels, switching statistics, smoothness, zero ends."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.data import DEFAULT_REKLAB_ROOT, load_ankle_trial
from armlab.errors import ConfigError
from armlab.perturbations import prbs_position

FS = 1000.0
A, DT_SW, F_SMOOTH = 0.03, 0.15, 20.0


def _long(seed: int = 0) -> np.ndarray:
    # 300 s: 2000 switching intervals
    return prbs_position(
        300_000,
        FS,
        amplitude_rad=A,
        switch_interval_s=DT_SW,
        smooth_hz=F_SMOOTH,
        rng=np.random.default_rng(seed),
    )


def test_starts_and_ends_at_zero_and_stays_within_the_levels():
    x = _long()
    assert x[0] == 0.0 and x[-1] == 0.0
    # the fades are raised cosines (zero slope at the ends): the first step is tiny
    assert abs(x[1]) < 1e-3 * A
    # critically damped smoothing never overshoots a level
    assert np.max(np.abs(x)) <= A * (1 + 1e-12)


def test_levels_are_plus_minus_amplitude_at_the_end_of_every_interval():
    x = _long()
    n_int = int(DT_SW * FS)
    ends = np.arange(2 * n_int - 1, x.size - 2 * n_int, n_int)  # last sample of each interval, no fades
    # two poles at 20 Hz settle as (1 + w t) exp(-w t) = 6e-7 of a jump after 150 ms (w t = 18.8)
    np.testing.assert_allclose(np.abs(x[ends]), A, rtol=1e-5)


def test_switching_probability_is_one_half():
    x = _long(1)
    n_int = int(DT_SW * FS)
    signs = np.sign(x[np.arange(2 * n_int - 1, x.size - 2 * n_int, n_int)])
    p = np.mean(signs[1:] != signs[:-1])
    # binomial with n ~ 2000: sd 0.011; 4 sd
    assert abs(p - 0.5) < 0.045
    # and the levels are balanced the same way
    assert abs(np.mean(signs > 0) - 0.5) < 0.045


def test_jumps_are_smooth_at_the_smoothing_bandwidth():
    x = _long(2)
    w = 2 * math.pi * F_SMOOTH
    # steepest slope of a critically damped jump of 2A: 2A·w/e per second; 2 % for the discrete poles
    assert np.max(np.abs(np.diff(x))) * FS <= 2 * A * w / math.e * 1.02
    # above 5x the smoothing frequency the spectrum is down by more than 40 dB from its low band
    spec = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(x.size, 1 / FS)
    low = spec[(f > 0.5) & (f < 2)].mean()
    high = spec[(f > 5 * F_SMOOTH) & (f < 6 * F_SMOOTH)].mean()
    assert high < 1e-4 * low


def test_same_seed_same_sequence_and_different_seeds_differ():
    a = prbs_position(5000, FS, rng=np.random.default_rng(7))
    b = prbs_position(5000, FS, rng=np.random.default_rng(7))
    c = prbs_position(5000, FS, rng=np.random.default_rng(8))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"amplitude_rad": -0.1}, "amplitude_rad"),
        ({"smooth_hz": 600.0}, "Nyquist"),
        ({"switch_interval_s": 1e-4}, "under one sample"),
        ({"switch_interval_s": 4.0}, "no room"),
    ],
)
def test_bad_arguments_raise_config_errors(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        prbs_position(5000, FS, rng=np.random.default_rng(0), **kwargs)


def test_defaults_match_the_reklab_recording():
    if not (DEFAULT_REKLAB_ROOT / "z_df.csv").is_file():
        pytest.skip(f"REKLAB ankle data not present at {DEFAULT_REKLAB_ROOT}")
    real = load_ankle_trial("z_df")
    p = real.position - np.median(real.position)
    sim = prbs_position(real.n_samples, real.fs_hz, rng=np.random.default_rng(3))

    def switches_per_s(x):
        fast = np.abs(np.gradient(x, 1 / real.fs_hz)) > 0.3  # rad/s: inside a jump
        onsets = np.flatnonzero(fast[1:] & ~fast[:-1])
        onsets = onsets[np.r_[True, np.diff(onsets) > 50]]  # one per jump
        return onsets.size / (x.size / real.fs_hz)

    # the same peak excursion (real: pulses to 0.022 +- 0.004 rad, max 0.028) within 15 %
    assert np.percentile(np.abs(sim), 99) == pytest.approx(np.percentile(np.abs(p), 99), rel=0.15)
    # the same switching rate (real: 4 per second) within 10 % (binomial spread over 60 s: 3 %)
    assert switches_per_s(sim) == pytest.approx(switches_per_s(p), rel=0.10)

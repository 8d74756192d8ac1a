"""The ten-sine joint reference of the virtual-force-sensor protocol: range, derivative, fade-in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.perturbations.sum_of_sines import SumOfSines, sum_of_sines

RANGE_RAD = np.deg2rad(10.0)  # the paper's 10 deg per joint (Sec. II-C-1)
BAND_HZ = (0.2, 2.0)  # the protocol's band: components at 0.2, 0.4, ..., 2.0 Hz, period 5 s


def _bare_sum(ref: SumOfSines, t: np.ndarray) -> np.ndarray:
    """(n, joints) the unfaded sum a_j sum_i sin(2 pi f_i t + phi_ji) at any t, negative included."""
    arg = 2 * np.pi * ref.freqs_hz * t[:, None, None] + ref.phases[None]
    return ref.amplitude * np.sin(arg).sum(axis=-1)


def _draw(seed: int = 0, **kw) -> SumOfSines:
    args = dict(n_sines=10, band_hz=BAND_HZ, range_rad=RANGE_RAD, n_joints=2, fade_s=0.0)
    args.update(kw)
    return sum_of_sines(np.random.default_rng(seed), **args)


def test_frequencies_are_evenly_spaced_over_the_band():
    ref = _draw(n_sines=10)
    np.testing.assert_array_equal(ref.freqs_hz, np.linspace(0.2, 2.0, 10))
    assert ref.phases.shape == (2, 10) and ref.amplitude.shape == (2,)
    assert np.all((ref.phases >= 0) & (ref.phases < 2 * np.pi))
    assert _draw(n_sines=1, band_hz=(0.5, 2.0)).freqs_hz.tolist() == [0.5]


@pytest.mark.parametrize("n_joints", [1, 2, 3])
def test_peak_to_peak_over_one_period_equals_the_range(n_joints):
    ref = _draw(seed=n_joints, n_joints=n_joints)
    # One period of the 0.2 Hz grid is 5 s. The reference was scaled on 20000 samples of it
    # (h = 0.25 ms); a sampled extremum misses the true one by at most 1/2 |r''| (h/2)^2, i.e.
    # (2 pi 2 Hz h/2)^2 / 2 ~ 1e-6 of the amplitude sum. Here a 5x finer grid: seen 3e-7 relative.
    t = np.linspace(0.0, 5.0, 100_001)
    v = ref.value(t)
    assert v.shape == (t.size, n_joints)
    np.testing.assert_allclose(np.ptp(v, axis=0), RANGE_RAD, rtol=1e-5)
    # the sum repeats after one period: the range over 4 periods is the same
    t4 = np.linspace(0.0, 20.0, 100_001)
    np.testing.assert_allclose(np.ptp(ref.value(t4), axis=0), RANGE_RAD, rtol=1e-5)


def test_range_with_frequencies_that_are_not_multiples_of_the_lowest():
    # 0.3, 0.533, 0.767, 1.0 Hz: common period 30 s (gcd 1/30 Hz). The module then measures the
    # range over 100/lo = 333 s on 20000 samples (h = 16.7 ms): the sampled extremum may miss the
    # true one by (2 pi 1 Hz h/2)^2 / 2 ~ 1.4e-3 of the amplitude sum; seen 2.5e-4. Allow 2e-3.
    # Reference range here: one 30 s period on a 0.2 ms grid (grid error ~ 2e-7).
    ref = _draw(seed=3, n_sines=4, band_hz=(0.3, 1.0), n_joints=3)
    t = np.linspace(0.0, 30.0, 150_001)
    np.testing.assert_allclose(np.ptp(ref.value(t), axis=0), RANGE_RAD, rtol=2e-3)


def test_value_is_the_documented_sum():
    ref = _draw(seed=5)
    t = np.array([0.0, 0.37, 1.2, 4.99])
    want = np.array(
        [
            [
                ref.amplitude[j]
                * sum(
                    math.sin(2 * math.pi * f * tk + p)
                    for f, p in zip(ref.freqs_hz, ref.phases[j], strict=True)
                )
                for j in range(2)
            ]
            for tk in t
        ]
    )
    np.testing.assert_allclose(ref.value(t), want, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ref.value(t), _bare_sum(ref, t), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("fade_s", [0.0, 0.5, 2.0])
def test_derivative_matches_central_differences(fade_s):
    ref = _draw(seed=7, fade_s=fade_s)
    t = np.linspace(-fade_s - 0.5, 4.0, 1501)
    # stay away from the ends of the fade: the unfaded reference jumps at t = 0, and the raised
    # cosine is C1 only (r'' jumps at -fade_s and 0, a central difference there errs by h |dr''|/4)
    t = t[(np.abs(t) > 1e-3) & (np.abs(t + fade_s) > 1e-3)]
    h = 1e-6
    fd = (ref.value(t + h) - ref.value(t - h)) / (2 * h)
    # central difference: truncation h^2/6 |r'''| ~ 1e-12 * (2 pi 2)^3 * 0.1 rad ~ 2e-10 rad/s;
    # round-off eps |r| / h ~ 1e-11 rad/s. The derivative itself is ~0.3 rad/s.
    np.testing.assert_allclose(ref.derivative(t), fd, atol=1e-7)
    assert np.abs(ref.derivative(t)).max() > 0.1


def test_fade_in_starts_from_rest_and_joins_continuously():
    fade = 1.5
    ref = _draw(seed=11, fade_s=fade)
    unfaded = _draw(seed=11, fade_s=0.0)
    np.testing.assert_array_equal(ref.amplitude, unfaded.amplitude)  # the fade does not rescale
    before = np.linspace(-fade - 3.0, -fade, 50)
    assert np.all(ref.value(before) == 0.0) and np.all(ref.derivative(before) == 0.0)
    # from t = 0 on the faded reference is the full sum
    after = np.linspace(0.0, 5.0, 50)
    np.testing.assert_array_equal(ref.value(after), unfaded.value(after))
    np.testing.assert_array_equal(ref.derivative(after), unfaded.derivative(after))
    # continuity of value and slope at both ends of the fade (raised cosine: C1): a step of 1e-9 s
    # changes a C1 signal by <~ 1e-9 * |r'| ~ 1e-9 rad and its slope by <~ 1e-9 * |r''|
    for t0 in (-fade, 0.0):
        lo, hi = np.array([t0 - 1e-9]), np.array([t0 + 1e-9])
        np.testing.assert_allclose(ref.value(lo), ref.value(hi), atol=1e-8)
        np.testing.assert_allclose(ref.derivative(lo), ref.derivative(hi), atol=1e-7)
    # midway through the fade the weight is 1/2
    mid = np.array([-fade / 2])
    np.testing.assert_allclose(ref.value(mid), 0.5 * _bare_sum(ref, mid), rtol=1e-12)


def test_unfaded_reference_is_zero_before_the_start():
    ref = _draw(seed=2, fade_s=0.0)
    t = np.array([-2.0, -1e-6])
    assert np.all(ref.value(t) == 0.0) and np.all(ref.derivative(t) == 0.0)
    assert np.all(ref.value(np.array([0.0])) != 0.0)  # random phases: sin(phi) != 0


def test_same_seed_same_reference():
    a, b = _draw(seed=42), _draw(seed=42)
    np.testing.assert_array_equal(a.phases, b.phases)
    np.testing.assert_array_equal(a.amplitude, b.amplitude)
    t = np.linspace(0, 5, 101)
    np.testing.assert_array_equal(a.value(t), b.value(t))
    assert not np.array_equal(a.phases, _draw(seed=43).phases)
    # two joints of one draw get their own phases
    assert not np.array_equal(a.phases[0], a.phases[1])


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (dict(n_sines=0), "n_sines"),
        (dict(n_sines=2.5), "n_sines"),
        (dict(band_hz=(2.0, 1.0)), "band_hz"),
        (dict(band_hz=(0.0, 1.0)), "band_hz"),
        (dict(band_hz=(-0.2, 1.0)), "band_hz"),
        (dict(band_hz=(0.2, math.inf)), "band_hz"),
        (dict(range_rad=0.0), "range_rad"),
        (dict(range_rad=-0.1), "range_rad"),
        (dict(range_rad=math.nan), "range_rad"),
        (dict(range_rad=math.inf), "range_rad"),
    ],
)
def test_bad_inputs_rejected(kw, match):
    with pytest.raises(ConfigError, match=match):
        _draw(**kw)

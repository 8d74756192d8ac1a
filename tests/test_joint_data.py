"""armlab.protocols.joint_1dof.diagnosis.data: band-limiting, decimation, train/held-out split, "
"repeats, noise floor."""

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
    prbs_position,
    prepared,
)
from scipy import signal

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.families import fit_model
from armlab.errors import DataError
from armlab.protocols.joint_1dof.diagnosis.data import (
    fit_decimation,
    highpass_sos,
    noise_floor,
    prepare_trials,
    repeat_groups,
)
from armlab.protocols.joint_1dof.diagnosis.models import JOINT_FAMILY

_KW = dict(fs_fit_hz=250.0, band_hz=40.0, holdout_fraction=1.0 / 3.0, slow_hz=0.3, min_duration_s=6.0)


def _sines(t, freqs_hz, amplitude, rng):
    """Sum of sines and its exact first and second derivatives (rad, rad/s, rad/s²)."""
    w = 2 * np.pi * np.asarray(freqs_hz)[:, None]
    phase = w * t + rng.uniform(0, 2 * np.pi, (w.size, 1))
    return (
        (amplitude * np.sin(phase)).sum(0),
        (amplitude * w * np.cos(phase)).sum(0),
        (-amplitude * w**2 * np.sin(phase)).sum(0),
    )


def test_decimates_to_an_integer_fraction_of_the_recorded_rate():
    x = prbs_position(np.random.default_rng(0), 8.0)
    rec = JointTrial("a", x, nominal_torque(x))
    (tr,) = prepare_trials([rec], **_KW)
    assert tr.fs_hz == 250.0 and tr.raw_fs_hz == JOINT_FS_HZ
    assert tr.x.size == x.size // 4 == tr.y.size == tr.v.size == tr.a.size == tr.m.size
    np.testing.assert_allclose(tr.t_s, np.arange(tr.x.size) / 250.0)
    # 1000 / 300 is not an integer: the largest q keeping the rate at or above 300 Hz is 3, so the
    # fitting rate becomes 333.3 Hz
    (tr3,) = prepare_trials([rec], **{**_KW, "fs_fit_hz": 300.0})
    assert tr3.fs_hz == pytest.approx(1000.0 / 3.0)
    assert tr3.x.size == -(-x.size // 3)


@pytest.mark.parametrize(("fs", "fs_fit"), [(660.0, 330.0), (740.0, 370.0), (500.0, 250.0), (2000.0, 250.0)])
def test_the_fitting_rate_is_never_below_the_asked_one(fs, fs_fit):
    """660 Hz data (the ODE referee draws 500-2000 Hz) fit at 330 Hz, not at round(2.64) -> 220 Hz,
    whose 110 Hz Nyquist cannot carry the sensor-bandwidth candidate (the diagnosis was refused)."""
    assert fs / fit_decimation(fs, 250.0) == pytest.approx(fs_fit)


def test_last_fraction_is_held_out_and_the_ends_are_not_scored():
    x = prbs_position(np.random.default_rng(1), 12.0)
    (tr,) = prepare_trials([JointTrial("a", x, nominal_torque(x))], **{**_KW, "holdout_fraction": 0.25})
    n, edge = tr.x.size, int(2.0 * tr.fs_hz)  # default edge_s = 2 s
    assert tr.train.dtype == bool and tr.held.dtype == bool
    assert not (tr.train & tr.held).any()
    split = round(0.75 * n)
    np.testing.assert_array_equal(np.flatnonzero(tr.train), np.arange(edge, split))
    np.testing.assert_array_equal(np.flatnonzero(tr.held), np.arange(split, n - edge))
    (tr0,) = prepare_trials([JointTrial("a", x, nominal_torque(x))], **{**_KW, "edge_s": 0.0})
    assert tr0.train.sum() == round(2 / 3 * n) and (tr0.train | tr0.held).all()


def test_band_limits_torque_and_differentiates_position():
    t = np.arange(int(8 * JOINT_FS_HZ)) / JOINT_FS_HZ
    x = 0.02 * np.sin(2 * np.pi * 5.0 * t)
    torque = 3.0 * np.sin(2 * np.pi * 5.0 * t) + 2.0 * np.sin(2 * np.pi * 150.0 * t)
    (tr,) = prepare_trials([JointTrial("a", x, torque)], **_KW)
    mid = slice(250, -250)  # away from the ends
    # a 4th-order Butterworth at 40 Hz run forward and backward passes 5 Hz with gain
    # 1/(1 + (5/40)^8) = 1 - 6e-8 and leaves (40/150)^8 = 2.6e-5 of 150 Hz: the torque is the 5 Hz
    # part alone to 1e-4 of its amplitude
    ts = tr.t_s[mid]
    np.testing.assert_allclose(tr.y[mid], 3.0 * np.sin(2 * np.pi * 5.0 * ts), atol=3e-4)
    # five-point central differences at 1 kHz: relative error (ωΔt)⁴/30 = 3e-8 at 5 Hz, and the
    # band filter's 6e-8 gain loss: 1e-6 of the amplitude is ten times both
    w = 2 * np.pi * 5.0
    np.testing.assert_allclose(tr.v[mid], 0.02 * w * np.cos(w * ts), atol=1e-6 * 0.02 * w)
    np.testing.assert_allclose(tr.a[mid], -0.02 * w * w * np.sin(w * ts), atol=1e-6 * 0.02 * w * w)


def test_derivatives_stay_accurate_up_to_the_band_edge():
    # at 35 Hz and 1 kHz (ωΔt = 0.22) the three-point stencils miss (ωΔt)²/6 = 0.8 % of the
    # velocity and (ωΔt)²/3 = 1.6 % of the acceleration (np.gradient twice); on clean referee
    # recordings that left 13-24 % of the noise variance unexplained. The five-point stencils
    # miss (ωΔt)⁴/30 = 8e-5 and (ωΔt)⁴/90 = 3e-5. The band filter acts alike on x, v and a, so
    # the amplitude ratios are the derivatives' own.
    t = np.arange(int(8 * JOINT_FS_HZ)) / JOINT_FS_HZ
    w = 2 * np.pi * 35.0
    (tr,) = prepare_trials([JointTrial("a", 0.02 * np.sin(w * t), np.zeros_like(t))], **_KW)
    mid = slice(250, -250)
    basis = np.stack([np.sin(w * tr.t_s[mid]), np.cos(w * tr.t_s[mid])], axis=1)

    def amplitude(z):
        return np.linalg.norm(np.linalg.lstsq(basis, z[mid], rcond=None)[0])

    assert amplitude(tr.v) / (w * amplitude(tr.x)) == pytest.approx(1.0, abs=1e-3)
    assert amplitude(tr.a) / (w * w * amplitude(tr.x)) == pytest.approx(1.0, abs=1e-3)


def test_slow_torque_has_zero_mean_and_unit_rms_and_follows_the_tonic_level():
    rng = np.random.default_rng(2)
    x = prbs_position(rng, 10.0)
    t = np.arange(x.size) / JOINT_FS_HZ
    tonic = 2.0 * np.sin(0.4 * t)
    (tr,) = prepare_trials([JointTrial("a", x, nominal_torque(x) + tonic)], **_KW)
    assert tr.m.mean() == pytest.approx(0.0, abs=1e-12)
    assert np.sqrt(np.mean(tr.m**2)) == pytest.approx(1.0)
    # the stiffness acting on the perturbation's own slow content is removed: m is the tonic level
    q = int(round(JOINT_FS_HZ / tr.fs_hz))
    inner = slice(int(2 * tr.fs_hz), -int(2 * tr.fs_hz))
    assert np.corrcoef(tr.m[inner], tonic[::q][inner])[0, 1] > 0.95


def test_filtered_torque_stays_the_model_of_the_filtered_motion_up_to_the_ends():
    # a trial cut in mid-motion (as recordings are) with the exact torque of I·a + B·v + K·x:
    # prepare_trials must keep its filtered torque that combination of its filtered x, v, a at
    # the ends too (else the scoring high-pass spreads the mismatch over a second of the trial)
    t = np.arange(int(12 * JOINT_FS_HZ)) / JOINT_FS_HZ
    x, v, a = _sines(t, np.arange(1.0, 20.0, 0.7), 0.004, np.random.default_rng(1))
    assert min(abs(v[0]), abs(v[-1])) > 0.5 and min(abs(a[0]), abs(a[-1])) > 50  # moving at both ends
    records = [JointTrial("a", x, -(JOINT_I * a + JOINT_B * v + JOINT_K * x))]
    (tr,) = prepare_trials(records, **{**_KW, "edge_s": 0.0})
    error = tr.y + JOINT_I * tr.a + JOINT_B * tr.v + JOINT_K * tr.x
    # five-point central differences at 1 kHz miss < 1e-5 of each derivative at 20 Hz; the 2 %
    # bound is for the band filter's edge handling
    assert np.max(np.abs(error)) < 0.02 * np.sqrt(np.mean(tr.y**2))
    trials, hp, y_band = prepared(records)
    nominal = fit_model(trials, y_band, (), hp, family=JOINT_FAMILY)
    assert nominal.linear_names == ("I", "B", "K")
    # the torque opposes the motion: the coefficients of the columns [a, v, x] are -I, -B, -K
    np.testing.assert_allclose(-nominal.beta[0], [JOINT_I, JOINT_B, JOINT_K], rtol=0.01)


def test_first_and_last_samples_are_band_limited_too():
    # a 1 N·m raw spike on the first, a middle and the last sample: the anti-alias filter must
    # spread each one like the middle one (peak 2·40/1000 of it); the even edge padding mirrors an
    # edge spike onto itself, at most doubling it. Pinning the edge samples to their raw values
    # (odd padding) would leave the full-band noise of the end samples in the scored torque.
    n = int(8 * JOINT_FS_HZ)
    torque = np.zeros(n)
    torque[[0, n // 2, n - 1]] = 1.0
    rec = JointTrial("a", prbs_position(np.random.default_rng(6), 8.0), torque)
    (tr,) = prepare_trials([rec], **{**_KW, "fs_fit_hz": JOINT_FS_HZ})
    peak = tr.y[n // 2]
    assert 0.05 < peak < 0.1
    assert abs(tr.y[0]) <= 2 * peak + 1e-9 and abs(tr.y[-1]) <= 2 * peak + 1e-9


@pytest.mark.parametrize(
    ("records", "kw", "message"),
    [
        ([], {}, "no trials to diagnose"),
        (
            [
                JointTrial("a", np.zeros(8000), np.zeros(8000)),
                JointTrial("b", np.zeros(4000), np.zeros(4000), 500.0),
            ],
            {},
            "trials have different sample rates {'a': 1000.0, 'b': 500.0}; resample them to one rate first",
        ),
        (
            [JointTrial("short", np.zeros(5000), np.zeros(5000))],
            {},
            "trial 'short' lasts 5.00 s; the diagnosis needs at least 6 s",
        ),
        (
            [JointTrial("a", np.zeros(7000), np.zeros(7000))],
            {},
            "trial 'a' lasts 7.00 s; 2 s at each end are not scored, which leaves less than half of it",
        ),
        (
            [JointTrial("a", np.zeros(8000), np.zeros(8000))],
            {"fs_fit_hz": 80.0},  # q = floor(12.5) = 12: 83.3 Hz, Nyquist margin needs 40/0.45 = 89 Hz
            "diagnosis.band_hz=40 Hz needs a fitting rate above 89 Hz; the data (1000 Hz) with "
            "diagnosis.fs_fit_hz=80 give 83.3333 Hz",
        ),
    ],
)
def test_bad_trials_are_refused_with_the_reason(records, kw, message):
    with pytest.raises(DataError) as err:
        prepare_trials(records, **{**_KW, **kw})
    assert message in str(err.value)


def test_repeat_groups_finds_repeats_of_one_position():
    rng = np.random.default_rng(4)
    x1, x2 = prbs_position(rng, 6.0), prbs_position(rng, 6.0)
    torque = np.zeros_like(x1)
    records = [
        JointTrial("s1_r0", x1, torque),
        JointTrial("s2_r0", x2, torque),
        JointTrial("s1_r1", x1 + rng.normal(0, 1e-4, x1.size), torque),  # encoder noise: still a repeat
        JointTrial("s2_r1", x2, torque),
        JointTrial("s1_short", x1[:-10], torque[:-10]),  # another length: never a repeat
        JointTrial("s3", prbs_position(rng, 6.0), torque),
    ]
    assert repeat_groups(records) == [[0, 2], [1, 3]]
    assert repeat_groups(records[:2]) == []


def test_highpass_is_a_second_order_butterworth_at_the_scoring_edge():
    sos = highpass_sos(250.0, 0.3)
    assert sos.shape == (1, 6)
    f, h = signal.sosfreqz(sos, worN=[0.0, 0.3, 30.0], fs=250.0)
    np.testing.assert_allclose(np.abs(h), [0.0, 1 / np.sqrt(2), 1.0], atol=1e-6)


def _expected_band_variance(noise_std, cfg):
    """N·m² and relative std of its estimate: white noise through the band's filters (zero-phase:
    each power gain twice), and ∫S²/(T(∫S)²) the variance of a variance estimate per second."""
    f = np.linspace(0.0, cfg.fs_fit_hz / 2, 40001)
    _, h_lp = signal.sosfreqz(
        signal.butter(4, cfg.band_hz, fs=JOINT_FS_HZ, output="sos"), worN=f, fs=JOINT_FS_HZ
    )
    _, h_hp = signal.sosfreqz(highpass_sos(cfg.fs_fit_hz, cfg.highpass_hz), worN=f, fs=cfg.fs_fit_hz)
    s = np.abs(h_lp) ** 4 * np.abs(h_hp) ** 4
    return 2 * noise_std**2 / JOINT_FS_HZ * np.trapezoid(s, f), np.trapezoid(s * s, f) / np.trapezoid(
        s, f
    ) ** 2


def test_noise_floor_from_repeats_and_from_second_differences_recover_the_noise():
    cfg = DiagnosisConfig()
    rng = np.random.default_rng(5)
    duration, noise_std = 60.0, 0.15  # s, N·m
    records = joint_trials(prbs_position(rng, duration), nominal_torque, rng, noise_std=noise_std)
    trials, _, _ = prepared(records, cfg)
    expected, var_per_s = _expected_band_variance(noise_std, cfg)
    # the difference of two repeats over the 56 s scored (2 s left out at each end): 2.1 %
    rel_std = np.sqrt(var_per_s / (duration - 4.0))
    repeats = noise_floor(records, trials, band_hz=cfg.band_hz, highpass_hz=cfg.highpass_hz)
    assert repeats.source == "repeats"
    assert repeats.variance_Nm2 == pytest.approx(expected, rel=3 * rel_std)
    # PSD: white in the middle of the band at 2σ²/fs_raw
    mid = (repeats.f_hz > 5) & (repeats.f_hz < 25)
    assert np.mean(repeats.psd[mid]) == pytest.approx(2 * noise_std**2 / JOINT_FS_HZ, rel=0.1)

    single = noise_floor(records[:1], trials[:1], band_hz=cfg.band_hz, highpass_hz=cfg.highpass_hz)
    assert single.source.startswith("second differences")
    # 60 000 second differences estimate σ² to ±0.8 % (1 sd); the smoothed PRBS adds < 1 %
    assert single.variance_Nm2 == pytest.approx(expected, rel=0.04)
    assert single.variance_Nm2 == pytest.approx(repeats.variance_Nm2, rel=0.2)
    np.testing.assert_allclose(np.trapezoid(single.psd, single.f_hz), single.variance_Nm2)


def test_noise_floor_from_groups_of_repeats_of_different_lengths():
    # two perturbation sequences of different durations, each recorded twice
    rng = np.random.default_rng(9)
    records = [
        *joint_trials(prbs_position(rng, 10.0), nominal_torque, rng, noise_std=0.15),
        *joint_trials(prbs_position(rng, 14.0), nominal_torque, rng, noise_std=0.15),
    ]
    records = [JointTrial(f"t{i}", r.position, r.torque) for i, r in enumerate(records)]
    assert repeat_groups(records) == [[0, 1], [2, 3]]
    trials, _, _ = prepared(records)
    floor = noise_floor(records, trials, band_hz=40.0, highpass_hz=0.3)
    expected, var_per_s = _expected_band_variance(0.15, DiagnosisConfig())
    # 6 s + 10 s scored: 3 sampling sd of the pooled estimate
    assert floor.variance_Nm2 == pytest.approx(expected, rel=3 * np.sqrt(var_per_s / 16.0))
    assert floor.psd.shape == floor.f_hz.shape


def test_only_digital_filters_limit_the_recorded_rate():
    """The torque sensor's natural frequency (up to 100 kHz) is applied as an exact frequency
    response, so 100 Hz data are diagnosed with every candidate; the reflex's digital low-pass
    (up to 25 Hz) still needs a fitting rate above 50 Hz, and the error names it."""
    from armlab.protocols.joint_1dof.diagnosis.diagnose import _check_rate, candidate_names
    from armlab.protocols.joint_1dof.diagnosis.models import ANY_RATE_HZ, JOINT_SURROGATES

    names = candidate_names(DiagnosisConfig())
    assert "force_sensor_bandwidth" in names
    # every exempt frequency is a parameter of a candidate (a rename cannot leave it stale)
    assert all(
        any(f"{n}.{p.name}" == key for n, s in JOINT_SURROGATES.items() for p in s.params)
        for key in ANY_RATE_HZ
    )
    _check_rate(names, 100.0, 100.0)
    with pytest.raises(DataError, match="'reflex'"):
        _check_rate(names, 40.0, 40.0)

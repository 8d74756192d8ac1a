"""A robust ``none`` for the joint_1dof diagnosis (issue 18 item 2).

Clean recordings of a perfect nominal joint, with white torque noise from 1e-4 to 1e-1 of the
torque's rms, must be called ``none``: at the quiet end the noise no longer sets the smallest gap
a correct model reaches, the evaluation of the model does (the derivative estimator, the record's
ends). Ground truth: NumPy recordings whose torque is I·θ̈ + B·θ̇ + K·θ of the recorded angle,
with exact (analytic) derivatives or with ``numpy.gradient``'s (conftest), and noise of known
variance.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import (
    JOINT_B,
    JOINT_FS_HZ,
    JOINT_I,
    JOINT_K,
    JointTrial,
    nominal_torque,
    prbs_position,
    prepared,
)
from scipy import signal

from armlab.config.diagnosis import DiagnosisConfig
from armlab.protocols.joint_1dof.diagnosis.data import derivatives, noise_floor
from armlab.protocols.joint_1dof.diagnosis.derivative_floor import derivative_floor
from armlab.protocols.joint_1dof.diagnosis.diagnose import diagnose_joint

_LEVELS = (1e-4, 1e-3, 1e-2, 1e-1)  # noise std / torque rms: the three decades
_DURATION_S = 20.0  # s: 12 s scored (2 s ends), a third held out


def _multisine(rng, fs: float, duration_s: float):
    """(rad, rad/s, rad/s²): 0.5-20 Hz multisine of ~0.02 rad rms with its exact derivatives."""
    t = np.arange(int(duration_s * fs)) / fs
    f = np.arange(0.5, 20.0, 0.5)[:, None]
    amp = 0.02 / np.sqrt(f.size) / (1.0 + f / 5.0)
    phase = 2 * np.pi * f * t + rng.uniform(0, 2 * np.pi, f.shape)
    w = 2 * np.pi * f
    return (
        (amp * np.sin(phase)).sum(0),
        (amp * w * np.cos(phase)).sum(0),
        (-amp * w**2 * np.sin(phase)).sum(0),
    )


def _records(kind: str, level: float, fs: float, seed: int = 1):
    """Two repeats of one perturbation: the torque of a perfect nominal plus white noise of
    ``level`` × its rms. ``exact``: analytic derivatives; ``gradient``: numpy.gradient's."""
    rng = np.random.default_rng(seed)
    if kind == "exact":
        x, v, a = _multisine(rng, fs, _DURATION_S)
        y = -(JOINT_I * a + JOINT_B * v + JOINT_K * x)
    else:
        x = prbs_position(rng, _DURATION_S)
        y = nominal_torque(x)
    s = level * float(np.sqrt(np.mean(y**2)))
    return [JointTrial(f"rep{k}", x, y + rng.normal(0.0, s, x.size), fs) for k in range(2)], s


@pytest.mark.parametrize("level", _LEVELS)
@pytest.mark.parametrize(("kind", "fs"), [("exact", 500.0), ("exact", 2000.0), ("gradient", JOINT_FS_HZ)])
def test_a_perfect_nominal_is_none_from_1e4_to_1e1_of_the_torque(kind, fs, level):
    results, _ = diagnose_joint(_records(kind, level, fs)[0], DiagnosisConfig())
    assert results["verdict"] == ["none"], results["gap"]


@pytest.mark.parametrize("level", _LEVELS)
def test_the_sensor_noise_floor_recovers_known_noise_over_three_decades(level):
    """One trial (second differences) and two repeats, against the noise's variance through the
    diagnosis' own filters (the anti-alias low-pass and scoring high-pass, each applied twice)."""
    records, s = _records("gradient", level, JOINT_FS_HZ)
    cfg = DiagnosisConfig()
    trials, _, _ = prepared(records, cfg)
    f = np.linspace(0.0, trials[0].fs_hz / 2, 4097)
    _, h_lp = signal.sosfreqz(
        signal.butter(4, cfg.band_hz, fs=JOINT_FS_HZ, output="sos"), worN=f, fs=JOINT_FS_HZ
    )
    _, h_hp = signal.sosfreqz(
        signal.butter(2, cfg.highpass_hz, "high", fs=trials[0].fs_hz, output="sos"),
        worN=f,
        fs=trials[0].fs_hz,
    )
    expected = 2 * s**2 / JOINT_FS_HZ * np.trapezoid(np.abs(h_lp) ** 4 * np.abs(h_hp) ** 4, f)
    for recs, trs in ((records[:1], trials[:1]), (records, trials)):
        floor = noise_floor(recs, trs, band_hz=cfg.band_hz, highpass_hz=cfg.highpass_hz)
        # 20 000 second differences estimate σ² to ±1.1 % (1 sd, MAD), 12 s of repeats' difference
        # to ±5.5 % (1 sd over ~330 degrees of freedom in the band): 4 sd of the coarser; at 1e-4
        # the signal's own second differences (the smoothed PRBS's corners) bias the MAD upwards
        # by < 10 % (measured 3-6 %), which the repeats, taken when smaller, do not have
        assert floor.variance_Nm2 == pytest.approx(expected, rel=0.22), (level, floor.source)


def test_derivatives_are_fourth_order_at_the_ends():
    """The one-sided end stencils: a 3 Hz sine at 500 Hz differentiated to ~1e-6 of its
    amplitude at every sample, ends included (np.gradient's second-order ends: ~1e-3)."""
    fs = 500.0
    t = np.arange(1000) / fs
    w = 2 * np.pi * 3.0
    v, a = derivatives(np.sin(w * t + 0.3), fs)
    # fourth order: error ~ (ωh)⁴ of ωh = 0.038: 2e-6 relative
    assert np.max(np.abs(v / w - np.cos(w * t + 0.3))) < 2e-6
    assert np.max(np.abs(a / w**2 + np.sin(w * t + 0.3))) < 2e-6


def test_the_derivative_floor_appears_only_where_the_data_favour_another_estimator():
    """Exact derivatives: the floor is at most the five-point stencil's own truncation, which the
    seven-point alternative shows (interior against interior, the ends shared): below 20 % of the
    noise floor at 1e-4 noise and 500 Hz, the referees' slowest rate (the acceleration's error
    (ωh)⁴/90 is 7e-4 at 40 Hz; measured 13.5 %, 0 at 1 kHz), and never above the gap it stands
    for (the nominal's held-out gap less the sensor floor, plus the held-out fits' 10 % spread);
    numpy.gradient's torque: the floor is the gap the choice leaves (within 10 %: that spread)."""
    cfg = DiagnosisConfig()
    for kind, fs in (("exact", 500.0), ("gradient", JOINT_FS_HZ)):
        records, _ = _records(kind, 1e-4, fs)
        results, _ = diagnose_joint(records, cfg)
        gap = results["gap"]
        if kind == "exact":
            assert gap["derivative_floor"] < 0.2 * gap["sensor_noise_floor"]
            excess = max(gap["nominal"] - gap["sensor_noise_floor"], 0.0)
            assert gap["derivative_floor"] <= 1.1 * excess + 0.1 * gap["sensor_noise_floor"]
        else:
            trials, hp, y_band = prepared(records, cfg)
            assert derivative_floor(trials, hp, y_band) > 0
            assert gap["derivative_floor"] == pytest.approx(
                gap["nominal"] - gap["sensor_noise_floor"], rel=0.1
            )
        assert gap["noise_floor"] == pytest.approx(gap["sensor_noise_floor"] + gap["derivative_floor"])


def test_an_effect_is_still_named_on_a_quiet_recording():
    """The floors do not hide a real effect: a 1 N·m·s/rad-class reflex on the exact multisine at
    1e-3 noise (its band power ~100x the noise's) is named."""
    rng = np.random.default_rng(2)
    x, v, a = _multisine(rng, JOINT_FS_HZ, _DURATION_S)
    y = -(JOINT_I * a + JOINT_B * v + JOINT_K * x)
    t = np.arange(x.size) / JOINT_FS_HZ
    w = 2 * np.pi * 3.0
    b, c = signal.bilinear([w * w], [1.0, 1.4 * w, w * w], JOINT_FS_HZ)
    reflex = -0.5 * signal.lfilter(b, c, np.maximum(np.interp(t - 0.045, t, v, left=0.0), 0.0))
    s = 1e-3 * float(np.sqrt(np.mean(y**2)))
    records = [JointTrial(f"rep{k}", x, y + reflex + rng.normal(0.0, s, x.size)) for k in range(2)]
    results, _ = diagnose_joint(records, DiagnosisConfig())
    assert results["verdict"] == ["reflex"], results["gap"]


def _on_grid(kind: str, step_of_rms: float, n: int):
    """``n`` identical repeats of a perfect nominal whose torque is recorded on a grid of
    ``step_of_rms`` × its rms and nothing else (a converter, or a file's rounding, with no noise
    beside it): most of its k-th differences are exactly 0."""
    rng = np.random.default_rng(1)
    if kind == "exact":
        x, v, a = _multisine(rng, 500.0, _DURATION_S)
        y, fs = -(JOINT_I * a + JOINT_B * v + JOINT_K * x), 500.0
    else:
        x = prbs_position(rng, _DURATION_S)
        y, fs = nominal_torque(x), JOINT_FS_HZ
    q = step_of_rms * float(np.sqrt(np.mean(y**2)))
    return [JointTrial(f"rep{k}", x, np.round(y / q) * q, fs) for k in range(n)], y, q


@pytest.mark.parametrize(
    ("kind", "step_of_rms", "n"),
    [("exact", 1e-2, 1), ("exact", 1e-2, 2), ("gradient", 1e-3, 1), ("gradient", 1e-2, 2)],
)
def test_a_perfect_nominal_on_a_torque_grid_is_none(kind, step_of_rms, n):
    """The grid's error is a floor no model removes: before, the MAD of the differences read 0
    (and identical repeats differ by nothing), the floor was 0 and the low-band check divided by
    it. The multisine crosses a step every sample (white q²/12); the smoothed PRBS holds still
    between its moves, so its error is a constant per hold (the grid's run-by-run model)."""
    records, _, _ = _on_grid(kind, step_of_rms, n)
    results, _ = diagnose_joint(records, DiagnosisConfig())
    assert results["verdict"] == ["none"], results["gap"]
    assert "grid" in results["gap"]["noise_source"] or n == 1


@pytest.mark.parametrize("kind", ["exact", "gradient"])
def test_the_torque_grid_floor_against_the_true_grid_error(kind):
    """Ground truth: the recorded minus the true torque through the scoring filters, over the
    scored samples. White q²/12 where the multisine crosses a step every sample (within 15 %: the
    grid's error is uniform only on average, 12 s at 250 Hz); on the PRBS's holds within a factor
    of three (the angle's grid model, checked there at 0.74-2.03 of the truth), and well above the
    white q²/12, which misses the holds' constants."""
    records, y, q = _on_grid(kind, 1e-2, 2)
    cfg = DiagnosisConfig()
    trials, hp, _ = prepared(records, cfg)
    floor = noise_floor(records, trials, band_hz=cfg.band_hz, highpass_hz=cfg.highpass_hz)
    tr = trials[0]
    e = signal.sosfiltfilt(hp, tr.to_fit_rate(records[0].torque - y), padtype="even")[tr.train | tr.held]
    truth = float(np.mean(e**2))
    if kind == "exact":
        assert floor.variance_Nm2 == pytest.approx(truth, rel=0.15), floor.source
    else:
        assert truth / 3 < floor.variance_Nm2 < 3 * truth, (floor.variance_Nm2, truth, floor.source)
        white = 2 * q * q / 12 / JOINT_FS_HZ * cfg.band_hz  # an upper bound of white q²/12 in band
        assert floor.variance_Nm2 > 3 * white


def test_a_reflex_is_still_named_on_a_torque_grid():
    """The grid's floor does not hide a real effect: the reflex of the quiet-recording test on a
    torque grid of 1e-3 of its rms, no noise."""
    rng = np.random.default_rng(2)
    x, v, a = _multisine(rng, JOINT_FS_HZ, _DURATION_S)
    t = np.arange(x.size) / JOINT_FS_HZ
    w = 2 * np.pi * 3.0
    b, c = signal.bilinear([w * w], [1.0, 1.4 * w, w * w], JOINT_FS_HZ)
    reflex = -0.5 * signal.lfilter(b, c, np.maximum(np.interp(t - 0.045, t, v, left=0.0), 0.0))
    y = -(JOINT_I * a + JOINT_B * v + JOINT_K * x) + reflex
    q = 1e-3 * float(np.sqrt(np.mean(y**2)))
    records = [JointTrial(f"rep{k}", x, np.round(y / q) * q) for k in range(2)]
    results, _ = diagnose_joint(records, DiagnosisConfig())
    assert results["verdict"] == ["reflex"], results["gap"]

"""Issue 20, second review: a non-zero co-contraction σ is part of every truth the checks score
against (Eq. 2.2.4: K_cont = diag(k_σ)·σ), and a stop without trials leaves NaN rows that the
checks step over instead of failing on them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.models import THESIS_FIELD, quadratic_basis
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, SimulationConfig
from armlab.protocols.cartesian_online.experiment import simulate_cartesian
from armlab.protocols.cartesian_online.results import estimate_cartesian


@pytest.fixture(scope="module")
def thesis_trials():
    # noise study off: checks 3, 4, 5, 9 read only the noise-free cases
    cfg = CartesianOnlineConfig(simulation=SimulationConfig(noise_study_std_N=0.0))
    return cfg, simulate_cartesian(cfg).trials


def test_coefficients_at_sigma_add_k_sigma_to_the_constant_term():
    # direct evaluation of Eq. 2.2.4 at random points: polynomial at σ equals K(q, σ)
    q = np.random.default_rng(0).uniform([0.85, 0.0], [1.05, 0.2], size=(50, 2))
    for sigma in (0.0, 0.3, 1.0):
        k_poly = quadratic_basis(q) @ THESIS_FIELD.coefficients_at(sigma).T
        np.testing.assert_allclose(k_poly, THESIS_FIELD.stiffness(q, sigma), rtol=1e-14)
    np.testing.assert_array_equal(THESIS_FIELD.coefficients_at(0.0), THESIS_FIELD.scaled_coefficients)
    with pytest.raises(ConfigError, match=r"sigma .* must lie in \[0, 1\], got 1.5"):
        THESIS_FIELD.coefficients_at(1.5)


def test_a_sigma_one_run_passes_checks_5_and_9():
    # before the mend the truths left k_σ·σ out and checks 5 and 9 failed while applying
    cfg = CartesianOnlineConfig(simulation=SimulationConfig(sigma=1.0, noise_study_std_N=0.0))
    results, _ = estimate_cartesian(simulate_cartesian(cfg).trials, cfg.identification)
    rows = {c["id"]: c for c in results["checks"]}
    assert results["sigma"] == 1.0
    for n in (4, 5, 9):
        assert rows[n]["applies"] and rows[n]["passed"], rows[n]
    # check 1 stays the Table values at σ = 0
    assert rows[1]["passed"]


@pytest.mark.parametrize("case", ["exp2", "exp3", "exp4"])
def test_a_stop_without_trials_does_not_fail_the_checks(thesis_trials, case):
    cfg, trials = thesis_trials
    meta = trials.trial_meta
    drop = (np.asarray(meta["case"]) == case) & (np.asarray(meta["stop"]) == 7)
    results, _ = estimate_cartesian(trials.select(~drop), cfg.identification)
    rows = {c["id"]: c for c in results["checks"]}
    # the remaining 19 stops still identify the field: the checks that read this case pass
    ids = {"exp2": (3,), "exp3": (4,), "exp4": (5, 9)}[case]
    for n in ids:
        assert rows[n]["passed"], rows[n]


# one source for the sample-rate rule; refusals of the reference paths --------------------------
def test_preflight_and_sample_share_the_ramp_rate_rule():
    from armlab.perturbations import MIN_SAMPLES_PER_SEGMENT, TRAPEZOIDAL
    from armlab.protocols.cartesian_online.preflight import validate

    # the trapezoid's 50 ms ramp (thesis §3.1.1) at 10 samples: 200 Hz
    assert TRAPEZOIDAL.min_fs_hz == pytest.approx(MIN_SAMPLES_PER_SEGMENT / 0.05)
    TRAPEZOIDAL.sample(TRAPEZOIDAL.min_fs_hz)
    with pytest.raises(ConfigError, match=r"fs = 199 Hz gives fewer than 10 samples.*fs >= 200 Hz"):
        TRAPEZOIDAL.sample(199.0)
    cfg = CartesianOnlineConfig()
    bad = dataclasses.replace(cfg, sensors=dataclasses.replace(cfg.sensors, fs_hz=199.0))
    with pytest.raises(ConfigError, match=r"sensors.fs_hz=199 Hz .* valid: >= 200 Hz"):
        validate(bad)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "line"}, r"unknown reference path kind 'line'; valid: waypoints, circle, sinusoid, spiral"),
        ({"kind": "circle", "duration_s": 0.0}, r"duration_s must be positive, got 0.0"),
        ({"kind": "circle", "radius_m": -0.1}, r"got radius_m=-0.1, omega_rad_s="),
        ({"kind": "circle", "omega_rad_s": np.inf}, r"omega_rad_s finite, got radius_m=0.1, omega_rad_s=inf"),
        ({"kind": "circle", "centre": (np.nan, 0.1)}, r"centre must be two finite numbers \(x, y\) m, got"),
        (
            {"kind": "spiral", "end_radius_fraction": 0.0},
            r"end_radius_fraction must lie in \(0, 1\], got 0.0",
        ),
        (
            {"kind": "circle", "end_radius_fraction": 0.5},
            r"read by kind 'spiral' only; a 'circle' path needs 1",
        ),
        ({"kind": "waypoints", "waypoints": ((0.9, 0.1, 0.0),)}, r"at least two \(x, y, s\) rows"),
        (
            {"kind": "waypoints", "waypoints": ((0.9, 0.1, 0.0), (1.0, 0.1, 50.0))},
            r"waypoint times must increase from 0 to duration_s = 100.0 s",
        ),
    ],
)
def test_reference_path_refusals_name_the_problem(kwargs, message):
    from armlab.perturbations.reference_paths import ReferencePath

    with pytest.raises(ConfigError, match=message):
        ReferencePath(**kwargs)


def test_path_and_stop_refusals_name_the_problem():
    from armlab.perturbations import TRIANGULAR, circle_path, spiral_path, stop_path_times, stop_timeline

    with pytest.raises(ConfigError, match=r"revolutions must be positive, got 0"):
        circle_path(0)
    with pytest.raises(ConfigError, match=r"revolutions must be positive, got -1"):
        spiral_path(0.1, -1)
    with pytest.raises(ConfigError, match=r"n_stops must be a positive integer, got 0"):
        stop_path_times(0)
    path = circle_path()
    one = [np.array([[1.0, 0.0]])]
    with pytest.raises(ConfigError, match=r"stop_times must increase within \[0, 100.0\] s"):
        stop_timeline(path, TRIANGULAR, np.array([150.0]), one)
    with pytest.raises(ConfigError, match=r"one direction list per stop"):
        stop_timeline(path, TRIANGULAR, np.array([10.0, 20.0]), one)
    with pytest.raises(ConfigError, match=r"each stop needs at least one \(x, y\) direction"):
        stop_timeline(path, TRIANGULAR, np.array([10.0]), [np.zeros((0, 2))])
    with pytest.raises(ConfigError, match=r"fs must be positive and pause_s non-negative, got fs=0"):
        stop_timeline(path, TRIANGULAR, np.array([10.0]), one, fs=0.0)
    # stops fill equal slots of the path's own duration (not the module's 100 s)
    np.testing.assert_allclose(stop_path_times(4, 40.0), [5.0, 15.0, 25.0, 35.0])


def test_trials_without_path_time_are_refused():
    from armlab.errors import DataError
    from armlab.protocols.cartesian_online.experiment import records_from_trials

    trials = simulate_cartesian(CartesianOnlineConfig(simulation=SimulationConfig(n_stops=3))).trials
    meta = {k: v for k, v in trials.trial_meta.items() if k != "path_time_s"}
    with pytest.raises(DataError, match=r"the trials lack \['path_time_s'\]"):
        records_from_trials(dataclasses.replace(trials, trial_meta=meta))

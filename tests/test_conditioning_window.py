"""Protocol conditioning_window against ground truth (CI sweeps the observation window)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.config.schema import (
    ArmConfig,
    CuffConfig,
    EstimatorConfig,
    ReflexConfig,
    ScenarioConfig,
    SensorsConfig,
)
from armlab.config.subject import SubjectConfig
from armlab.errors import ConfigError
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import (
    estimate_protocol,
    linearisation_bias,
    simulate_protocol,
    window_specs,
)


def _run(cfg: ConditioningWindowConfig):
    rec, scenario = simulate_protocol(cfg)
    results, _ = estimate_protocol(rec.trials, cfg.estimator, window_specs(scenario, cfg.estimator))
    return rec, results


@pytest.fixture(scope="module")
def exact():
    # the ideal lab: linear muscles (exact linearised truth), rigid cuff, ideal sensors, no reflex,
    # a steady subject, no filter; 13 trials per window (12 identify: every direction twice) —
    # exact data need few trials
    cfg = ConditioningWindowConfig(
        arm=ArmConfig(muscle="linear"),
        cuff=CuffConfig(rigid=True),
        sensors=SensorsConfig(preset="ideal"),
        reflex=ReflexConfig(enabled=False),
        subject=SubjectConfig(enabled=False),
        estimator=EstimatorConfig(lowpass_hz=None),
        scenario=ScenarioConfig(name="conditioning_window", n_trials=13),
    )
    return _run(cfg)


def test_every_window_recovers_truth_on_exact_data(exact):
    _, results = exact
    windows = results["windows"]
    assert len(windows) == 26 + 3  # the paper's 26 windows + 3 extension windows
    for w in windows:
        # 1 %: what remains on exact data is MuJoCo's O(timestep) integration error (0.5 ms Euler:
        # xi ~0.3 %) amplified by cond(W) ~ 3e3 in the shortest window (K ~0.9 % at 120 ms).
        assert w["K_rel_err"] < 0.01, (w["t_obs_s"], w["K_rel_err"])
        assert w["D_rel_err"] < 0.01, (w["t_obs_s"], w["D_rel_err"])
        assert w["xi_rel_err"] < 0.01, (w["t_obs_s"], w["xi_rel_err"])
        assert min(w["validation"]["vaf_pct"]) > 99.0


def test_exact_data_criteria_hold_from_the_first_window(exact):
    _, results = exact
    c = results["criteria"]["full"]
    assert c["K_pd_from_s"] == pytest.approx(0.12)
    assert c["symmetric_from_s"] == pytest.approx(0.12)


def test_ground_truth_is_consistent_with_the_model(exact):
    rec, results = exact
    K = np.asarray(results["ground_truth"]["K"])
    assert np.all(np.linalg.eigvalsh(0.5 * (K + K.T)) > 0)
    # the same numbers travel with the trials
    assert np.allclose(rec.trials.attrs["ground_truth"]["K"], K)


@pytest.fixture(scope="module")
def noisy_pair():
    # the sensor chain alone: realistic sensors, Hill muscles, the stiff 20 kN/m cuff of
    # CuffConfig and a steady subject (the default lab's soft tissue and activation fluctuation
    # are pinned against the paper in test_conditioning_fidelity.py); reflex off and on
    base = {
        "scenario": ScenarioConfig(name="conditioning_window", k_values=[26]),
        "cuff": CuffConfig(),
        "subject": SubjectConfig(enabled=False),
    }
    off = _run(ConditioningWindowConfig(reflex=ReflexConfig(enabled=False), **base))[1]
    on = _run(ConditioningWindowConfig(**base))[1]
    return off, on


def test_default_noise_without_reflex_K_within_10_percent_beyond_400ms(noisy_pair):
    off, _ = noisy_pair
    long = [w for w in off["windows"] if w["t_obs_s"] >= 0.4 - 1e-9]
    assert long
    for w in long:
        # 10 %: the bound; measured ~4 % with the 20 Hz zero-phase filter (seed 0)
        assert w["K_rel_err"] < 0.10, (w["t_obs_s"], w["K_rel_err"])


def test_reflex_drives_the_estimate_away_from_intrinsic_truth(noisy_pair):
    off, on = noisy_pair
    err_on = np.array([w["K_rel_err"] for w in on["windows"]])
    err_off = np.array([w["K_rel_err"] for w in off["windows"]])
    # beyond the reflex latencies the reflex adds stiffness the intrinsic truth does not have:
    # the error is several times the reflex-free one and grows with the window
    assert np.all(err_on > 3 * err_off)
    assert np.all(np.diff(err_on) > 0)
    K_on = np.asarray(on["windows"][-1]["K"])
    K_true = np.asarray(on["ground_truth"]["K"])
    assert np.trace(K_on) > 1.3 * np.trace(K_true)


def test_same_seed_bit_identical_different_seed_differs():
    cfg = ConditioningWindowConfig(
        scenario=ScenarioConfig(name="conditioning_window", k_values=[1], n_trials=4)
    )
    a = simulate_protocol(cfg)[0].trials
    b = simulate_protocol(cfg)[0].trials
    c = simulate_protocol(
        ConditioningWindowConfig(
            seed=1, scenario=ScenarioConfig(name="conditioning_window", k_values=[1], n_trials=4)
        )
    )[0].trials
    for name in a.channels:
        assert np.array_equal(a.channels[name], b.channels[name]), name
    assert not np.array_equal(a.channels["hand_force"], c.channels["hand_force"])


def test_window_longer_than_record_is_rejected():
    cfg = ConditioningWindowConfig(
        scenario=ScenarioConfig(name="conditioning_window", k_values=[1], n_trials=4),
        estimator=EstimatorConfig(t_obs_s=[5.0]),
    )
    rec, scenario = simulate_protocol(cfg)
    with pytest.raises(ConfigError, match="longer than the recorded data"):
        estimate_protocol(rec.trials, cfg.estimator, window_specs(scenario, cfg.estimator))


def test_linearisation_bias_is_reported_and_exceeds_the_linear_variant():
    # Exact data except for the muscle model: the linear variant leaves only MuJoCo's integration
    # error; the Hill muscle's curved force-length-velocity relations leave a real bias, which
    # issue 2's measurement puts at K 0.4 %, D 3.1 % at T_obs = 370 ms.
    small = ScenarioConfig(name="conditioning_window", k_values=[1, 26], n_trials=13)
    hill = linearisation_bias(ConditioningWindowConfig(scenario=small))
    linear = linearisation_bias(ConditioningWindowConfig(arm=ArmConfig(muscle="linear"), scenario=small))
    assert hill["muscle"] == "hill" and hill["t_obs_s"] == pytest.approx(0.37)
    assert linear["K_rel_err"] < 0.002 and linear["D_rel_err"] < 0.002
    assert hill["K_rel_err"] < 0.02 and hill["D_rel_err"] < 0.06  # small: the model holds at 0.05 rad
    assert hill["D_rel_err"] > 5 * linear["D_rel_err"]  # but it is there, and it is the muscle's

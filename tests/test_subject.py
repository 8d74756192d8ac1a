"""armlab.sim.subject: the subject's activation fluctuation, and the effective truth on exact data."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.config.schema import ArmConfig, ReflexConfig, ScenarioConfig
from armlab.config.subject import SubjectConfig
from armlab.errors import ConfigError
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import simulate_protocol, window_specs
from armlab.protocols.conditioning_window.truths import effective_truth
from armlab.sim.subject import activation_commands

BASE = np.array([0.2, 0.25, 0.2, 0.3, 0.2, 0.22])


def _draw(subject, seed=0, n_trials=200, n_steps=2000):
    return activation_commands(BASE, subject, n_trials, n_steps, 2, 1000.0, np.random.default_rng(seed))


def test_fluctuation_has_the_stated_rms_and_is_reproducible():
    subject = SubjectConfig(enabled=True, fluctuation_cv=0.05, fluctuation_hz=2.0, trial_cv=0.0)
    cmd = _draw(subject)
    assert cmd.shape == (200, 2000, 6)
    rel = cmd / BASE - 1.0
    # 10 %: 200 trials x 1 s of a 2 Hz process hold ~400 independent stretches per muscle
    assert np.std(rel) == pytest.approx(0.05, rel=0.1)
    assert np.array_equal(cmd, _draw(subject))  # same generator state, same commands
    assert not np.array_equal(cmd, _draw(subject, seed=1))
    assert np.array_equal(cmd[:, 0::2], cmd[:, 1::2])  # held over the 2 physics steps of a sample


def test_trial_variation_is_common_to_the_muscles_and_constant_in_a_trial():
    cmd = _draw(SubjectConfig(enabled=True, fluctuation_cv=0.0, trial_cv=0.1))
    rel = cmd / BASE - 1.0
    assert np.allclose(rel, rel[:, :1, :1])  # one factor per trial
    assert np.std(rel[:, 0, 0]) == pytest.approx(0.1, rel=0.2)  # 200 trials: ~5 % sampling error


def test_subject_config_rejects_bad_values():
    with pytest.raises(ConfigError, match=r"subject.fluctuation_cv must lie in \[0, 0.5\)"):
        SubjectConfig(fluctuation_cv=0.7)
    with pytest.raises(ConfigError, match=r"subject.fluctuation_hz must lie in \(0, 50\] Hz"):
        SubjectConfig(fluctuation_hz=0.0)
    assert not SubjectConfig(enabled=True).active  # no magnitude: nothing fluctuates


def test_effective_truth_is_the_intrinsic_truth_without_reflex():
    # linear muscles, reflex off: the effective truth is the ideal lab's estimate, exact up to
    # MuJoCo's integration error (< 1 % at 0.5 ms Euler, see test_conditioning_window)
    cfg = ConditioningWindowConfig(
        arm=ArmConfig(muscle="linear"),
        reflex=ReflexConfig(enabled=False),
        scenario=ScenarioConfig(name="conditioning_window", k_values=[26], n_trials=7),
    )
    rec, scenario = simulate_protocol(cfg)
    eff = effective_truth(cfg, rec.trials, scenario, window_specs(scenario, cfg.estimator))
    K = np.asarray(rec.truth.as_dict()["K"])
    for w in eff:
        assert np.linalg.norm(np.asarray(w["K"]) - K) / np.linalg.norm(K) < 0.01


def test_the_same_seed_gives_bit_identical_fluctuating_trials():
    cfg = ConditioningWindowConfig(
        scenario=ScenarioConfig(name="conditioning_window", k_values=[1], n_trials=4)
    )
    a = simulate_protocol(cfg)[0].trials
    b = simulate_protocol(cfg)[0].trials
    steady = simulate_protocol(replace(cfg, subject=replace(cfg.subject, enabled=False)))[0].trials
    assert np.array_equal(a.channels["hand_force"], b.channels["hand_force"])
    assert not np.array_equal(a.channels["hand_force"], steady.channels["hand_force"])
    # a steady subject holds the hold's activation: no fluctuation before onset
    act = steady.channels["true_activation"][:, :250]
    assert np.allclose(act, act[:, :1], atol=1e-6)


def test_a_fluctuation_corner_above_nyquist_is_a_config_error():
    # SubjectConfig accepts up to 50 Hz; at a 100 Hz sample rate that is the Nyquist frequency
    subject = SubjectConfig(enabled=True, fluctuation_cv=0.03, fluctuation_hz=50.0)
    with pytest.raises(ConfigError, match=r"subject.fluctuation_hz must lie in \(0, 50.0\) Hz"):
        activation_commands(np.array([0.1]), subject, 1, 100, 1, 100.0, np.random.default_rng(0))

"""Protocol fractional_elbow (seeds/004) against the five-element ground truth."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from omegaconf import OmegaConf

from armlab.config.schema import (
    ElbowConfig,
    FrfConfig,
    ReflexConfig,
    ScenarioConfig,
    SensorsConfig,
    SimConfig,
)
from armlab.errors import ConfigError
from armlab.protocols.fractional_elbow import hooks
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig
from armlab.protocols.fractional_elbow.experiment import estimate_fractional, simulate_fractional

CFG = FractionalElbowConfig(
    protocol_name="fractional_elbow",
    elbow=ElbowConfig(impedance="five_element"),
    reflex=ReflexConfig(enabled=False),
    # 0.1 ms steps: at 0.5 ms the explicit grasp damper biases d1 by ~12 % (measured)
    sim=SimConfig(timestep_s=0.0001),
    scenario=ScenarioConfig(name="fractional_elbow"),
    sensors=SensorsConfig(preset="realistic", fs_hz=2000.0),
)


@pytest.fixture(scope="module")
def five_element_run():
    rec = simulate_fractional(CFG)
    trials, truth = rec.trials, rec.truth
    return trials, truth, estimate_fractional(trials, CFG.frf, truth)[0]


def test_reestimate_rebuilds_the_truth_from_a_stored_config_of_any_vintage(five_element_run):
    # a run stores its composed config with the trials; runs made before the per-protocol configs
    # stored every group of every protocol (here an extra arm group): both re-estimate alike, and
    # exactly as the run itself did (same trials, same settings, same truth)
    trials, _, results = five_element_run
    stored = OmegaConf.create(OmegaConf.to_yaml(OmegaConf.structured(CFG)))  # as read from trials.h5
    old = OmegaConf.merge(stored, {"arm": {"muscle": "hill"}, "capstan": {"drag": True}})
    for cfg in (stored, old):
        again = hooks.reestimate(trials, cfg, [])
        assert again["five_element_rel_err"] == results["five_element_rel_err"]
        assert again["models"].keys() == results["models"].keys()


def test_third_order_model_recovers_the_five_elements(five_element_run):
    _, _, results = five_element_run
    err = results["five_element_rel_err"]
    # the 5 %; measured M 0.6, k1 0.3, k2 0.8, d1 3.3, d2 1.0 % (d1, the grasp damper,
    # shows mostly above the 9 Hz grasp mode and is the least determined)
    assert max(err.values()) < 0.05, err


def test_table_I_structures_are_fitted_with_the_papers_indices(five_element_run):
    _, _, results = five_element_run
    models = results["models"]
    assert set(models) == {"27", "28", "29", "A", "B"}
    assert models["27"]["alpha"] == 1.0 and models["27"]["r2"] > 0.98
    # the 4-parameter fractional (28) beats the 3-parameter (29) (measured R² 0.986 vs 0.858)
    assert models["28"]["r2"] > models["29"]["r2"]
    # integer 3rd order beats the 2-pole models, as in Table I
    assert models["27"]["mse"] < models["A"]["mse"]
    assert results["frf"]["n_freq"] == 134  # 0.12-15 Hz on the 2 kHz / 18000 grid


def test_bad_processing_settings_are_rejected(five_element_run):
    trials, truth, _ = five_element_run
    with pytest.raises(ConfigError, match="longer than the trial"):
        estimate_fractional(trials, FrfConfig(welch_window=100_000), truth)
    with pytest.raises(ConfigError, match="beyond Nyquist"):
        estimate_fractional(trials, FrfConfig(band_hz=(0.12, 1500.0)), truth)
    with pytest.raises(ConfigError, match="differs from the scenario"):
        simulate_fractional(replace(CFG, sensors=SensorsConfig(fs_hz=1000.0)))
    with pytest.raises(ConfigError, match="frf.alpha_step must divide 1"):
        FrfConfig(alpha_step=0.3)
    with pytest.raises(ConfigError, match=r"elbow.fractional_order must lie in \(0, 1\)"):
        ElbowConfig(fractional_order=1.5)
    assert np.all(np.asarray(trials.trial_meta["tracking_error"]) < 0.2)


@pytest.fixture(scope="module")
def fractional_run():
    cfg = replace(CFG, elbow=ElbowConfig(impedance="fractional", fractional_order=0.5))
    rec = simulate_fractional(cfg)
    trials, truth = rec.trials, rec.truth
    return truth, estimate_fractional(trials, cfg.frf, truth)[0]


def test_fractional_truth_gives_the_true_order(fractional_run):
    truth, results = fractional_run
    frac = results["fractional_five_element"]
    assert frac["true_order"] == truth.fractional_order == 0.5
    # the 0.1; measured: 0.5 exactly for seeds 0, 1, 2 (0.4 and 0.6 cost 1.2x and 1.03x)
    assert frac["order_error"] <= 0.1 + 1e-9, frac
    # springpot coefficient, arm and grasp at the chosen order (measured <= 6 %)
    assert max(frac["rel_err"].values()) < 0.1, frac["rel_err"]
    # the integer five-element model is a worse description of a fractional arm
    assert min(frac["cost"]) < 0.5 * frac["cost"][list(frac["orders"]).index(1.0)]  # measured 2.6x


@pytest.mark.slow
def test_fractional_truth_of_order_0_7_is_found():
    cfg = replace(CFG, elbow=ElbowConfig(impedance="fractional", fractional_order=0.7))
    rec = simulate_fractional(cfg)
    trials, truth = rec.trials, rec.truth
    frac = estimate_fractional(trials, cfg.frf, truth)[0]["fractional_five_element"]
    assert frac["order_error"] <= 0.1 + 1e-9, frac

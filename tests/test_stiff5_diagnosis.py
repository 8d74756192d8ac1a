"""The stiffness_5dof_emg diagnosis: clean data -> none, a strong reflex -> reflex, bad input refused,
the noise floor against a known noise (small datasets in module-scoped fixtures: CI-cheap)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig
from armlab.errors import DataError
from armlab.protocols.stiffness_5dof_emg.config import Stiffness5dofConfig, TrialsConfig
from armlab.protocols.stiffness_5dof_emg.diagnosis.data import prepare_stiff5
from armlab.protocols.stiffness_5dof_emg.diagnosis.diagnose import diagnose_stiff5
from armlab.protocols.stiffness_5dof_emg.experiment import build_lab, simulate_stiffness_stage


def _trials(preset: str, reflex: bool = False, seed: int = 3):
    cfg = Stiffness5dofConfig(
        stages=["stiffness"], trials=TrialsConfig(n_per_condition=20, conditions=["X+10", "Z-10"])
    )
    cfg.seed = seed
    cfg.sensors.preset = preset
    cfg.reflex.enabled = reflex
    return simulate_stiffness_stage(cfg, build_lab())


@pytest.fixture(scope="module")
def clean():
    return _trials("realistic")


def test_clean_lab_is_none(clean):
    results, _ = diagnose_stiff5(clean, DiagnosisConfig())
    assert results["verdict"] == ["none"], results["gap"]


def test_strong_reflex_is_named():
    results, _ = diagnose_stiff5(_trials("realistic", reflex=True), DiagnosisConfig())
    assert results["verdict"][0] == "reflex"
    # the lab's reflex law is the surrogate's (rectified stretch per muscle): it explains nearly all
    assert results["ranking"][0]["explained_fraction"] > 0.8


def test_floor_matches_a_known_white_noise():
    trials = _trials("ideal")
    sigma = (
        0.5  # N, white noise added to the base force: a 50 ms bin of 100 samples averages it to sigma / 10
    )
    rng = np.random.default_rng(0)
    ch = dict(trials.channels)
    ch["base_force"] = ch["base_force"] + sigma * rng.standard_normal(ch["base_force"].shape)
    cs = prepare_stiff5(replace(trials, channels=ch))
    expected = sigma / 10.0 * np.sqrt(1.25)  # the row's bin plus the pre-interval mean (4 bins)
    # 40 trials x 3 spreads of 4 bins per axis: the std estimate's standard error is
    # 1/sqrt(2 x 120) ~ 6.5 %; 20 % is three of them
    got = np.sqrt(cs.noise_var[10:13])
    np.testing.assert_allclose(got, expected, rtol=0.2)


def test_bad_input_is_refused(clean, tmp_path):
    from armlab.protocols.stiffness_5dof_emg.diagnosis.data import load_stiff5_trials

    with pytest.raises(DataError, match=r"\.h5"):
        load_stiff5_trials(tmp_path)  # a folder without its trial file
    cond = np.zeros(clean.n_trials, int)
    cond[-5:] = 1
    few = replace(clean, trial_meta={**clean.trial_meta, "condition": cond})
    with pytest.raises(DataError, match="at least 10 trials"):
        prepare_stiff5(few)

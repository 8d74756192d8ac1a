"""armlab.config.diagnosis: DiagnosisConfig and RefereeConfig validation and Hydra composition."""

from __future__ import annotations

import pytest
from hydra import compose, initialize
from omegaconf import OmegaConf

from armlab.config.diagnosis import (
    DiagnosisConfig,
    RefereeConfig,
    register_diagnosis_configs,
)
from armlab.config.store import apply_overrides
from armlab.errors import ConfigError


def test_defaults_are_valid():
    cfg = DiagnosisConfig()
    assert cfg.candidates is None and cfg.exclude == [] and not cfg.per_trial
    assert 0 < cfg.highpass_hz < cfg.band_hz < 0.45 * cfg.fs_fit_hz
    ref = RefereeConfig()
    assert ref.protocol is None and ref.n_trials >= 2  # None: the registry's default referee


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"fs_fit_hz": 0.0}, "diagnosis.fs_fit_hz and band_hz must be > 0"),
        ({"band_hz": -1.0}, "diagnosis.fs_fit_hz and band_hz must be > 0"),
        ({"highpass_hz": 50.0}, "diagnosis.highpass_hz must lie in (0, band_hz=40.0), got 50.0"),
        ({"highpass_hz": 0.0}, "diagnosis.highpass_hz must lie in (0, band_hz=40.0), got 0.0"),
        ({"holdout_fraction": 0.9}, "diagnosis.holdout_fraction must lie in [0.05, 0.5], got 0.9"),
        ({"holdout_fraction": 0.01}, "diagnosis.holdout_fraction must lie in [0.05, 0.5], got 0.01"),
        ({"max_effects": 4}, "diagnosis.max_effects must be 1, 2 or 3, got 4"),
        ({"max_effects": 0}, "diagnosis.max_effects must be 1, 2 or 3, got 0"),
        ({"min_duration_s": 0.0}, "diagnosis.min_duration_s must be > 0"),
        ({"min_step_fraction": -0.1}, "diagnosis.min_step_fraction must be >= 0"),
        ({"none_tolerance": -1.0}, "diagnosis.none_tolerance must be >= 0"),
    ],
)
def test_bad_diagnosis_settings_are_refused(kw, message):
    with pytest.raises(ConfigError) as err:
        DiagnosisConfig(**kw)
    assert message in str(err.value)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"replicates": 0}, "referee.replicates >= 1 and n_trials >= 2"),
        ({"n_trials": 1}, "referee.replicates >= 1 and n_trials >= 2"),
        ({"noise_std_Nm": 0.0}, "referee.noise_std_Nm must be > 0"),
        ({"cond_windows": [0, 26]}, "referee.cond_windows must be window indices in 1..26, got [0, 26]"),
        ({"cond_windows": []}, "referee.cond_windows must be window indices in 1..26"),
    ],
)
def test_bad_referee_settings_are_refused(kw, message):
    with pytest.raises(ConfigError) as err:
        RefereeConfig(**kw)
    assert message in str(err.value)


def test_hydra_composes_the_registered_schemas():
    register_diagnosis_configs()
    register_diagnosis_configs()  # idempotent
    with initialize(version_base="1.3", config_path=None):
        cfg = compose(config_name="diagnosis_config", overrides=["band_hz=30", "exclude=[reflex]"])
        diag = OmegaConf.to_object(cfg)
        assert isinstance(diag, DiagnosisConfig)
        assert diag.band_hz == 30.0 and diag.exclude == ["reflex"]
        ref = OmegaConf.to_object(compose(config_name="referee_config", overrides=["replicates=2"]))
        assert isinstance(ref, RefereeConfig) and ref.replicates == 2
        with pytest.raises(
            ConfigError, match=r"diagnosis.holdout_fraction must lie in \[0.05, 0.5\], got 0.9"
        ):
            OmegaConf.to_object(compose(config_name="diagnosis_config", overrides=["holdout_fraction=0.9"]))


def test_cli_style_overrides():
    cfg = apply_overrides(
        DiagnosisConfig(), "diagnosis", ["diagnosis.exclude=[reflex]", "diagnosis.per_trial=true"]
    )
    assert cfg.exclude == ["reflex"] and cfg.per_trial is True
    with pytest.raises(ConfigError, match="unknown diagnosis field 'nope'; valid: "):
        apply_overrides(DiagnosisConfig(), "diagnosis", ["diagnosis.nope=1"])

"""The subject's activation fluctuation in the fractional_elbow lab (armlab.sim.subject, seeds/000 values).

The effect is switchable (``subject.enabled``, off by default), seeded by a third child of each
trial's generator (a steady subject draws exactly the data it always did), and CHECKED on Table I
with the values calibrated on the conditioning paper (docs/reproduction/fractional_elbow.md).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.config.schema import DirectDriveConfig, ElbowConfig, ReflexConfig, SimConfig
from armlab.errors import ConfigError
from armlab.models.direct_drive_scene import build_direct_drive_scene
from armlab.protocols.compose import check_effects, compose
from armlab.protocols.conditioning_window.config import SUBJECT as COND_SUBJECT
from armlab.protocols.fractional_elbow import PROTOCOL
from armlab.protocols.fractional_elbow.config import SUBJECT
from armlab.protocols.fractional_elbow.experiment import estimate_fractional, simulate_fractional
from armlab.reproduction.fractional import added_effect_variants, table_I_checks
from armlab.sensors.channel import ChannelSpec
from armlab.sim.force_control import simulate_force_trial


def test_values_are_the_conditioning_labs_and_the_effect_is_off_by_default():
    # the same physical effect, values calibrated on seeds/000 and not re-tuned here
    assert {k: v for k, v in SUBJECT.items() if k != "enabled"} == {
        k: v for k, v in COND_SUBJECT.items() if k != "enabled"
    }
    cfg = compose(["protocol=fractional_elbow"])[1]
    assert not cfg.subject.enabled and cfg.subject.fluctuation_cv == pytest.approx(0.035)
    assert compose(["protocol=fractional_elbow", "subject.enabled=true"])[1].subject.active


def test_named_in_the_lab_and_refused_through_the_catalogue():
    assert PROTOCOL.lab_effects["cocontraction_variation"] == "subject.enabled"
    assert "cocontraction_variation" in PROTOCOL.catalogue
    exp = compose(["protocol=fractional_elbow", "effects=[cocontraction_variation]"])[1]
    with pytest.raises(ConfigError, match="subject.enabled"):  # one switch per physical effect
        check_effects(PROTOCOL, exp)
    names = [v.name for v in added_effect_variants()]
    assert "subject_fluctuation" in names and "subject_fluctuation" not in [
        v.name for v in added_effect_variants(quick=True)
    ]


def test_a_muscle_command_of_the_wrong_shape_is_refused():
    elbow = ElbowConfig()
    scene = build_direct_drive_scene(elbow, SimConfig(timestep_s=1e-4))
    with pytest.raises(ConfigError, match="muscle_base has shape"):
        simulate_force_trial(
            scene,
            np.zeros(100),
            2000.0,
            0.01,
            elbow,
            ReflexConfig(enabled=False),
            DirectDriveConfig(),
            ChannelSpec(),
            ChannelSpec(),
            np.random.default_rng(0),
            muscle_base=np.full((50, 2), 0.5),
        )


@pytest.fixture(scope="module")
def runs():
    """Reflex off, so that the activation moves only with the subject (two 40 s trials each)."""
    base = compose(["protocol=fractional_elbow", "reflex.enabled=false"])[1]
    on = replace(base, subject=replace(base.subject, enabled=True))
    return simulate_fractional(base).trials, simulate_fractional(on).trials, on


def test_the_fluctuation_reaches_the_muscles_at_its_configured_size(runs):
    steady, moving, cfg = runs
    a0, a1 = steady.channels["true_activation"], moving.channels["true_activation"]
    # a steady subject holds its co-contraction exactly
    assert np.ptp(a0) < 1e-9 and a0[0, 0, 0] == pytest.approx(cfg.elbow.cocontraction)
    # within a trial: 3.5 % rms of the trial's level per muscle (the activation dynamics pass the
    # 2 Hz noise nearly unchanged; 40 s hold ~160 independent samples: +-0.6 % read)
    rel = a1.std(axis=1) / a1.mean(axis=1)
    assert np.all(np.abs(rel - cfg.subject.fluctuation_cv) < 0.01), rel
    # the trial's level: co-contraction x (1 + 10 % eta), common to both muscles
    level = a1.mean(axis=1) / cfg.elbow.cocontraction - 1.0
    assert np.all(np.abs(level[:, 0] - level[:, 1]) < 0.02) and np.all(np.abs(level) < 0.4), level


def test_the_subject_has_its_own_stream(runs):
    steady, moving, cfg = runs
    # the force reference comes from the trial's first child: identical with or without the subject
    np.testing.assert_array_equal(steady.channels["f_ref"], moving.channels["f_ref"])
    assert not np.array_equal(steady.channels["phi_true"], moving.channels["phi_true"])
    again = simulate_fractional(cfg).trials  # same config and seed: bit-identical
    np.testing.assert_array_equal(again.channels["true_activation"], moving.channels["true_activation"])
    np.testing.assert_array_equal(again.channels["theta_measured"], moving.channels["theta_measured"])


@pytest.fixture(scope="module")
def subject_table_I():
    cfg = compose(["protocol=fractional_elbow", "subject.enabled=true"])[1]
    rec = simulate_fractional(cfg)
    res = estimate_fractional(rec.trials, cfg.frf, rec.truth)[0]
    return res, table_I_checks(res["models"])


def test_table_I_check_with_the_default_lab_plus_the_subject(subject_table_I):
    """The check of docs/reproduction/fractional_elbow.md (default lab + subject, seed 0): the
    residuals reach the paper's size (R² 0.83-0.86, paper 0.80-0.94; steady subject 0.94-0.99),
    alpha (29) falls in 1.1 +- 0.2, and the low-frequency angle noise lifts the measured DC gain out
    of Fig. 4's band (why the subject stays off in this lab)."""
    res, checks = subject_table_I
    assert 0.80 <= min(checks["r2"]) and max(checks["r2"]) <= 0.94, checks
    assert checks["alpha_29_ok"], checks
    assert res["fig4_features"]["measured"]["dc_db"] > -46.0  # paper -49.1...-46.0 (steady: -49.2)


@pytest.mark.xfail(
    strict=True,
    reason="with the subject, (28) still fits best and alpha (28) is 1.2 (paper 1.4 +- 0.1): "
    "docs/reproduction/fractional_elbow.md",
)
def test_the_subject_brings_table_I_ranking_and_alpha_28(subject_table_I):
    _, checks = subject_table_I
    assert checks["alpha_28_ok"] and checks["ranking_as_paper"], checks

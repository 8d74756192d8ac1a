"""armlab.protocols.joint_1dof.diagnosis.diagnose: candidate lists and the results of ``diagnose_joint``
(pooled and
per trial) on synthetic joint trials with a known effect (see conftest.py).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import (
    JOINT_B,
    JOINT_I,
    JOINT_K,
    joint_trials,
    nominal_torque,
    prbs_position,
    reflex_joint_torque,
)

from armlab.config.diagnosis import DiagnosisConfig
from armlab.errors import ConfigError
from armlab.protocols._files import json_default
from armlab.protocols.joint_1dof.diagnosis.diagnose import candidate_names, diagnose_joint
from armlab.protocols.joint_1dof.diagnosis.models import JOINT_SURROGATES
from armlab.protocols.joint_1dof.diagnosis.rules import RULES

_CANDIDATES = ["reflex", "joint_friction", "channel_delay"]

_NONE_TOL = DiagnosisConfig().with_rules(RULES).none_tolerance  # 1, of the floor


def _records(torque_fn, *, seed=0, duration=12.0):
    rng = np.random.default_rng(seed)
    return joint_trials(prbs_position(rng, duration), torque_fn, rng, noise_std=0.15)


def _json(results) -> dict:
    return json.loads(json.dumps(results, default=json_default))


def test_candidate_names():
    assert candidate_names(DiagnosisConfig()) == list(JOINT_SURROGATES)
    assert candidate_names(DiagnosisConfig(exclude=["reflex"])) == [
        n for n in JOINT_SURROGATES if n != "reflex"
    ]
    cfg = DiagnosisConfig(candidates=["channel_delay", "reflex"], exclude=["reflex"])
    assert candidate_names(cfg) == ["channel_delay"]


@pytest.mark.parametrize(
    ("cfg", "message"),
    [
        (
            DiagnosisConfig(candidates=["reflex", "nope"]),
            "unknown candidate effect 'nope' for joint_1dof; valid: ['reflex',",
        ),
        (DiagnosisConfig(exclude=["cable_drag"]), "unknown candidate effect 'cable_drag' for joint_1dof"),
        (
            DiagnosisConfig(candidates=["reflex"], exclude=["reflex"]),
            "no candidate effects left after exclude=['reflex']; valid: ['reflex',",
        ),
    ],
)
def test_bad_candidate_lists_are_refused(cfg, message):
    with pytest.raises(ConfigError) as err:
        candidate_names(cfg)
    assert message in str(err.value)


@pytest.fixture(scope="module")
def reflex_results():
    return diagnose_joint(_records(reflex_joint_torque), DiagnosisConfig(candidates=_CANDIDATES))


def test_effect_well_above_noise_is_named(reflex_results):
    results, series = reflex_results
    assert results["verdict"] == ["reflex"]
    assert results["protocol"] == "joint_1dof" and results["trials"] == ["rep0", "rep1"]
    assert {e["name"] for e in results["ranking"]} == set(_CANDIDATES)  # every candidate ranked
    for e in results["ranking"]:
        assert {"held_out_gap", "gap_reduction", "delta_bic", "explained_fraction", "params"} <= set(e)
        assert "model" not in e
    assert results["ranking"][0]["name"] == "reflex"
    gap = results["gap"]
    assert gap["noise_source"] == "repeats"
    assert [a["effects"] for a in gap["added"]] == [["reflex"]]
    # the reflex model brings the held-out gap down to the noise floor (within the protocol's
    # none_tolerance, what the diagnosis itself counts as noise), from well above it
    assert gap["nominal"] > 10 * gap["noise_floor"]
    assert gap["added"][0]["held_out_gap"] == pytest.approx(gap["noise_floor"], rel=_NONE_TOL)
    assert series["all"]["stages"][-1].effects == ("reflex",)


def test_results_report_positive_impedance_and_where_the_gap_is(reflex_results):
    results, _ = reflex_results
    assert results["torque_sign"].startswith("antiphase")
    final = results["how_far"][-1]
    assert final["effects"] == ["reflex"]
    for p in final["parameters"]:  # the torque sign folded in: positive I, B, K
        assert p["I"] == pytest.approx(JOINT_I, rel=0.05)
        assert p["B"] == pytest.approx(JOINT_B, rel=0.05)
        assert p["K"] == pytest.approx(JOINT_K, rel=0.02)
    assert final["nonlinear_parameters"]["reflex.delay_s"] == pytest.approx(0.04, abs=0.005)
    where = results["where"]
    assert len(where["bands"]) == 4 and len(where["windows"]) == 5
    assert [t["trial"] for t in where["per_trial"]] == ["rep0", "rep1"]
    # the nominal residual follows the velocity with the reflex latency (plus its low-pass lag)
    assert where["residual_tests"]["peak_cross_lag_s"] > 0.04
    assert set(where["parameter_bias"][0]) == {"I", "B", "K", "measured", "simulated"}


def test_results_are_json_serialisable(reflex_results):
    results, _ = reflex_results
    back = _json(results)
    assert back["verdict"] == ["reflex"]
    assert back["settings"]["candidates"] == _CANDIDATES
    assert back["settings"]["fs_fit_hz"] == 250.0
    assert back["gap"]["nominal"] == pytest.approx(results["gap"]["nominal"])


def test_noise_alone_gives_none():
    results, _ = diagnose_joint(_records(nominal_torque, seed=1), DiagnosisConfig(candidates=_CANDIDATES))
    assert results["verdict"] == ["none"]
    assert results["gap"]["added"] == []
    assert results["gap"]["nominal"] == pytest.approx(results["gap"]["noise_floor"], rel=_NONE_TOL)
    assert len(results["how_far"]) == 1
    _json(results)


def test_effect_excluded_from_the_candidates_gives_unknown():
    cfg = DiagnosisConfig(candidates=_CANDIDATES, exclude=["reflex"])
    results, _ = diagnose_joint(_records(reflex_joint_torque), cfg)
    assert results["verdict"] == ["unknown"]
    assert {e["name"] for e in results["ranking"]} == {"joint_friction", "channel_delay"}
    assert results["settings"]["exclude"] == ["reflex"]
    _json(results)


def test_per_trial_mode_diagnoses_every_trial_on_its_own():
    records = _records(reflex_joint_torque, seed=2)
    results, series = diagnose_joint(
        records, DiagnosisConfig(candidates=["reflex", "channel_delay"], per_trial=True)
    )
    assert results["verdict"] == {"rep0": ["reflex"], "rep1": ["reflex"]}
    assert set(results["ranking"]) == set(results["gap"]) == {"rep0", "rep1"} == set(series)
    assert [p["trial"] for p in results["per_trial"]] == ["rep0", "rep1"]
    for p in results["per_trial"]:
        assert p["trials"] == [p["trial"]]
        # one trial has no repeat: the floor comes from the second differences of its torque
        assert p["gap"]["noise_source"].startswith("second differences")
    assert results["settings"]["per_trial"] is True
    _json(results)

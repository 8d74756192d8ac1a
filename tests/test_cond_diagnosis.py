"""Conditioning-window diagnosis: data preparation, candidate models, diagnosis, referee, files.

Datasets come from the simulated laboratory (30 trials of the k = 26 window, linear muscles,
ideal encoders, white F/T force noise), so the truth of every hidden effect is known.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.config.effects import EFFECTS
from armlab.config.schema import CuffConfig
from armlab.config.subject import SubjectConfig
from armlab.diagnosis.families import fit_model
from armlab.diagnosis.scoring import expected_verdict
from armlab.errors import ConfigError, DataError
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.diagnosis.data import prepare_cond
from armlab.protocols.conditioning_window.diagnosis.diagnose import cond_candidates, diagnose_cond
from armlab.protocols.conditioning_window.diagnosis.models import COND_FAMILY, COND_SURROGATES, cond_columns
from armlab.protocols.conditioning_window.diagnosis.referee import COND_CLASSES, make_cond_dataset
from armlab.protocols.conditioning_window.experiment import simulate_protocol

NOISE_N = 0.3  # N, white F/T force noise of the referee (RefereeConfig.force_noise_N)


def _cfg(**effects) -> ConditioningWindowConfig:
    base = ConditioningWindowConfig(protocol_name="conditioning_window")
    fx = replace(base.effects, force_sensor_noise=EFFECTS["force_sensor_noise"](std=NOISE_N), **effects)
    return replace(
        base,
        arm=replace(base.arm, muscle="linear"),
        cuff=CuffConfig(rigid=True),  # CuffConfig's own damping for the compliant-cuff dataset
        reflex=replace(base.reflex, enabled=False),
        sensors=replace(base.sensors, preset="ideal"),
        scenario=replace(base.scenario, k_values=[26]),
        effects=fx,
        subject=SubjectConfig(),  # a steady subject: the hidden effects are the only departures
    )


@pytest.fixture(scope="module")
def nominal_trials():
    return simulate_protocol(_cfg())[0].trials


@pytest.fixture(scope="module")
def cuff_trials():
    cfg = _cfg()
    cfg = replace(cfg, cuff=replace(cfg.cuff, rigid=False, stiffness_N_per_m=6000.0))
    return simulate_protocol(cfg)[0].trials


@pytest.fixture(scope="module")
def cuff_diagnosis(tmp_path_factory, cuff_trials):
    """The cuff dataset diagnosed once, end to end as `armlab diagnose` does (its trial file written,
    read back through the protocol's hooks, diagnosed, report and figures written): (folder of
    trials.h5, output folder, results, series). The series are the diagnoser's own return value,
    seen on its way (a spy: the diagnosis itself runs unchanged)."""
    from armlab.data.h5io import write_trials
    from armlab.runner import diagnose as runner

    tmp = tmp_path_factory.mktemp("cond_diag")
    write_trials(tmp / "trials.h5", cuff_trials)
    seen = []

    def spy(*args, **kwargs):
        seen.append(real(*args, **kwargs))
        return seen[-1]

    real = runner.run_diagnoser
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(runner, "run_diagnoser", spy)
        out, res = runner.run_diagnosis(tmp / "trials.h5", "conditioning_window", [], tmp / "out")
    ((results, series),) = seen
    assert results is res
    return tmp, out, res, series


def test_nominal_model_recovers_the_exact_truth_without_noise():
    cfg = _cfg()
    cfg = replace(cfg, effects=replace(cfg.effects, force_sensor_noise=None))
    trials = simulate_protocol(cfg)[0].trials
    cs = prepare_cond(trials, band_hz=40.0, holdout_fraction=1 / 3)
    fm = fit_model((cs,), [cs.y], (), None, family=COND_FAMILY)
    truth = trials.attrs["ground_truth"]
    k = fm.beta[0][7:11].reshape(2, 2)
    np.testing.assert_allclose(k, truth["K"], rtol=0.01)
    np.testing.assert_allclose(fm.beta[0][:3], truth["xi"], rtol=0.02)


def test_noise_floor_matches_the_injected_noise(nominal_trials):
    from armlab.models.planar_arm import jacobian

    cs = prepare_cond(nominal_trials, band_hz=40.0, holdout_fraction=1 / 3)
    # white force noise NOISE_N per axis through each scoring row's own J^T, band-limited to 40
    # of the 500 Hz Nyquist band, plus the trial's baseline-mean error (~1/16 of it: 200 ms of
    # 40 Hz noise); rtol: the fixture's 30 trials × ~250 pre-onset samples of 40 Hz noise (~600
    # independent values) estimate a variance to ~6 % sd, so 15 % is about 2.5 sd
    gain = np.sum(jacobian(cs.q, cs.l1, cs.l2) ** 2, axis=-2)  # (m, n, 2): |column i of J|²
    expected = NOISE_N**2 * cs.rows(gain) * 40.0 / 500.0
    for j in (0, 1):
        rows = cs.row_channel == j
        np.testing.assert_allclose(cs.row_noise_var[rows].mean(), 1.06 * expected[rows].mean(), rtol=0.15)
    # one held-out trial in each (group, direction) cell of 5 repeats
    assert cs.held_trials.sum() == 6 and cs.train.sum() + cs.held.sum() == cs.y.size


def test_diagnosis_of_the_nominal_lab_is_none(nominal_trials):
    res, _ = diagnose_cond(nominal_trials, DiagnosisConfig())
    assert res["verdict"] == ["none"]
    g = res["gap"]
    assert g["nominal"] <= 1.25 * g["noise_floor"]
    assert {e["name"] for e in res["ranking"]} == set(COND_SURROGATES)
    absorbed = {tuple(p["effects"]) for p in res["indistinct"]}
    assert ("payload_mass", "arm inertia") in absorbed and ("plane_tilt", "arm stiffness") in absorbed


def test_cuff_compliance_is_found_with_its_stiffness(cuff_diagnosis):
    _, _, res, series = cuff_diagnosis  # diagnose_cond with the default DiagnosisConfig()
    assert res["verdict"][0] == "cuff_compliance"
    c = res["how_far"][1]["nonlinear_parameters"]["cuff_compliance.compliance_m_per_N"]
    assert 1 / c == pytest.approx(6000.0, rel=0.3)  # N/m, the simulated cuff
    g = res["gap"]
    assert g["added"][0]["held_out_gap"] < g["nominal"] - 0.7 * (g["nominal"] - g["noise_floor"])
    assert series["all"]["corrected"].shape == series["all"]["measured"].shape
    windows = res["where"]["windows"]
    assert [w["window_ms"] for w in windows][0] == [0, 20]


def test_compliance_basis_from_measured_force_does_not_explain_noise(nominal_trials):
    cs = prepare_cond(nominal_trials, band_hz=40.0, holdout_fraction=1 / 3)
    fm0 = fit_model((cs,), [cs.y], (), None, family=COND_FAMILY)
    fm1 = fit_model((cs,), [cs.y], (COND_SURROGATES["cuff_compliance"],), None, family=COND_FAMILY)
    held = cs.held
    r0 = np.sum(fm0.residuals[0][held] ** 2)
    r1 = np.sum(fm1.residuals[0][held] ** 2)
    assert r1 > 0.9 * r0  # no cuff: the surrogate gains (almost) nothing on held-out trials


def test_columns_of_output_effects_keep_the_nominal_shape(nominal_trials):
    cs = prepare_cond(nominal_trials, band_hz=40.0, holdout_fraction=1 / 3)
    base = cond_columns(cs, (), {})
    shifted = cond_columns(cs, (COND_SURROGATES["channel_delay"],), {"channel_delay.delay_s": 0.0})
    np.testing.assert_allclose(shifted, base, atol=1e-9 * np.abs(base).max())
    assert base.shape == (cs.y.size, 11)


def test_candidate_errors_name_the_valid_choices():
    with pytest.raises(ConfigError, match="valid"):
        cond_candidates(DiagnosisConfig(candidates=["transmission_compliance"]))
    with pytest.raises(ConfigError, match="no candidate"):
        cond_candidates(DiagnosisConfig(candidates=["reflex"], exclude=["reflex"]))


def test_short_trials_are_refused(nominal_trials):
    short = nominal_trials.select(np.ones(nominal_trials.n_trials, bool))
    with pytest.raises(DataError, match="0.4 s"):
        prepare_cond(
            type(short)(
                fs_hz=short.fs_hz,
                onset_index=short.onset_index,
                channels={k: v[:, :500] for k, v in short.channels.items()},
                units=short.units,
                trial_meta=short.trial_meta,
                attrs=short.attrs,
            ),
            band_hz=40.0,
            holdout_fraction=1 / 3,
        )


def test_lab_force_effects_delay_and_filter_the_force():
    from armlab.sim.lab import _force_effects

    z = np.zeros((1, 50, 1))
    z[0, 10:] = 1.0
    fx = replace(ConditioningWindowConfig().effects, channel_delay=EFFECTS["channel_delay"](delay_s=0.003))
    out = _force_effects(z, fx, 1000.0)
    assert out[0, 12, 0] == 0.0 and out[0, 13, 0] == 1.0
    fx = replace(
        ConditioningWindowConfig().effects,
        force_sensor_bandwidth=EFFECTS["force_sensor_bandwidth"](cutoff_hz=20.0),
    )
    out = _force_effects(z, fx, 1000.0)
    assert 0 < out[0, 12, 0] < 0.5 and out[0, -1, 0] == pytest.approx(
        1.0, abs=0.05
    )  # Butterworth overshoot 4 %


def test_referee_dataset_hides_the_truth(tmp_path):
    ref = RefereeConfig(protocol="conditioning_window", seed=0, cond_trials=12)
    ds = make_cond_dataset("cuff_compliance", 0, ref, DiagnosisConfig(), tmp_path / "d")
    from armlab.data.h5io import read_trials

    trials = read_trials(tmp_path / "d" / "trials.h5")
    assert set(trials.channels) == {"hand_pos", "hand_force"}
    assert "ground_truth" not in trials.attrs
    assert ds.enr > 0 and ds.truth["effect_rms_Nm"] >= ds.truth["unabsorbed_effect_rms_Nm"]
    assert expected_verdict("left_out:reflex", COND_CLASSES) == {"unknown"}
    assert expected_verdict("none", COND_CLASSES) == {"none"}
    with pytest.raises(FileExistsError, match="new folder"):  # refused before simulating
        make_cond_dataset("cuff_compliance", 0, ref, DiagnosisConfig(), tmp_path / "d")
    assert len(COND_CLASSES) >= 9


def test_cli_diagnose_writes_report_and_never_overwrites(cuff_diagnosis):
    from armlab.runner.diagnose import run_diagnosis

    data, out, res, _ = cuff_diagnosis
    report = (out / "report.md").read_text()
    assert "cuff" in report and "Where the gap lies" in report
    assert json.loads((out / "results.json").read_text())["verdict"] == res["verdict"]
    assert (out / "diagnosis.rrd").stat().st_size > 0
    with pytest.raises(DataError, match="never overwrites"):
        run_diagnosis(data / "trials.h5", "conditioning_window", [], out)

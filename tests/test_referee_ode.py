"""The second, ODE-generated referee of the joint_1dof diagnosis (referee.generator=ode)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.joint_import import load_joint_data
from armlab.diagnosis.scoring import expected_verdict
from armlab.errors import ConfigError
from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES
from armlab.protocols.joint_1dof.diagnosis.referee_ode import ODE_CLASSES, make_ode_dataset
from armlab.runner.diagnose import run_benchmark, run_diagnoser


def test_a_dataset_is_written_read_back_and_diagnosed_end_to_end(tmp_path):
    # CI size: one perturbation recorded twice, 8.5 s (the diagnosis keeps 2 s edges and needs half
    # the record inside them), evaluation seed
    ref = RefereeConfig(n_trials=2, ode_trial_s=[8.5, 8.5], seed=1000)
    diag = DiagnosisConfig(min_duration_s=8.0)
    ds = make_ode_dataset("none", 0, ref, diag, tmp_path / "trials")
    assert sorted(p.name for p in ds.folder.iterdir()) == ["seq0_rep0.csv", "seq0_rep1.csv"]
    trials = load_joint_data(ds.folder, min_duration_s=diag.min_duration_s)
    assert trials[0].fs_hz == pytest.approx(ds.truth["fs_hz"], rel=1e-9)
    assert 500 <= ds.truth["fs_hz"] <= 2000 and ds.truth["generator"] == "ode" and ds.enr == 0.0
    np.testing.assert_array_equal(trials[0].position, trials[1].position)  # a repeat: same motion,
    assert not np.array_equal(trials[0].torque, trials[1].torque)  # other noise
    results, _ = run_diagnoser(ds.folder, "joint_1dof", diag)
    assert results["torque_sign"] == "in phase"  # this generator's sign (the first referee's: antiphase)
    # the nominal fitted on clean data finds the generator's joint: I, B, K of the truth within 5 %
    # (the noise drawn here is <= 1e-1 of the torque rms; the fit's spread on 8.5 s is ~1 %)
    truth = ds.truth["subject"]
    for fitted in results["how_far"][0]["parameters"]:
        for name in ("I", "B", "K"):
            assert fitted[name] == pytest.approx(truth[name], rel=0.05), name


def test_classes_extend_the_first_referees_with_the_catalogue_effects_it_lacks():
    assert set(JOINT_CLASSES) <= set(ODE_CLASSES)
    for name in ("encoder_quantisation", "force_sensor_drift", "voluntary_torque"):
        assert expected_verdict(name, ODE_CLASSES) == {name}
    assert expected_verdict("left_out:reflex", ODE_CLASSES) == {"unknown"}


def test_an_unknown_generator_is_refused_naming_the_valid_ones(tmp_path):
    with pytest.raises(ConfigError, match=r"valid: \['default', 'ode'\]"):
        run_benchmark(["referee.protocol=joint_1dof", "referee.generator=mujoco"], tmp_path / "b")
    with pytest.raises(ConfigError, match=r"valid: \['default'\]"):
        run_benchmark(["referee.protocol=conditioning_window", "referee.generator=ode"], tmp_path / "c")
    # the ODE referee reads its own trial lengths; the first referee refuses them, never ignores them
    with pytest.raises(ConfigError, match="not read by the joint_1dof referee"):
        run_benchmark(["referee.protocol=joint_1dof", "referee.ode_trial_s=[20,30]"], tmp_path / "d")
    assert not any(tmp_path.iterdir())


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured on the tuning seed 7 (docs/joint_1dof_referees.md): encoder_quantisation is named "
    "on multisines only (on a PRBS or steps the grid's error in the band is a floor no model of the "
    "angle removes, 2 of 7 at ENR >= 1), force_sensor_drift has no candidate yet (issue 18 item 3) "
    "and the rules were tuned on the MuJoCo referee only",
)
def test_full_ode_benchmark_meets_the_issue_targets(tmp_path):
    # issue 18: 10 replicates per class on the evaluation seed: top-1 >= 90 % where ENR >= 1, false
    # alarms on none <= 5 %, median shrink >= 70 % (~40 min on 2 cores)
    _, summary = run_benchmark(
        ["referee.protocol=joint_1dof", "referee.generator=ode", "referee.replicates=10"], tmp_path / "b"
    )
    assert summary["n_classes"] == len(ODE_CLASSES)
    for key, target in summary["targets"].items():
        assert target["met"], f"ode referee: {key} = {target['value']} against the target {target['target']}"

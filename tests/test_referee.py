"""The referee of the diagnosis: pseudo-real datasets and a small blind benchmark (CI size)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.joint_import import load_joint_data
from armlab.diagnosis.scoring import expected_verdict
from armlab.errors import DataError
from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES, make_dataset
from armlab.runner.diagnose import run_benchmark


def test_dataset_is_deterministic_and_holds_no_truth_in_its_trial_folder(tmp_path):
    ref = RefereeConfig(trial_s=12.0)
    a = make_dataset("reflex", 0, ref, DiagnosisConfig(), tmp_path / "a")
    b = make_dataset("reflex", 0, ref, DiagnosisConfig(), tmp_path / "b")
    assert sorted(p.name for p in a.folder.iterdir()) == [f"seq{i % 2}_rep{i // 2}.csv" for i in (0, 2, 1, 3)]
    ta, tb = load_joint_data(a.folder), load_joint_data(b.folder)
    for x, y in zip(ta, tb, strict=True):
        np.testing.assert_array_equal(x.torque, y.torque)
    # repeats share the perturbation, not the noise
    np.testing.assert_array_equal(ta[0].position, ta[1].position)
    assert not np.array_equal(ta[0].torque, ta[1].torque)
    assert a.enr > 0 and a.truth["hidden"] == ["reflex"]
    with pytest.raises(FileExistsError):
        make_dataset("reflex", 0, ref, DiagnosisConfig(), tmp_path / "a")


def test_classes_cover_none_singles_a_pair_and_a_left_out_effect():
    assert len(JOINT_CLASSES) >= 9
    assert expected_verdict("none", JOINT_CLASSES) == {"none"}
    assert expected_verdict("left_out:reflex", JOINT_CLASSES) == {"unknown"}
    assert expected_verdict("reflex+joint_friction", JOINT_CLASSES) == {"reflex", "joint_friction"}


@pytest.mark.parametrize(
    ("protocol_items", "classes"),
    [
        (["referee.trial_s=12"], ["none", "reflex", "force_sensor_bandwidth", "left_out:reflex"]),
        # slow (make test-all): ~14 s of CI's 5-minute budget; CI keeps the conditioning plug-in's
        # own diagnosis tests (tests/test_cond_diagnosis.py) and this benchmark's joint_1dof case
        pytest.param(
            ["referee.protocol=conditioning_window", "referee.cond_trials=18"],
            ["none", "cuff_compliance", "joint_friction", "left_out:reflex"],
            marks=pytest.mark.slow,
        ),
    ],
)
def test_small_blind_benchmark(tmp_path, protocol_items, classes):
    # CI size: four classes, one replicate each, evaluation seeds, for each protocol; the full
    # 10 x 10 run is `armlab diagnose-benchmark` (make test-all: test_full_benchmark_...).
    # Shorter datasets than the defaults, about half the diagnosis time: 12 s joint trials (4/4
    # correct on the evaluation seeds 1000 and 1001, as with 20 s) and 18 conditioning trials, 3
    # per direction (4/4 on seed 1000 and 3/4 on seed 1001, as with the protocol's 30)
    overrides = ["referee.replicates=1", f"referee.classes=[{','.join(classes)}]", *protocol_items]
    out, summary = run_benchmark(overrides, tmp_path / "bench")
    assert summary["n_cases"] == 4
    assert summary["false_alarm_none"] == 0.0
    assert summary["top1"] >= 0.75
    cases = json.loads((out / "benchmark.json").read_text())["cases"]
    assert {c["class"] for c in cases} == set(classes)
    with pytest.raises(DataError, match="never overwrites"):
        run_benchmark(overrides, out)


@pytest.mark.slow
@pytest.mark.parametrize("protocol", ["joint_1dof", "conditioning_window"])
def test_full_benchmark_meets_the_issue_targets(tmp_path, protocol):
    # issue 5: >= 9 classes x 10 replicates on the evaluation seed; top-1 >= 90 % where ENR >= 1,
    # false alarms <= 5 %, median held-out shrink >= 70 % on correct cases (joint ~12 min,
    # conditioning window ~7 min on 2 cores)
    _, summary = run_benchmark([f"referee.protocol={protocol}", "referee.replicates=10"], tmp_path / "b")
    assert summary["n_classes"] >= 9 and summary["n_cases"] >= 90
    for key, target in summary["targets"].items():
        assert target["met"], f"{protocol}: {key} = {target['value']} against the target {target['target']}"

"""armlab.diagnosis.benchmark_summary (and the scoring half of
armlab.protocols.joint_1dof.diagnosis.referee) on
hand-made cases: confusion counts, rates, targets, the Markdown table.

``referee.make_dataset`` needs the joint simulator and is not tested here.
"""

from __future__ import annotations

import math

import pytest

from armlab.config.diagnosis import RefereeConfig
from armlab.diagnosis import scoring
from armlab.diagnosis.benchmark_summary import TARGETS, format_benchmark, summarise
from armlab.diagnosis.scoring import expected_verdict
from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES, describe


def score_case(cls, results):
    """Score against the joint referee's classes."""
    return scoring.score_case(cls, results, expected_verdict(cls, JOINT_CLASSES))


def _case(cls, predicted, *, enr=2.0, shrink=0.8, verdict=None):
    verdict = verdict or [predicted]
    expected = expected_verdict(cls, JOINT_CLASSES)
    return {
        "class": cls,
        "predicted": predicted,
        "verdict": verdict,
        "enr": enr,
        "top1": predicted in expected,
        "top2": predicted in expected,
        "exact": set(verdict) == expected,
        "shrink_of_excess": shrink,
    }


def _cases():
    return [
        _case("none", "none", enr=0.0, shrink=math.nan),
        _case("none", "none", enr=0.0, shrink=math.nan),
        _case("none", "reflex", enr=0.0, shrink=0.1),  # a false alarm
        _case("reflex", "reflex", enr=3.0, shrink=0.9),
        _case("reflex", "reflex", enr=0.7, shrink=0.6),
        _case("reflex", "unknown", enr=1.5, shrink=0.0),  # missed although strong
        _case("joint_friction", "joint_friction", enr=5.0, shrink=0.8),
        _case("joint_friction", "none", enr=0.3, shrink=0.0),  # missed, weak
        _case("left_out:reflex", "unknown", enr=2.0, shrink=0.0),  # correct, nothing added
        _case("reflex+joint_friction", "reflex", enr=4.0, shrink=0.95, verdict=["reflex", "joint_friction"]),
    ]


def test_confusion_counts_rows_by_class_and_columns_by_first_verdict():
    s = summarise(_cases())
    assert s["n_cases"] == 10 and s["n_classes"] == 5
    assert list(s["confusion"]) == [
        "none",
        "reflex",
        "joint_friction",
        "left_out:reflex",
        "reflex+joint_friction",
    ]
    assert list(s["confusion"]["none"]) == ["joint_friction", "none", "reflex", "unknown"]
    assert s["confusion"]["none"] == {"joint_friction": 0, "none": 2, "reflex": 1, "unknown": 0}
    assert s["confusion"]["reflex"] == {"joint_friction": 0, "none": 0, "reflex": 2, "unknown": 1}
    assert s["confusion"]["left_out:reflex"]["unknown"] == 1
    assert sum(sum(row.values()) for row in s["confusion"].values()) == 10


def test_rates_and_targets():
    s = summarise(_cases())
    # top-1 right: none ×2, reflex ×2, friction ×1, left-out ×1, pair ×1 = 7 of 10
    assert s["top1"] == pytest.approx(0.7)
    assert s["exact"] == pytest.approx(0.7)
    # ENR ≥ 1 effect cases (reflex 3.0, 1.5; friction 5.0; left-out 2.0; pair 4.0: 4 of 5 right)
    # plus the three none cases (2 right): 6 of 8
    assert s["top1_enr_ge_1"] == pytest.approx(6 / 8)
    assert s["false_alarm_none"] == pytest.approx(1 / 3)
    # correct attributions to effects: 0.9, 0.6, 0.8, 0.95; the left-out case's "unknown" is
    # correct but adds no effect, so it has no shrink to count
    assert s["median_shrink"] == pytest.approx(0.85)
    assert s["targets"] == {
        "top1_enr_ge_1": {"value": pytest.approx(0.75), "target": TARGETS["top1_enr_ge_1"], "met": False},
        "false_alarm_none": {
            "value": pytest.approx(1 / 3),
            "target": TARGETS["false_alarm_none"],
            "met": False,
        },
        "median_shrink": {"value": pytest.approx(0.85), "target": TARGETS["median_shrink"], "met": True},
    }


def test_accuracy_against_enr_and_per_class():
    s = summarise(_cases())
    bins = {tuple(b["enr"]): (b["n"], b["top1"]) for b in s["accuracy_vs_enr"]}
    assert bins[(0.0, 0.5)] == (1, 0.0)  # friction at 0.3, missed
    assert bins[(0.5, 1.0)] == (1, 1.0)
    assert bins[(1.0, 2.0)] == (1, 0.0)
    assert bins[(2.0, 4.0)] == (2, 1.0)
    assert bins[(4.0, math.inf)] == (2, 1.0)
    assert sum(n for n, _ in bins.values()) == 7  # every effect case once, none cases in no bin
    assert s["per_class"]["reflex"] == {
        "n": 3,
        "top1": pytest.approx(2 / 3),
        "top1_enr_ge_1": 0.5,
        "exact": 2 / 3,
    }
    assert s["per_class"]["none"]["top1_enr_ge_1"] is None  # none cases have no ENR


def test_all_targets_met():
    cases = [_case("none", "none", enr=0.0, shrink=math.nan) for _ in range(20)]
    cases += [_case("reflex", "reflex", enr=2.0, shrink=0.75) for _ in range(10)]
    t = summarise(cases)["targets"]
    assert t["top1_enr_ge_1"]["met"] and t["median_shrink"]["met"]
    assert t["false_alarm_none"] == {"value": 0.0, "target": 0.05, "met": True}


def test_missing_figures_are_none_not_met_or_failed():
    s = summarise([_case("reflex", "unknown", enr=0.2, shrink=0.0)])
    assert s["false_alarm_none"] is None and s["median_shrink"] is None and s["top1_enr_ge_1"] is None
    assert all(t["met"] is None for t in s["targets"].values())


def test_markdown_table():
    s = summarise(_cases()) | {"timing_s": 12.0, "median_diagnosis_s": 1.5}
    ref = RefereeConfig(protocol="joint_1dof", replicates=2)
    md = format_benchmark(s, ref, describe(ref))
    assert md.startswith("# Diagnosis benchmark — protocol `joint_1dof`\n")
    assert "5 classes × 2 replicates = 10 datasets" in md
    assert "| top-1 accuracy where ENR ≥ 1 (incl. none) | 75 % | 90 % | False |" in md
    assert "| false alarms on none | 33 % | 5 % | False |" in md
    assert "| median shrink of the gap above the floor (correct cases) | 85 % | 70 % | True |" in md
    assert "| class | joint_friction | none | reflex | unknown |" in md
    assert "| none | 0 | 2 | 1 | 0 |" in md
    assert "| 4–inf | 2 | 100 % |" in md
    assert "| none | 3 | 67 % | — | 67 % |" in md
    assert md.endswith("\n")


# --- referee scoring (armlab.protocols.joint_1dof.diagnosis.referee) ---


def test_expected_verdicts_of_the_joint_classes():
    assert expected_verdict("none", JOINT_CLASSES) == {"none"}
    assert expected_verdict("reflex", JOINT_CLASSES) == {"reflex"}
    assert expected_verdict("reflex+joint_friction", JOINT_CLASSES) == {"reflex", "joint_friction"}
    assert expected_verdict("left_out:reflex", JOINT_CLASSES) == {"unknown"}
    # the minimum: at least 9 classes
    assert len(JOINT_CLASSES) >= 9
    with pytest.raises(KeyError):
        expected_verdict("nope", JOINT_CLASSES)


def _results(verdict, ranking, nominal, floor, added):
    return {
        "verdict": verdict,
        "ranking": [{"name": n} for n in ranking],
        "gap": {
            "nominal": nominal,
            "noise_floor": floor,
            "added": [{"effects": verdict[: i + 1], "held_out_gap": g} for i, g in enumerate(added)],
        },
    }


def test_score_case_right_first_guess_and_shrink():
    s = score_case("reflex", _results(["reflex"], ["reflex", "channel_delay"], 0.05, 0.01, [0.014]))
    assert s["top1"] and s["top2"] and s["exact"] and s["predicted"] == "reflex"
    assert s["shrink_of_excess"] == pytest.approx(0.9)  # (0.05 - 0.014) / (0.05 - 0.01)
    assert s["shrink_of_gap"] == pytest.approx(0.72)
    assert s["gap_final"] == 0.014


def test_score_case_takes_the_shrink_of_an_effect_named_below_the_scoring_band():
    # joint_1dof's force_sensor_drift: the scoring band's gap is the nominal's (at the floor), the
    # shrink is the drift's own, of the slow excess (results["low_band"], docs/diagnosis_schema.md)
    res = _results(["force_sensor_drift"], [], 0.0102, 0.01, [])
    res["low_band"] = {"named": True, "force_sensor_drift": {"shrink": 0.93}}
    s = scoring.score_case("force_sensor_drift", res, {"force_sensor_drift"})
    assert s["top1"] and s["exact"] and s["shrink_of_excess"] == 0.93
    res["low_band"]["named"] = False  # reported, not named: the band's shrink stays
    assert scoring.score_case("none", res | {"verdict": ["none"]}, {"none"})["shrink_of_excess"] == 0.0


def test_score_case_second_guess_and_partial_pairs():
    s = score_case("reflex", _results(["channel_delay"], ["channel_delay", "reflex"], 0.05, 0.01, [0.03]))
    assert not s["top1"] and s["top2"] and not s["exact"]
    pair = score_case(
        "reflex+joint_friction", _results(["joint_friction"], ["joint_friction"], 0.05, 0.01, [0.02])
    )
    assert pair["top1"] and not pair["exact"]


def test_score_case_none_and_unknown():
    s = score_case("none", _results(["none"], ["channel_delay", "reflex"], 0.01, 0.01, []))
    assert s["top1"] and s["top2"] and s["exact"]
    assert math.isnan(s["shrink_of_excess"])  # nothing above the floor to shrink
    s = score_case("none", _results(["reflex"], ["reflex"], 0.02, 0.01, [0.012]))
    assert not s["top1"] and not s["top2"]
    s = score_case("left_out:reflex", _results(["unknown"], ["joint_friction"], 0.05, 0.01, []))
    assert s["top1"] and s["exact"] and s["shrink_of_excess"] == 0.0

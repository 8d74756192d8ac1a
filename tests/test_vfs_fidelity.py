"""Issue 17, paper 003: the default lab's added effects and the paper's headline figures.

Fast tests isolate each added effect on a reduced configuration (one array or the arm alone,
15 s trials: 12 s least squares, 3 s VAF) and check its mechanism; the slow test runs the full
default lab once and pins every headline of issue 17 within its tolerance
(docs/reproduction/virtual_force_sensor.md: calibration on Table III, checks on Tables IV-VI).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.cli import compose
from armlab.protocols.virtual_force_sensor.experiment import simulate_vfs
from armlab.protocols.virtual_force_sensor.results import estimate_vfs
from armlab.reproduction.vfs_headlines import TARGETS, check, headlines

SHORT = {"trial_s": 15.0, "id_s": 12.0, "val_s": 3.0, "settle_s": 1.0, "robot_id_trials": 1}


def _run(capstan: dict | None = None, **vfs) -> dict:
    cfg = compose(["protocol=virtual_force_sensor"])[1]
    cfg = replace(
        cfg,
        vfs=replace(cfg.vfs, **{**SHORT, **vfs}),
        capstan=replace(cfg.capstan, **(capstan or {})),
    )
    rec = simulate_vfs(cfg)
    return estimate_vfs(rec.trials, cfg.vfs, rec.truth)[0]


def _mass_gap(results: dict) -> dict[str, float]:
    return headlines(results)["gap_m_kg"]


def test_inertia_error_of_the_identified_model_puts_method1_mass_below_method2():
    # Eq. (10): the identified model carries m_e more end-effector mass than the robot of the
    # fixture trials, so Method 1 reads m - m_e; Method 2 (the F/T sensor) does not see it.
    # Isolated (no hysteresis, no Coulomb friction): tolerance 10 % of m_e on the shift for the
    # 12 s least squares; Method 2 moves only because the lighter robot tracks a little differently
    # behind its compliant cables (seen 0.005 kg at M1), bound 0.01 kg.
    common = {"drag_hysteresis_m": 0.0, "coulomb_Nm": 0.0}
    grid = {"stiffness": ["K1"], "payloads": ["M1", "M5"], "trials_per_config": 1, "arm_trials": 0}
    off = _run({**common, "id_ee_mass_kg": 0.0}, **grid)
    on = _run({**common, "id_ee_mass_kg": 0.2}, **grid)
    for label in ("M1", "M5"):
        assert _mass_gap(on)[label] - _mass_gap(off)[label] == pytest.approx(-0.2, abs=0.02)
        assert _mass_gap(on)[label] < -0.15  # the paper's sign
        m2 = [r["fixture"]["table_III"][label]["method2"]["m"]["mean"] for r in (on, off)]
        assert m2[0] == pytest.approx(m2[1], abs=0.01)


def test_harness_hysteresis_takes_method1_vaf_below_100_percent_and_spares_method2():
    # The dry friction of the cables is no function of X or X'' (Eq. (5)): it stays in Method 1's
    # residual. K4 (soft along x, the cables' stiff axis) with M1: seen x VAF 99.8 % without,
    # 93-96 % with the default hysteresis; Method 2 > 99.5 % either way
    grid = {"stiffness": ["K4"], "payloads": ["M1"], "trials_per_config": 1, "arm_trials": 0}
    without = _run({"drag_hysteresis_m": 0.0}, **grid)["fixture"]["table_III"]["K4"]
    with_h = _run({}, **grid)["fixture"]["table_III"]["K4"]
    assert min(without["method1"]["vaf_pct"]) > 99.0
    assert with_h["method1"]["vaf_pct"][0] < 98.0
    assert with_h["method1"]["vaf_pct"][0] < with_h["method1"]["vaf_pct"][1]  # stiffer axis (y) higher
    assert min(with_h["method2"]["vaf_pct"]) > 99.0


def test_drag_field_with_its_neutral_point_at_the_fixtures_keeps_method1_xv_near_method2():
    # Table V: the cables pull little at the arm's posture (12 mm from the neutral point, ~0.5 N),
    # so Method 1's Xv stays within 10 mm of Method 2's (seen 4 mm); the pre-issue-17 pull towards
    # the shoulder axis (neutral point 0.25 m: 133 mm away, 5.8 N) put it 43 mm off
    arm = {"trials_per_config": 0, "arm_trials": 1}
    near = headlines(_run({}, **arm))
    far = headlines(_run({"drag_neutral_m": (0.25, 0.0)}, **arm))
    assert near["xv_diff_mm"] < TARGETS["xv_diff_mm"][1]
    assert far["xv_diff_mm"] > 30.0


def test_subject_fluctuation_lowers_the_arm_vaf_of_both_methods():
    # the relaxed subject's activation fluctuation (paper 000's values, not re-tuned) is force that
    # Eq. (9) does not explain: both methods' arm VAF drop; the same trials without it (same
    # perturbations and sensor noise: the subject draws from its own generator) fit better
    arm = {"trials_per_config": 0, "arm_trials": 2}
    cfg = compose(["protocol=virtual_force_sensor"])[1]
    vafs = []
    for enabled in (True, False):
        c = replace(
            cfg, vfs=replace(cfg.vfs, **{**SHORT, **arm}), subject=replace(cfg.subject, enabled=enabled)
        )
        rec = simulate_vfs(c)
        t5 = estimate_vfs(rec.trials, c.vfs, rec.truth)[0]["arm"]["table_V"]
        vafs.append([np.mean(t5[m]["vaf_pct"]["mean"]) for m in ("method1", "method2")])
    (on1, on2), (off1, off2) = vafs
    assert on1 < off1 and on2 < off2, vafs


def test_headlines_and_targets_read_a_hand_made_result():
    t3 = {
        "K1": {me: {"k_xx": {"mean": v}} for me, v in (("method1", 450.0), ("method2", 410.0))},
        "M1": {me: {"m": {"mean": v}} for me, v in (("method1", 0.45), ("method2", 0.52))},
    }
    trial = {
        "stiffness": "K1",
        "method1": {"x0": [0.370, -0.009]},
        "method2": {"x0": [0.364, -0.029]},
    }
    res = {
        "fixture": {
            "table_III": t3,
            "trials": [trial],
            "table_IV": {"K1": {"M1": [97.0, 93.0]}, "K3": {"M1": [88.0, 96.0]}},
        },
        "truth": {"fixture": {"K1": {"x0": [0.364, -0.009]}}},
    }
    h = headlines(res)
    assert h["gap_k_xx_N_per_m"] == {"K1": pytest.approx(40.0)}
    assert h["gap_m_kg"] == {"M1": pytest.approx(-0.07)}
    assert h["x0_max_err_mm"] == {"method1": pytest.approx(6.0), "method2": pytest.approx(20.0)}
    assert h["table_IV_vaf_pct"] == (88.0, 97.0) and h["table_IV_stiffer_higher"] == 1.0
    met = check(h)
    assert met["gap_k_xx_N_per_m"] and met["gap_m_kg"] and met["table_IV_vaf_pct"]
    assert not met["x0_max_err_mm"]  # Method 2's 20 mm is beyond the paper's 18 mm
    assert "table_V_vaf_pct" not in met  # no arm trials, nothing judged


@pytest.fixture(scope="module")
def default_run() -> dict:
    cfg = compose(["protocol=virtual_force_sensor"])[1]
    rec = simulate_vfs(cfg)
    return headlines(estimate_vfs(rec.trials, cfg.vfs, rec.truth)[0])


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [
        "gap_k_xx_N_per_m",  # calibration: the paper's range +30...+56 N/m, every array
        "gap_m_kg",  # calibration: Method 1 below Method 2 by 0.03-0.10 kg, every payload
        "x0_max_err_mm",  # calibration: the paper's "within 18 mm", both methods, every trial
        "xv_diff_mm",  # check: Table V's 383 vs 382 mm, issue 17 allows 10 mm
    ],
)
def test_default_lab_meets_the_headline(default_run, name):
    assert check(default_run)[name], (name, default_run[name], TARGETS[name])


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="not reproduced (docs/reproduction/virtual_force_sensor.md)")
@pytest.mark.parametrize("name", ["table_IV_vaf_pct", "table_IV_stiffer_higher", "table_V_vaf_pct"])
def test_default_lab_misses_the_check(default_run, name):
    # Table IV: the stiffer axis of K3-K5 stays above 98 % (paper <= 97.7 %) and in K1/K2 the
    # y-VAF equals or beats the x-VAF in 5 of 10 cells; Table V: the simulated arm is a linear
    # system whose only unexplained force is the subject's activation fluctuation at paper 000's
    # size, far too small at 4 % activation (see the docs). Strict: passing would flag the fix
    assert check(default_run)[name], (name, default_run[name], TARGETS[name])


@pytest.mark.slow
def test_default_lab_table_vi_viscous_terms(default_run):
    # check, not tuned: Coulomb friction (0.05 N·m) folds into alpha4, alpha5 (+14.5 %, +27 %)
    a4, a5 = default_run["alpha45_rel_err"]
    assert 0.0 < a4 < 0.3 and 0.0 < a5 < 0.4  # a NaN fails these comparisons too

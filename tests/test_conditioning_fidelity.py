"""The default conditioning-window lab against the paper's headline figures (issue 17, seeds/000).

One default run (default config, default seed, all 780 trials; ~40 s on 2 cores) is shared by
the module. Calibrated on: the full model's K-positive-definite (320 ms) and quasi-symmetric
(370 ms) thresholds of Fig. 4. Checked on (never tuned): the quasi-constant threshold (400 ms),
the reduced known-xi model of Fig. 5 reaching positive definiteness earlier, the stiffness's order.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.cli import compose
from armlab.protocols.conditioning_window import hooks
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import PAPER_THRESHOLDS_S
from armlab.reproduction.conditioning import REDUCED_LEAD_MIN_MS

# s, the "done when": each full-model threshold within +-20 ms of the paper's, i.e. two
# 10 ms window steps (one step of resolution on each side of a reading of "T_obs > 320 ms")
THRESHOLD_TOL_S = 0.020
# s, the Fig. 5 check: the reduced (known-xi) model positive definite at least 30 ms
# before the full model (paper: ~300 ms against 320-370 ms); the study's own constant
REDUCED_LEAD_S = REDUCED_LEAD_MIN_MS / 1000.0


@pytest.fixture(scope="module")
def default_run():
    cfg = compose(["protocol=conditioning_window"])[1]
    results, _ = hooks.simulate(cfg).estimate()
    return cfg, results


def test_composed_default_equals_the_config_class_default(default_run):
    cfg, _ = default_run
    direct = ConditioningWindowConfig()
    assert cfg.cuff == direct.cuff and cfg.subject == direct.subject and cfg.estimator == direct.estimator


@pytest.mark.parametrize(
    ("criterion", "paper_key", "role"),
    [
        ("K_pd_from_s", "K_pd_after_s", "calibration"),
        ("symmetric_from_s", "symmetric_after_s", "calibration"),
        ("constant_from_s", "constant_after_s", "check"),
    ],
)
def test_full_model_thresholds_within_20ms_of_the_paper(default_run, criterion, paper_key, role):
    _, results = default_run
    sim = results["criteria"]["full"][criterion]
    assert sim is not None, f"{criterion} ({role}) never reached"
    assert abs(sim - PAPER_THRESHOLDS_S[paper_key]) <= THRESHOLD_TOL_S + 1e-9, (criterion, role, sim)


def test_reduced_model_positive_definite_at_least_30ms_earlier(default_run):
    # a check (Fig. 5): nothing was tuned on it; the reduced model takes xi from the full fit as
    # the paper does (IV-D), a choice made from the paper's text
    _, results = default_run
    full = results["criteria"]["full"]["K_pd_from_s"]
    red = results["criteria"]["reduced"]["K_pd_from_s"]
    assert results["xi_source"] == "full_fit"
    assert full is not None and red is not None
    assert full - red >= REDUCED_LEAD_S - 1e-9, (full, red)


def test_stiffness_stays_human_plausible(default_run):
    # K at the longest paper window within a factor 2 of the order [[15, 6], [6, 16]] N m/rad of
    # the 000 posture (the plausibility bound), positive definite, positive coupling
    _, results = default_run
    w = next(w for w in results["windows"] if w["t_obs_s"] == pytest.approx(0.37) and not w["extension"])
    K = np.asarray(w["K"])
    assert np.all(np.linalg.eigvalsh(0.5 * (K + K.T)) > 0)
    for i in range(2):
        assert 7.5 <= K[i, i] <= 32.0, K
        assert 0.0 < K[i, 1 - i] < min(K[0, 0], K[1, 1]), K


def test_errors_are_reported_against_two_labelled_truths(default_run):
    _, results = default_run
    assert set(results["truths"]) == {"intrinsic", "effective"}
    for w in results["windows"]:
        assert w["K_err_intrinsic"] == w["K_rel_err"]
        for entry in (w, w["reduced"]):
            for key in ("K_err_intrinsic", "D_err_intrinsic", "K_err_effective", "D_err_effective"):
                assert np.isfinite(entry[key]), key
    text = hooks.format_table(results)
    assert "int = intrinsic" in text and "eff = effective" in text
    assert "K err int  eff" in text


def test_effective_truth_carries_the_reflex_stiffness(default_run):
    # the reflexes add stiffness over the window: the effective truth is stiffer than the
    # intrinsic one (by ~70 % at these gains) and stiffens as the window grows
    _, results = default_run
    K_int = np.asarray(results["ground_truth"]["K"])
    first, last = results["windows"][0], results["windows"][-1]
    assert np.trace(last["K_eff"]) > 1.3 * np.trace(K_int)
    assert np.trace(last["K_eff"]) > np.trace(first["K_eff"])


def test_tolerances_are_stated_in_results(default_run):
    cfg, results = default_run
    tol = results["tolerances"]
    assert tol["symmetry_tol"] == cfg.estimator.symmetry_tol
    assert tol["constancy_tol_per_s"] == cfg.estimator.constancy_tol_per_s
    assert "per s of T_obs" in hooks.format_table(results)


def test_ideal_subject_is_one_switch_away():
    default = compose(["protocol=conditioning_window"])[1].subject
    cfg = compose(["protocol=conditioning_window", "subject.enabled=false"])[1]
    assert default.active and cfg.subject == replace(default, enabled=False)  # nothing else moves
    assert not cfg.subject.active


@pytest.mark.slow
def test_thresholds_hold_on_the_median_over_ten_seeds():
    # the calibration was made on seed 0; on seeds 0-9 (nothing tuned on 1-9) each full-model
    # threshold's median is within the same +-20 ms of the paper's and the reduced model's median
    # lead is >= 30 ms (docs/reproduction/conditioning_window.md has the per-seed table). A seed
    # whose criterion is never met counts as later than every window (the median then moves up).
    never = np.inf
    firsts = {key: [] for key in ("K_pd_from_s", "symmetric_from_s", "constant_from_s")}
    leads = []
    for seed in range(10):
        cfg = compose(["protocol=conditioning_window", f"seed={seed}"])[1]
        crit = hooks.simulate(cfg).estimate()[0]["criteria"]
        for key in firsts:
            firsts[key].append(never if crit["full"][key] is None else crit["full"][key])
        leads.append(crit["full"]["K_pd_from_s"] - crit["reduced"]["K_pd_from_s"])
    for key, paper_key in (
        ("K_pd_from_s", "K_pd_after_s"),
        ("symmetric_from_s", "symmetric_after_s"),
        ("constant_from_s", "constant_after_s"),
    ):
        median = float(np.median(firsts[key]))
        assert abs(median - PAPER_THRESHOLDS_S[paper_key]) <= THRESHOLD_TOL_S + 1e-9, (key, firsts[key])
    assert float(np.median(leads)) >= REDUCED_LEAD_S - 1e-9, leads

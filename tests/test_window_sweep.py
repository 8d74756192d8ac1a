"""CI's observation-window sweep (issue 21 item 3): the summary across jobs and the gate.

The fast tests build job results by hand (what each window holds is known); the slow one runs the
real sweep on a copy of armlab whose derivative has its sign flipped and checks the gate fails
(`.ci/run` runs it after the sweep).
"""

from __future__ import annotations

import copy
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from armlab.errors import DataError
from armlab.protocols.conditioning_window.window_sweep import gate, read_jobs, summarise

REPO = Path(__file__).resolve().parents[1]
BASELINE = REPO / ".ci" / "window_sweep_baseline.json"
TOL = {"symmetry_tol": 0.1, "constancy_tol": 0.05, "constancy_tol_per_s": 5.0}
MARGIN = {"K_err": 0.10, "D_err": 0.10, "xi_err": 0.10, "K_err_eff": 0.1, "D_err_eff": 0.2, "xi_err_eff": 0.1}
K_TRUE = np.array([[15.0, 6.0], [6.0, 16.0]])  # N m/rad, of the order of the paper's arm


def _window(k: int, t_obs: float, *, pd: bool, k_err: float = 0.1, extension: bool = False) -> dict:
    """A window whose K is positive definite or not, symmetric, and K_err as given."""
    K = K_TRUE * (1 + k_err) if pd else np.array([[15.0, 6.0], [6.0, -4.0]])
    D = np.eye(2)
    est = {"K": K.tolist(), "D": D.tolist(), "asym_K": 0.0, "asym_D": 0.0}
    errs = {"K_err_effective": k_err, "D_err_effective": 0.2, "K_err_intrinsic": 0.3, "D_err_intrinsic": 0.1}
    return {
        "k": k,
        "t_obs_s": t_obs,
        "extension": extension,
        "n_trials_identify": 29,
        **est,
        **errs,
        "xi": [0.4, 0.25, 0.13],
        "xi_eff": [0.4, 0.25, 0.13],
        "xi_rel_err": 0.05,
        "reduced": {**est, **errs},
    }


def _jobs(first_pd: int, n: int = 8, k_err: float = 0.1) -> list[dict]:
    """One job per window k = 1..n (T_obs = 120 + 10 (k-1) ms), K p.d. from window ``first_pd``;
    the last job also holds two extension windows, as the protocol's last group does."""
    jobs = []
    for k in range(1, n + 1):
        wins = [_window(k, 0.11 + 0.01 * k, pd=k >= first_pd, k_err=k_err)]
        wins += [_window(k, t, pd=True, k_err=k_err, extension=True) for t in (0.40, 0.50)]
        jobs.append({"seed": 0, "tolerances": TOL, "windows": wins})
    return jobs


def test_summary_orders_windows_keeps_the_last_groups_extensions_and_finds_first_met():
    s = summarise(_jobs(first_pd=4))
    assert [w["k"] for w in s["windows"]] == [1, 2, 3, 4, 5, 6, 7, 8, 8, 8]  # extensions of k=8 only
    assert s["first_met"]["full"]["K_pd_from_s"] == pytest.approx(0.15)  # window k=4
    assert s["first_met"]["reduced"]["symmetric_from_s"] == pytest.approx(0.12)  # symmetric throughout
    assert s["longest"]["full"]["K_err_eff"] == pytest.approx(0.1) and s["longest_t_obs_s"] == 0.5
    assert s["longest"]["full"]["xi_err"] == 0.05 and "xi_err" not in s["longest"]["reduced"]


def test_gate_allows_one_window_and_fails_beyond_it():
    base = summarise(_jobs(first_pd=4))
    assert gate(summarise(_jobs(first_pd=5)), base, max_window_shift=1, error_margin=MARGIN) == []
    failures = gate(summarise(_jobs(first_pd=6)), base, max_window_shift=1, error_margin=MARGIN)
    # K's jump at the p.d. transition moves the quasi-constant window with it
    assert {"full K_pd_from_s", "reduced K_pd_from_s"} <= {f.split(":")[0] for f in failures}
    assert all("+2 windows" in f for f in failures)


def test_gate_fails_when_an_error_at_the_longest_window_grows_beyond_its_margin():
    base = summarise(_jobs(first_pd=4, k_err=0.10))
    assert gate(summarise(_jobs(first_pd=4, k_err=0.19)), base, max_window_shift=1, error_margin=MARGIN) == []
    failures = gate(summarise(_jobs(first_pd=4, k_err=0.25)), base, max_window_shift=1, error_margin=MARGIN)
    assert [f.split(" at ")[0] for f in failures] == ["full K_err_eff", "reduced K_err_eff"]


def test_a_criterion_that_stops_being_met_fails_the_gate():
    base = summarise(_jobs(first_pd=4))
    jobs = _jobs(first_pd=4)
    jobs[-1]["windows"][-1] = _window(8, 0.50, pd=False, extension=True)  # the longest window fails
    failures = gate(summarise(jobs), base, max_window_shift=1, error_margin=MARGIN)
    assert any("K_pd_from_s: first met at never" in f for f in failures)


def test_summary_and_gate_refuse_mixed_or_mismatched_sweeps(tmp_path):
    jobs = _jobs(first_pd=4)
    other = copy.deepcopy(jobs)
    other[0]["seed"] = 1
    with pytest.raises(DataError, match="seed"):
        summarise(other)
    with pytest.raises(DataError, match="same window"):
        summarise(jobs + jobs[:1])
    with pytest.raises(DataError, match="different windows"):
        gate(summarise(jobs[:5]), summarise(jobs), max_window_shift=1, error_margin=MARGIN)
    (tmp_path / "0").mkdir()
    with pytest.raises(DataError, match="did not finish"):
        read_jobs(tmp_path)
    with pytest.raises(DataError, match="no job folders"):
        read_jobs(tmp_path / "0")


def test_the_committed_baseline_is_a_summary_of_the_paper_windows():
    base = json.loads(BASELINE.read_text())
    t = [w["t_obs_s"] for w in base["windows"]]
    assert len(t) == 29 and t[0] == pytest.approx(0.12) and t[-1] == pytest.approx(0.5)  # 26 + 3 extensions
    assert base["n_trials_identify"] == [29]  # the paper's 30 trials per window, one held out


def test_one_job_holding_every_window_is_judged_as_the_run_judges_it(tmp_path):
    """The sweep's summary and a run's own results.json ``criteria`` come from the same judgement."""
    from armlab.api import run

    res = run(
        "conditioning_window",
        ["scenario.k_values=[1,13,26]", "scenario.n_trials=6", "output.recording=false"]
        + ["output.figures=false"],
        out=tmp_path / "r",
    ).results
    s = summarise([res])
    for model in ("full", "reduced"):
        assert s["first_met"][model] == res["criteria"][model]


@pytest.mark.slow
def test_the_gate_fails_on_an_estimator_with_the_derivative_sign_flipped(tmp_path):
    """A copy of armlab whose q̇ has its sign flipped: K is unchanged (τ is linear in q̇ and the
    inertial terms even in it), D flips — the gate must see it in D's error."""
    broken = tmp_path / "src"
    for part in ("armlab", "configs", "models", "scenarios"):  # the package finds these beside it
        shutil.copytree(REPO / part, broken / part, ignore=shutil.ignore_patterns("__pycache__"))
    processing = broken / "armlab" / "estimation" / "processing.py"
    text = processing.read_text()
    line = "    qd, qdd = differentiate(q, fs_hz, axis=1)\n"
    assert text.count(line) == 1
    processing.write_text(text.replace(line, line + "    qd = -qd  # deliberately broken\n"))
    env = {**os.environ, "PYTHONPATH": str(broken)}
    proc = subprocess.run(
        [sys.executable, str(REPO / ".ci" / "window_sweep.py"), "--out", str(tmp_path / "sweep")],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=1800,
    )
    assert proc.returncode == 1, proc.stdout + proc.stderr
    failed = [ln for ln in proc.stderr.splitlines() if ln.startswith("window sweep gate FAILED")]
    assert any("full D_err" in ln for ln in failed), proc.stderr

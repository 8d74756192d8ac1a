"""The observation-window sweep that CI watches: one Hydra job per window, one summary, one gate.

``armlab run --multirun protocol=conditioning_window scenario.k_values=[1],[2],...`` runs each
window of the paper (T_obs = T_k + 70 ms; the last group also carries the extension windows) as
its own job. :func:`summarise` gathers the jobs' ``results.json`` into one table ordered by T_obs
and judges the paper's criteria (section IV-D) across the whole sweep as a run does
(:func:`.experiment.criteria_flags`); :func:`gate` compares a summary with a committed baseline
and lists what moved: the window at which a criterion is first met (by more than
``max_window_shift`` windows) and the error of K, D and xi against the truth at the longest window
(by more than ``error_margin``).

Why D and xi too, and the intrinsic truth: a sign error in the derivatives (q̇ → −q̇) leaves the
least-squares K exactly unchanged (τ is linear in q̇; the inertial terms are even in q̇) and so
every criterion on K; it flips D — and the effective truth with it, as that is the same estimator
run on an ideal lab — so only D's error against the intrinsic truth sees it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from armlab.errors import DataError
from armlab.estimation import criteria
from armlab.protocols.conditioning_window.experiment import criteria_flags, first_met

__all__ = ["CRITERIA", "MODELS", "gate", "read_jobs", "summarise"]

#: the criteria of section IV-D, as results.json names their first-met windows
CRITERIA = ("K_pd_from_s", "symmetric_from_s", "constant_from_s")
#: the full (Eq. 10: xi, D, K) and the reduced (Eq. 23: D, K, xi known) least squares
MODELS = ("full", "reduced")


def read_jobs(sweep_dir: Path) -> list[dict]:
    """The ``results.json`` of every job folder of a sweep (several sweep folders may be given as a
    list, e.g. the shards of a CI matrix). A job without results is an error naming it."""
    dirs = [sweep_dir] if isinstance(sweep_dir, str | Path) else list(sweep_dir)
    jobs = []
    for d in map(Path, dirs):
        if not d.is_dir():
            raise DataError(f"{d} is not a sweep folder")
        folders = sorted(p for p in d.iterdir() if p.is_dir() and p.name.isdigit())
        if not folders:
            raise DataError(f"{d} holds no job folders (0/, 1/, ...): give the out= of a --multirun")
        for p in folders:
            if not (p / "results.json").is_file():
                raise DataError(f"job {p} has no results.json: it did not finish")
            jobs.append(json.loads((p / "results.json").read_text()))
    return jobs


def _params(entry: dict, model: str) -> np.ndarray:
    """The window's parameter vector in the estimator's order (Eq. 10: xi, D, K; Eq. 23: D, K)."""
    e = entry if model == "full" else entry["reduced"]
    parts = ([e["xi"]] if model == "full" else []) + [np.ravel(e["D"]), np.ravel(e["K"])]
    return np.concatenate([np.ravel(p) for p in parts])


def summarise(jobs: list[dict]) -> dict:
    """One table of the sweep's windows and the criteria judged across it.

    Returns:
        ``{"windows": [{"t_obs_s", "k", "extension", "<model>": {"K_pd", "symmetric",
        "constant", <errors>}}], "first_met": {model: {criterion: t_obs_s or None}}, "longest":
        {model: {<errors>}}, "tolerances": {...}, "seed", "n_trials_identify"}``; the errors are
        relative Frobenius errors (fractions) against the intrinsic truth (``K_err``, ``D_err``,
        ``xi_err``: the arm model linearised at the operating point — the ground truth, which no
        estimator bug moves) and against the effective truth (``..._eff``: the same estimator in
        an ideal lab, results_schema.md — tighter, but blind to a bug the estimator makes in both).

    Raises:
        DataError: jobs of different seeds or tolerances, two jobs with the same window, or no job.
    """
    if not jobs:
        raise DataError("the sweep has no jobs")
    tol = {json.dumps(j["tolerances"], sort_keys=True) for j in jobs}
    seeds = {j["seed"] for j in jobs}
    if len(tol) > 1 or len(seeds) > 1:
        raise DataError(f"the jobs differ in seed {sorted(seeds)} or tolerances; one sweep, one setting")
    tolerances = jobs[0]["tolerances"]
    # a one-window job also estimates the extension windows on its own trial group; the sweep keeps
    # those of the longest group only, as one run of the protocol holds them
    last = max(w["k"] for j in jobs for w in j["windows"])
    kept = (w for j in jobs for w in j["windows"] if not w["extension"] or w["k"] == last)
    entries = sorted(kept, key=lambda w: w["t_obs_s"])
    t_obs = np.array([w["t_obs_s"] for w in entries])
    if np.any(np.diff(t_obs) <= 0):
        raise DataError(f"two jobs hold the same window (T_obs {t_obs.tolist()}); one job per window")
    rows = [{"t_obs_s": float(w["t_obs_s"]), "k": w["k"], "extension": w["extension"]} for w in entries]
    first, longest = {}, {}
    for model in MODELS:
        est = [w if model == "full" else w["reduced"] for w in entries]
        flags = criteria_flags(  # the protocol's own judgement, on the jobs' stored estimates
            t_obs,
            [np.asarray(e["K"]) for e in est],
            [np.asarray(e["D"]) for e in est],
            np.stack([_params(w, model) for w in entries]),
            symmetry_tol=tolerances["symmetry_tol"],
            constancy_tol=tolerances["constancy_tol"],
            constancy_tol_per_s=tolerances.get("constancy_tol_per_s"),
        )
        errors = {  # against the intrinsic truth (the model's own, independent of the estimator)
            "K_err": [e["K_err_intrinsic"] for e in est],  # and the effective one (results_schema.md)
            "D_err": [e["D_err_intrinsic"] for e in est],
            "K_err_eff": [e["K_err_effective"] for e in est],
            "D_err_eff": [e["D_err_effective"] for e in est],
        }
        if model == "full":
            errors["xi_err"] = [w["xi_rel_err"] for w in entries]
            errors["xi_err_eff"] = [
                criteria.relative_error(np.asarray(w["xi"]), np.asarray(w["xi_eff"])) for w in entries
            ]
        for i, row in enumerate(rows):
            row[model] = {
                **{name: bool(f[i]) for name, f in flags.items()},
                **{k: float(v[i]) for k, v in errors.items()},
            }
        first[model] = first_met(t_obs, flags)
        longest[model] = {k: float(v[-1]) for k, v in errors.items()}
    return {
        "windows": rows,
        "first_met": first,
        "longest": longest,
        "longest_t_obs_s": float(t_obs[-1]),
        "tolerances": tolerances,
        "seed": seeds.pop(),
        "n_trials_identify": sorted({w["n_trials_identify"] for w in entries}),
    }


def _index(t: float | None, grid: list[float]) -> int:
    """Position of a first-met window on the baseline's grid; never met is one past the last."""
    if t is None:
        return len(grid)
    return int(np.argmin(np.abs(np.asarray(grid) - t)))


def gate(
    summary: dict, baseline: dict, *, max_window_shift: int, error_margin: dict[str, float]
) -> list[str]:
    """What moved from the baseline beyond the allowance (empty: the gate passes).

    Args:
        summary, baseline: :func:`summarise` outputs of the same sweep (same windows).
        max_window_shift: windows a criterion's first-met window may move either way.
        error_margin: per error (``K_err``, ``D_err``, ``xi_err``), how much (a fraction: 0.05 =
            5 points of relative error) it may grow above the baseline's at the longest window.

    Raises:
        DataError: the two sweeps have different windows (a baseline of another sweep).
    """
    grid = [w["t_obs_s"] for w in baseline["windows"]]
    now_grid = [w["t_obs_s"] for w in summary["windows"]]
    if len(now_grid) != len(grid) or not np.allclose(now_grid, grid, atol=1e-9, rtol=0):
        raise DataError("the sweep and the baseline hold different windows; compare the same sweep")
    failures = []
    for model in MODELS:
        for name in CRITERIA:
            now, then = summary["first_met"][model][name], baseline["first_met"][model][name]
            shift = _index(now, grid) - _index(then, grid)
            if abs(shift) > max_window_shift:
                failures.append(
                    f"{model} {name}: first met at {_ms(now)} (baseline {_ms(then)}), {shift:+d} windows "
                    f"(allowed ±{max_window_shift})"
                )
        for key, then in baseline["longest"][model].items():
            now = summary["longest"][model][key]
            if now > then + error_margin[key]:
                failures.append(
                    f"{model} {key} at T_obs {summary['longest_t_obs_s'] * 1e3:.0f} ms: {now:.1%} "
                    f"(baseline {then:.1%}, allowed up to {then + error_margin[key]:.1%})"
                )
    return failures


def _ms(t: float | None) -> str:
    return "never" if t is None else f"{t * 1e3:.0f} ms"

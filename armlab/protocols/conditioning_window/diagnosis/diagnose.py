"""``armlab diagnose`` for the conditioning-window protocol: where, which effect, how far.

The nominal simulation is the paper's linearised arm (Eq. 9) with its 11 parameters calibrated on
the training trials (least squares over 0-400 ms after onset). Held-out trials are scored.
Pure computation: a trial set and a :class:`DiagnosisConfig` in, a JSON-ready results dict
(``docs/diagnosis_schema.md``) and the signals for figures out.
"""

from __future__ import annotations

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.attribution import select_candidates, select_effects
from armlab.diagnosis.families import FittedModel
from armlab.diagnosis.localise import WINDOWS_MS, masked_gap, trial_band_breakdown
from armlab.diagnosis.summary import gap_section, row_floor, stage_entry, verdict_section
from armlab.estimation.joint_ls import PARAM_NAMES
from armlab.protocols.conditioning_window.diagnosis.data import CHANNELS, CondSet, prepare_cond
from armlab.protocols.conditioning_window.diagnosis.models import COND_FAMILY, COND_SURROGATES
from armlab.protocols.conditioning_window.diagnosis.rules import RULES

__all__ = [
    "BIAS_WINDOWS_S",
    "cond_candidates",
    "diagnose_cond",
]

#: s, observation windows of the parameter-bias check (paper's T_obs range 110-370 ms, and 400).
BIAS_WINDOWS_S = (0.12, 0.2, 0.3, 0.4)


def cond_candidates(cfg: DiagnosisConfig) -> list[str]:
    """The candidate list after ``candidates`` / ``exclude`` (unknown names raise ConfigError)."""
    return select_candidates(cfg, COND_SURROGATES, "conditioning_window")


def _breakdowns(cs: CondSet, y: np.ndarray, resid: np.ndarray) -> dict:
    """Held-out gap by window after onset, joint, perturbation direction and frequency band."""
    noise = cs.row_noise_var
    t_ms = 1000.0 * cs.row_time_s
    held = cs.held
    windows = [
        {"window_ms": [lo, hi], **masked_gap(resid, y, noise, held & (t_ms >= lo) & (t_ms < hi))}
        for lo, hi in WINDOWS_MS
    ]
    channels = [
        {"channel": "torque", "axis": name, **masked_gap(resid, y, noise, held & (cs.row_channel == j))}
        for j, name in enumerate(CHANNELS)
    ]
    row_dir = cs.direction[cs.row_trial]
    conditions = [
        {"direction": int(d), **masked_gap(resid, y, noise, held & (row_dir == d))}
        for d in np.unique(cs.direction)
    ]
    # bands: spectra of the held-out trials' 0-400 ms residual and measured torque (Hann window)
    shape = (cs.n_trials, cs.n_window, 2)
    r3, y3 = resid.reshape(shape)[cs.held_trials], y.reshape(shape)[cs.held_trials]
    bands = trial_band_breakdown(r3, y3, cs.fs_hz)
    return {"windows": windows, "channels": channels, "conditions": conditions, "bands": bands}


def _residual_tests(cs: CondSet, resid: np.ndarray, max_lag_s: float = 0.1) -> dict:
    """Whiteness of the held-out residual and its cross-correlation with the joint velocity."""
    shape = (cs.n_trials, cs.n_window, 2)
    r = resid.reshape(shape)[cs.held_trials]
    v = cs.rows(cs.qd).reshape(shape)[cs.held_trials]
    lags = np.arange(int(round(max_lag_s * cs.fs_hz)) + 1)
    r0 = r - r.mean(axis=1, keepdims=True)
    v0 = v - v.mean(axis=1, keepdims=True)
    denom_r = np.sum(r0**2)
    acf = np.array([np.sum(r0[:, k:] * r0[:, : cs.n_window - k]) / denom_r for k in lags])
    xcf = np.array([np.sum(r0[:, k:] * v0[:, : cs.n_window - k]) for k in lags]) / np.sqrt(
        denom_r * np.sum(v0**2)
    )
    bound = 1.96 / np.sqrt(r0.size)
    k_max = int(np.argmax(np.abs(xcf)))
    return {
        "lags_s": (lags / cs.fs_hz).tolist(),
        "autocorrelation": acf.tolist(),
        "cross_correlation_velocity": xcf.tolist(),
        "bound_95": float(bound),
        "whiteness_lag_1_to_20ms": float(np.max(np.abs(acf[1 : int(0.02 * cs.fs_hz) + 1]))),
        "max_cross_correlation": float(xcf[k_max]),
        "max_cross_correlation_lag_s": float(lags[k_max] / cs.fs_hz),
    }


def _identify(cs: CondSet, target_rows: np.ndarray) -> list[dict]:
    """The 11-parameter least squares on the training trials over each bias window."""
    x = cs.rows(cs.nominal_columns)
    out = []
    for t_obs in BIAS_WINDOWS_S:
        mask = cs.train & (cs.row_time_s < t_obs - 0.5 / cs.fs_hz)
        zeta = np.linalg.lstsq(x[mask], target_rows[mask], rcond=None)[0]
        out.append({"t_obs_s": t_obs, **dict(zip(PARAM_NAMES, map(float, zeta), strict=True))})
    return out


def _stage(cs: CondSet, y: np.ndarray, model: FittedModel, measured_ident: list[dict], floor: float) -> dict:
    entry, _ = stage_entry(model, (cs,), [y], floor)
    sim_ident = _identify(cs, model.predictions[0])
    bias = [
        {"t_obs_s": m["t_obs_s"], **{k: m[k] - s[k] for k in PARAM_NAMES}, "measured": m, "simulated": s}
        for m, s in zip(measured_ident, sim_ident, strict=True)
    ]
    return {
        **entry,
        **_breakdowns(cs, y, model.residuals[0]),
        "parameters": dict(zip(model.linear_names, map(float, model.beta[0]), strict=True)),
        "nonlinear_parameters": dict(model.theta),
        "parameter_bias": bias,
        "n_params": model.n_params,
    }


def diagnose_cond(trials, cfg: DiagnosisConfig) -> tuple[dict, dict]:
    """Diagnose a conditioning-window trial set (see the module docstring).

    Args:
        trials: a :class:`armlab.data.trial.TrialSet` with ``hand_pos``, ``hand_force``.
        cfg: the diagnosis settings (``band_hz``, ``holdout_fraction`` and the selection rules).

    Returns:
        (results, series) — ``series["all"]`` holds the scoring set and each stage's prediction.
    """
    cfg = cfg.with_rules(RULES)
    cs = prepare_cond(trials, band_hz=cfg.band_hz, holdout_fraction=cfg.holdout_fraction)
    y = cs.y
    names = cond_candidates(cfg)
    floor = row_floor(cs, y)
    sel = select_effects(
        (cs,),
        [y],
        None,
        {n: COND_SURROGATES[n] for n in names},
        floor,
        cfg,
        band_share=cfg.band_hz / (0.5 * cs.fs_hz),
        family=COND_FAMILY,
    )
    measured_ident = _identify(cs, y)
    stages = [_stage(cs, y, m, measured_ident, floor) for m in sel.stages]
    metric = "held-out residual power / measured power, 0-400 ms after onset, both joints (1 - VAF)"
    results = {
        **verdict_section("conditioning_window", cfg, sel),
        "gap": {
            **gap_section(metric, stages, floor),
            "noise_source": (
                "band-limited torque over the pre-onset hold, as hand-force noise through each row's "
                "J(q)^T, plus the baseline-mean variance"
            ),
        },
        "where": {
            "windows": stages[0]["windows"],
            "bands": stages[0]["bands"],
            "channels": stages[0]["channels"],
            "conditions": stages[0]["conditions"],
            "residual_tests": _residual_tests(cs, sel.stages[0].residuals[0]),
            "parameter_bias": stages[0]["parameter_bias"],
        },
        "how_far": stages,
        "indistinct": sel.indistinct,
        "partial": sel.partial,
        "trials": list(cs.names),
        "scoring": {"held_out_trials": int(cs.held_trials.sum()), "window_s": cs.n_window / cs.fs_hz},
    }
    series = {
        "set": cs,
        "measured": y,
        "nominal": sel.stages[0].predictions[0],
        "corrected": sel.stages[-1].predictions[0],
        "stages": sel.stages,
    }
    return results, {"all": series}

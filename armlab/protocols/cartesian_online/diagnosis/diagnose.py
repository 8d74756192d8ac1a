"""``armlab diagnose`` for ``cartesian_online``: where the thesis's field misses, which effect, how far.

The nominal simulation is the thesis's quadratic field with ``D = δ√K`` (Eqs. 2.2.1-2.2.4, 3.4.1)
calibrated on the training sequences; the held-out sequences' force is predicted and scored
(:mod:`.data`, :mod:`.models`). Pure computation: a trial set and a :class:`DiagnosisConfig` in,
a JSON-ready results dict (docs/diagnosis_schema.md, section ``cartesian_online``) and the
signals for the figures out.
"""

from __future__ import annotations

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.attribution import select_candidates, select_effects
from armlab.diagnosis.families import FittedModel
from armlab.diagnosis.localise import WINDOWS_MS, masked_gap, trial_band_breakdown
from armlab.diagnosis.summary import gap_section, row_floor, stage_entry, verdict_section
from armlab.protocols.cartesian_online.diagnosis.data import AXES, CartSet, prepare_cart
from armlab.protocols.cartesian_online.diagnosis.models import CART_FAMILY, CART_SURROGATES
from armlab.protocols.cartesian_online.diagnosis.rules import RULES

__all__ = [
    "cart_candidates",
    "diagnose_cart",
]


def cart_candidates(cfg: DiagnosisConfig) -> list[str]:
    """The candidate list after ``candidates`` / ``exclude`` (unknown names raise ConfigError)."""
    return select_candidates(cfg, CART_SURROGATES, "cartesian_online")


def _trial_major(cs: CartSet, rows: np.ndarray) -> np.ndarray:
    """Scoring rows -> (m, n, 2), zero where not scored (padding, edge guard)."""
    out = np.zeros((*cs.scored.shape, 2))
    out[cs.scored] = rows.reshape(-1, 2)
    return out


def _breakdowns(cs: CartSet, y: np.ndarray, resid: np.ndarray) -> dict:
    """Held-out gap by window after onset, axis, sequence, perturbation and frequency band."""
    noise, held = cs.row_noise_var, cs.held
    t_ms = 1000.0 * cs.row_time_s
    row_stop, row_phase = cs.stop[cs.row_trial], cs.phase[cs.row_trial]
    windows = [
        {"window_ms": [lo, hi], **masked_gap(resid, y, noise, held & (t_ms >= lo) & (t_ms < hi))}
        for lo, hi in WINDOWS_MS
    ]
    channels = [
        {"channel": "hand_force", "axis": a, **masked_gap(resid, y, noise, held & (cs.row_axis == j))}
        for j, a in enumerate(AXES)
    ]
    sequences = [
        {"sequence": int(s), **masked_gap(resid, y, noise, held & (row_stop == s))}
        for s in np.unique(cs.stop[cs.held_trials])
    ]
    phases = [
        {"perturbation": str(ph), **masked_gap(resid, y, noise, held & (row_phase == ph))}
        for ph in np.unique(cs.phase)
    ]
    r3, y3 = _trial_major(cs, resid)[cs.held_trials], _trial_major(cs, y)[cs.held_trials]
    bands = trial_band_breakdown(r3, y3, cs.fs_hz)
    return {
        "windows": windows,
        "channels": channels,
        "sequences": sequences,
        "perturbations": phases,
        "bands": bands,
    }


def _residual_tests(cs: CartSet, resid: np.ndarray, max_lag_s: float = 0.05) -> dict:
    """Whiteness of the held-out residual and its cross-correlation with the hand velocity, over
    the scored samples (zero elsewhere: the padding and the edge guard)."""
    r = _trial_major(cs, resid)[cs.held_trials]
    v = cs.band(cs.v)[cs.held_trials]
    mask = np.broadcast_to(cs.scored[cs.held_trials][..., None], r.shape)
    n = r.shape[1]
    lags = np.arange(int(round(max_lag_s * cs.fs_hz)) + 1)
    count = np.maximum(mask.sum(axis=1, keepdims=True), 1)
    r0 = np.where(mask, r - np.where(mask, r, 0.0).sum(axis=1, keepdims=True) / count, 0.0)
    v0 = np.where(mask, v - np.where(mask, v, 0.0).sum(axis=1, keepdims=True) / count, 0.0)
    denom_r = np.sum(r0**2)
    acf = np.array([np.sum(r0[:, k:] * r0[:, : n - k]) / denom_r for k in lags])
    xcf = np.array([np.sum(r0[:, k:] * v0[:, : n - k]) for k in lags]) / np.sqrt(denom_r * np.sum(v0**2))
    k_max = int(np.argmax(np.abs(xcf)))
    return {
        "lags_s": (lags / cs.fs_hz).tolist(),
        "autocorrelation": acf.tolist(),
        "cross_correlation_velocity": xcf.tolist(),
        "bound_95": float(1.96 / np.sqrt(mask.sum())),
        "max_cross_correlation": float(xcf[k_max]),
        "max_cross_correlation_lag_s": float(lags[k_max] / cs.fs_hz),
    }


def _stage(cs: CartSet, y: np.ndarray, model: FittedModel, floor: float) -> dict:
    entry, _ = stage_entry(model, (cs,), [y], floor)
    return {
        **entry,
        **_breakdowns(cs, y, model.residuals[0]),
        "parameters": dict(zip(model.linear_names, map(float, model.beta[0]), strict=True)),
        "nonlinear_parameters": dict(model.theta),
        "n_params": model.n_params,
    }


def diagnose_cart(trials, cfg: DiagnosisConfig) -> tuple[dict, dict]:
    """Diagnose a ``cartesian_online`` trial set (see the module docstring).

    Args:
        trials: a :class:`armlab.data.trial.TrialSet` with ``hand_pos``, ``ref_pos``, ``hand_force``.
        cfg: the diagnosis settings (``band_hz`` and the selection rules).

    Returns:
        (results, series): ``series["all"]`` holds the scoring set and each stage's prediction.
    """
    cfg = cfg.with_rules(RULES)
    names = cart_candidates(cfg)
    cs = prepare_cart(trials, band_hz=cfg.band_hz)
    y = cs.y
    floor = row_floor(cs, y)
    sel = select_effects(
        (cs,),
        [y],
        None,
        {n: CART_SURROGATES[n] for n in names},
        floor,
        cfg,
        band_share=cfg.band_hz / (0.5 * cs.fs_hz),
        family=CART_FAMILY,
    )
    stages = [_stage(cs, y, m, floor) for m in sel.stages]
    metric = (
        "held-out residual power / measured force power, every scored sample, both axes, "
        f"0-{cfg.band_hz:g} Hz (1 - VAF)"
    )
    results = {
        **verdict_section("cartesian_online", cfg, sel),
        "gap": {
            **gap_section(metric, stages, floor),
            "noise_source": "second differences of the raw force (white noise assumed), trimmed mean "
            "per axis, through the band's zero-phase filter; plus the position's white noise (the "
            "same estimator on hand_pos) through the nominal field, K^2 and delta^2 K times the "
            "band's and the smoothed differentiator's gains; plus per-trial force offsets (the F/T's "
            "residual tare: the trial means of the nominal residual less a smooth function of the "
            "stop and time, per perturbation)",
            "trial_offset_N": [float(x) for x in np.sqrt(cs.offset_var)],
            "edge_guard_ms": 1000.0 * cs.edge_guard / cs.fs_hz,
            "velocity_cutoff_hz": [
                float(f) if np.isfinite(f) and f < cfg.band_hz else None for f in cs.vel_cutoff_hz
            ],
        },
        "where": {
            "windows": stages[0]["windows"],
            "bands": stages[0]["bands"],
            "channels": stages[0]["channels"],
            "sequences": stages[0]["sequences"],
            "perturbations": stages[0]["perturbations"],
            "residual_tests": _residual_tests(cs, sel.stages[0].residuals[0]),
        },
        "how_far": stages,
        "indistinct": sel.indistinct,
        "partial": sel.partial,
        "trials": list(cs.names),
        "nominal_field": {
            "k_N_per_m": cs.k0.tolist(),
            "delta": cs.delta0.tolist(),
            "note": "D = δ√K fit (12 + 2) on the training sequences, in Table 3.1's basis "
            "[1, x, y, x², 2xy, y²]",
        },
        "scoring": {
            "held_out_sequences": sorted({int(s) for s in cs.stop[cs.held_trials]}),
            "n_sequences": int(cs.stop.max()) + 1,
            "held_out_trials": int(cs.held_trials.sum()),
        },
    }
    series = {
        "set": cs,
        "measured": y,
        "nominal": sel.stages[0].predictions[0],
        "corrected": sel.stages[-1].predictions[0],
        "stages": sel.stages,
    }
    return results, {"all": series}

"""``armlab diagnose`` for the 1-DoF joint protocol: where, which effect, how far it shrinks.

Pure computation: imported trials and a :class:`DiagnosisConfig` in, a JSON-ready results dict
and the signals for figures/recordings out (files are written by the CLI; see
``docs/diagnosis_schema.md`` for every key).
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.attribution import (
    delta_bic,
    effective_samples,
    explains_enough,
    held_out_gap,
    select_candidates,
    select_effects,
    step_accepted,
)
from armlab.diagnosis.families import FittedModel, active_params, fit_model
from armlab.diagnosis.localise import band_breakdown, frf_parameters, residual_tests, window_breakdown
from armlab.diagnosis.summary import gap_section, stage_entry
from armlab.dsp import zero_phase
from armlab.errors import ConfigError, DataError
from armlab.protocols.joint_1dof.diagnosis.data import (
    fit_decimation,
    highpass_sos,
    noise_floor,
    prepare_trials,
)
from armlab.protocols.joint_1dof.diagnosis.derivative_floor import derivative_floor
from armlab.protocols.joint_1dof.diagnosis.low_band import low_band_check
from armlab.protocols.joint_1dof.diagnosis.models import (
    ANY_RATE_HZ,
    JOINT_FAMILY,
    JOINT_SURROGATES,
    JOINT_TV_FAMILY,
    OP_LINEAR_NAMES,
)
from armlab.protocols.joint_1dof.diagnosis.position_sensor import (
    GRID_EFFECT,
    grid_floor,
    position_sensor_summary,
)
from armlab.protocols.joint_1dof.diagnosis.rules import RULES
from armlab.protocols.joint_1dof.diagnosis.time_varying import scan_operating_point
from armlab.protocols.joint_1dof.diagnosis.tonic_cue import (
    RECTIFYING_EFFECTS,
    held_verdict,
    tonic_cue_check,
)

__all__ = [
    "candidate_names",
    "check_referee",
    "prepare_scoring",
    "diagnose_joint",
]

_METRIC = "held-out residual power / measured power in the scoring band (1 - VAF)"
_COCONTRACTION = "cocontraction_variation"  # the candidate whose cue :mod:`.tonic_cue` checks


def candidate_names(cfg: DiagnosisConfig) -> list[str]:
    """The joint candidates after ``candidates`` / ``exclude`` (unknown names raise ConfigError)."""
    return select_candidates(cfg, JOINT_SURROGATES, "joint_1dof")


def _torque_sign(nominal: FittedModel) -> float:
    """-1 when the recorded torque is antiphase to the angle (the impedance is -torque/position:
    the nominal's K, summed over trials, is negative), else 1."""
    return -1.0 if sum(float(np.mean(b[2])) for b in nominal.beta) < 0 else 1.0


def _impedance(model: FittedModel, sign: float) -> list[dict]:
    """Per trial, the linear parameters with the torque sign folded in (positive I, B, K)."""
    return [
        {k: float(sign * v) for k, v in zip(model.linear_names, beta, strict=True)} for beta in model.beta
    ]


def _stage(model, trials, y_band, noise, floor, sign, frf_meas) -> dict:
    entry, per_trial = stage_entry(model, trials, y_band, floor)
    frf_sim = [frf_parameters(tr, p) for tr, p in zip(trials, model.predictions, strict=True)]
    return {
        **entry,
        "per_trial": [
            {"trial": tr.name, "held_out_gap": g, "held_out_vaf_percent": 100.0 * (1.0 - g)}
            for tr, g in zip(trials, per_trial, strict=True)
        ],
        "bands": band_breakdown(trials, y_band, model.residuals, noise),
        "windows": window_breakdown(trials, y_band, model.residuals, noise.variance_Nm2),
        "parameters": _impedance(model, sign),
        "nonlinear_parameters": active_params(
            model.theta, tuple(JOINT_SURROGATES[e] for e in model.effects if e in JOINT_SURROGATES)
        ),
        "frf_bias": [
            {k: m[k] - s[k] for k in ("I", "B", "K")} | {"measured": m, "simulated": s}
            for m, s in zip(frf_meas, frf_sim, strict=True)
        ],
        "n_params": model.n_params,
    }


def prepare_scoring(records, cfg: DiagnosisConfig, **kw):
    """(prepared trials, scoring high-pass sections, measured torque in the scoring band).

    ``kw``: further arguments of :func:`armlab.protocols.joint_1dof.diagnosis.data.prepare_trials`
    (``edge_s``).
    """
    trials = prepare_trials(
        records,
        fs_fit_hz=cfg.fs_fit_hz,
        band_hz=cfg.band_hz,
        holdout_fraction=cfg.holdout_fraction,
        slow_hz=cfg.slow_hz,
        min_duration_s=cfg.min_duration_s,
        **kw,
    )
    hp = highpass_sos(trials[0].fs_hz, cfg.highpass_hz)
    return trials, hp, [zero_phase(hp, tr.y) for tr in trials]


def check_referee(ref, cfg: DiagnosisConfig) -> None:
    """ConfigError if datasets recorded at ``referee.fs_hz`` could not be diagnosed with ``cfg``
    (the checks :func:`prepare_trials` and the candidates' rates apply to the data), before the
    referee simulates any."""
    fs = float(ref.fs_hz)
    fs_fit = fs / fit_decimation(fs, cfg.fs_fit_hz)
    try:
        if cfg.band_hz >= 0.45 * fs_fit:
            raise DataError(
                f"diagnosis.band_hz={cfg.band_hz:g} Hz needs a fitting rate above "
                f"{cfg.band_hz / 0.45:.0f} Hz; the datasets give {fs_fit:g} Hz"
            )
        _check_rate(candidate_names(cfg), fs_fit, fs)
    except DataError as exc:
        raise ConfigError(f"referee.fs_hz={fs:g}: {exc}") from None


_OP_EFFECT = "operating_point_impedance"


def _operating_point(
    trials, y_band, hp, floor: float, cfg: DiagnosisConfig, band_share: float
) -> tuple[dict, FittedModel, FittedModel]:
    """Whether the impedance varies with the operating angle, where and how much, and how far a
    time-varying nominal shrinks the gap (:mod:`.time_varying`; docs/diagnosis_schema.md); and the
    stationary and time-varying nominals fitted for it.

    The time-varying nominal is judged over the stationary one by the core's rule for a step
    (:func:`~armlab.diagnosis.attribution.step_accepted`: penalised score, share of the excess,
    share of the floor), where the binned scan has found a parameter that varies. It is not held
    to the first-effect share (``min_first_explained``), which keeps a minor cause from being named
    alone: the scan's per-bin fits are the independent evidence that the impedance varies, and the
    effects it leaves unexplained are then selected, and judged, from the time-varying nominal."""
    stationary = fit_model(trials, y_band, (), hp, family=JOINT_FAMILY)
    sign = _torque_sign(stationary)
    scan = scan_operating_point(trials, y_band, hp, band_share=band_share, sign=sign)
    tv = fit_model(trials, y_band, (), hp, family=JOINT_TV_FAMILY)
    gap_s, rss_s, _ = held_out_gap(stationary, trials, y_band)
    gap_tv, rss_tv, _ = held_out_gap(tv, trials, y_band)
    excess = max(gap_s - floor, 0.0)
    shrink = gap_s - gap_tv
    dbic = delta_bic(rss_tv, rss_s, tv.n_params - stationary.n_params, effective_samples(trials, band_share))
    varies = bool(scan.varying) and step_accepted(
        cfg, first=False, excess0=excess, floor=floor, reduction=shrink, dbic=dbic
    )
    # K(p), B(p) of the time-varying nominal over the bins' range (trial-mean coefficients)
    beta = np.mean(np.asarray(tv.beta, float), axis=0) * sign
    names = list(tv.linear_names)
    grid = np.linspace(scan.edges_rad[0], scan.edges_rad[-1], 41)
    p = grid - trials[0].op_ref
    coef = {n: float(beta[names.index(n)]) for n in ("B", "K", *OP_LINEAR_NAMES)}
    curves = {
        "K": (coef["K"] + coef[OP_LINEAR_NAMES[0]] * p + coef[OP_LINEAR_NAMES[2]] * p**2).tolist(),
        "B": (coef["B"] + coef[OP_LINEAR_NAMES[1]] * p + coef[OP_LINEAR_NAMES[3]] * p**2).tolist(),
    }
    where = None
    if scan.varying:
        k = scan.varying[0]
        v = scan.values[k]
        where = {
            "parameter": k,
            "from_rad": float(scan.edges_rad[0]),
            "to_rad": float(scan.edges_rad[-1]),
            "lowest": {"value": float(v.min()), "at_rad": float(scan.centres_rad[int(np.argmin(v))])},
            "highest": {"value": float(v.max()), "at_rad": float(scan.centres_rad[int(np.argmax(v))])},
        }
    summary = {
        "varies": varies,
        "where": where,
        "binned": scan.as_dict(),
        "stationary_nominal_gap": gap_s,
        "time_varying_nominal_gap": gap_tv,
        "explained_fraction": shrink / excess if excess > 0 else 0.0,
        "delta_bic": dbic,
        "reference_rad": trials[0].op_ref,
        "coefficients": coef,
        "curves": {"operating_angle_rad": grid.tolist(), **curves},
    }
    return summary, stationary, tv


def _check_rate(names: list[str], fs_fit: float, fs_raw: float) -> None:
    """DataError if a candidate searches a frequency (a ``*_hz`` parameter) at or beyond the
    fitting rate's Nyquist frequency: its digital filter cannot be built there (e.g. 40 Hz data
    against the reflex's low-pass up to 25 Hz). Frequencies applied as an exact frequency
    response (:data:`ANY_RATE_HZ`: the torque sensor's) may lie anywhere."""
    for name in names:
        for p in JOINT_SURROGATES[name].params:
            if f"{name}.{p.name}" in ANY_RATE_HZ:
                continue
            if p.name.endswith("_hz") and not p.upper < fs_fit / 2:
                raise DataError(
                    f"data sampled at {fs_raw:g} Hz are fitted at {fs_fit:g} Hz, whose Nyquist frequency "
                    f"{fs_fit / 2:g} Hz cannot carry candidate {name!r} ({p.name} up to {p.upper:g} Hz); "
                    f"valid: data sampled at >= {2 * p.upper:g} Hz (diagnosis.fs_fit_hz above that), or "
                    f"diagnosis.exclude=[{name}]"
                )


def _grid_named(
    cfg: DiagnosisConfig,
    verdict: list[str],
    partial: list[str],
    stages: list[dict],
    floor: float,
    grid: float,
) -> tuple[list[str], list[str], float] | None:
    """(verdict, partial, floor accounted) naming the encoder's grid as the floor that explains
    the rest of the gap, or None to leave the verdict as it is.

    Only where the selection ended in ``unknown`` (nothing accepted, or a partial explanation):
    the grid's floor ``grid`` (:func:`~.position_sensor.grid_floor`, the whole gap the grid leaves
    in the nominal) less what the stage adding ``encoder_quantisation`` already removed, if one
    did, is judged as an effect by the core's rules: the first one's share when nothing was
    accepted before it (``min_first_explained`` of the nominal's excess) and, with the accepted
    effects, leaving at most ``1 - min_explained`` of it
    (:func:`~armlab.diagnosis.attribution.explains_enough`). ``stages``: the selection's stages
    (``held_out_gap``, ``effects``), the nominal first."""
    if grid <= 0 or "unknown" not in verdict:
        return None
    gaps = [st["held_out_gap"] for st in stages]
    excess0 = max(gaps[0] - floor, 0.0)
    at = next((i for i, st in enumerate(stages) if GRID_EFFECT in st["effects"]), None)
    rest = grid if at is None else max(grid - (gaps[at - 1] - gaps[at]), 0.0)
    if not partial and rest < cfg.min_first_explained * excess0:
        return None
    if not explains_enough(cfg, left=gaps[-1] - floor - rest, excess0=excess0, floor=floor):
        return None
    named = partial if GRID_EFFECT in partial else [*partial, GRID_EFFECT]
    return named, [], rest


def _diagnose_group(records, cfg: DiagnosisConfig) -> tuple[dict, dict]:
    trials, hp, y_band = prepare_scoring(records, cfg)
    fs = trials[0].fs_hz
    noise = noise_floor(records, trials, band_hz=cfg.band_hz, highpass_hz=cfg.highpass_hz)
    n_h = sum(int(np.sum(tr.held)) for tr in trials)
    tss = sum(float(np.sum(y[tr.held] ** 2)) for y, tr in zip(y_band, trials, strict=True))
    sensor_floor = noise.variance_Nm2 * n_h / tss
    # what the choice of derivative estimator alone leaves under a perfect nominal: it joins the
    # sensor noise wherever the rules read the floor (:mod:`.derivative_floor`)
    deriv_floor = derivative_floor(trials, hp, y_band) / tss
    floor = sensor_floor + deriv_floor
    names = candidate_names(cfg)
    _check_rate(names, fs, records[0].fs_hz)
    # a tonic level that the perturbation's speed envelope drives through a rectifier (the residual
    # follows the envelope a reflex's lag later) is no cue of co-contraction (:mod:`.tonic_cue`):
    # the candidate is not tried
    cue = tonic_cue_check(trials, cfg.slow_hz)
    cue["excluded"] = [_COCONTRACTION] if cue["rectified"] and _COCONTRACTION in names else []
    names = [n for n in names if n not in cue["excluded"]]
    band_share = (cfg.band_hz - cfg.highpass_hz) / (0.5 * fs)
    varying, stationary, tv_nominal = None, None, None
    if all(tr.op is not None for tr in trials):  # a time-varying recording
        varying, stationary, tv_nominal = _operating_point(trials, y_band, hp, floor, cfg, band_share)
    tv = varying is not None and varying["varies"]
    sel = select_effects(
        trials,
        y_band,
        hp,
        {n: JOINT_SURROGATES[n] for n in names if JOINT_SURROGATES[n].kind != "low_band"},
        floor,
        cfg,
        band_share=band_share,
        family=JOINT_TV_FAMILY if tv else JOINT_FAMILY,
        nominal=tv_nominal if tv else stationary,
    )
    # with a time-varying nominal, the stationary one is the first stage and the time-varying one
    # the stage that adds operating_point_impedance
    models = [stationary, *sel.stages] if tv else list(sel.stages)
    labels = (
        [[]] + [[_OP_EFFECT, *m.effects] for m in sel.stages] if tv else [list(m.effects) for m in models]
    )
    nominal = models[0]
    sign = _torque_sign(nominal)
    frf_meas = [frf_parameters(tr, y) for tr, y in zip(trials, y_band, strict=True)]  # once, for every stage
    stages = [
        {**_stage(m, trials, y_band, noise, floor, sign, frf_meas), "effects": label}
        for m, label in zip(models, labels, strict=True)
    ]
    steps = sel.ranking_steps()
    ranking = steps[0] if steps else []
    # where the reflex was scored, the most a rectifier explains alone (:func:`.tonic_cue.rectifier_rivals`)
    rect = [e["explained_fraction"] for e in ranking if e["name"] in RECTIFYING_EFFECTS]
    cue["rectifier_explained"] = max(rect) if rect else None
    verdict, partial = sel.verdict, sel.partial
    if tv:
        # the time-varying nominal is the first accepted effect: the core's rule for the effects
        # accepted together (they must leave at most 1 - min_explained of the stationary nominal's
        # excess, or be within none_tolerance of the floor) applied from the stationary nominal
        accepted = sel.partial or [n for n in sel.verdict if n not in ("none", "unknown")]
        excess = max(stages[0]["held_out_gap"] - floor, 0.0)
        left = stages[-1]["held_out_gap"] - floor
        explained = explains_enough(cfg, left=left, excess0=excess, floor=floor)
        verdict = [_OP_EFFECT, *accepted] if explained else [_OP_EFFECT, *accepted, "unknown"]
        partial = [] if explained else [_OP_EFFECT, *accepted]
    # an encoder's grid that no model of the recorded angle removes: a floor (:mod:`.position_sensor`)
    grid = grid_floor(trials, nominal.beta, hp, y_band) if GRID_EFFECT in names else 0.0
    named = _grid_named(cfg, verdict, partial, stages, floor, grid)
    if named is not None:
        verdict, partial, grid_rest = named
    # a slow torque that the perturbation's speed drives, which no named effect can make: they stand
    # in for a rectifying effect, and the verdict is unknown (:func:`.tonic_cue.held_verdict`)
    cue["held"] = held_verdict(cue, verdict, cue["rectifier_explained"], cfg.min_step_fraction)
    if cue["held"]:
        verdict, partial, named = ["unknown"], [e for e in cue["held"] if e != GRID_EFFECT], None
    # below the scoring band (:mod:`.low_band`): a drift is named where the band itself needs nothing
    low = low_band_check(
        trials,
        nominal,
        noise,
        hp,
        highpass_hz=cfg.highpass_hz,
        band_hz=cfg.band_hz,
        min_share=cfg.min_explained,
    )
    if verdict == ["none"] and low["named"] and "force_sensor_drift" in names:
        verdict = ["force_sensor_drift"]
    results = {
        "verdict": verdict,
        "ranking": ranking,
        "ranking_steps": steps,
        "gap": {
            **gap_section(_METRIC, stages, floor),
            "sensor_noise_floor": sensor_floor,
            "derivative_floor": deriv_floor,
            "noise_source": noise.source,
            # the recorded angle's error and the gap it leaves in the nominal (not in the floor)
            "position_sensor": {
                **position_sensor_summary(trials, nominal.beta, y_band, cfg.band_hz),
                "grid_floor": grid,
            },
            # a floor named in the verdict: accounted for in the gap, not removed from it
            **({"accounted": {"effect": GRID_EFFECT, "floor": grid_rest}} if named is not None else {}),
        },
        "where": {
            "bands": stages[0]["bands"],
            "windows": stages[0]["windows"],
            "per_trial": stages[0]["per_trial"],
            "channels": [{"channel": "torque", "axis": "joint", "held_out_gap": stages[0]["held_out_gap"]}],
            "residual_tests": residual_tests(trials, nominal.residuals),
            "parameter_bias": stages[0]["frf_bias"],
        },
        "how_far": stages,
        "indistinct": sel.indistinct,
        "partial": partial,
        "torque_sign": "antiphase (impedance = -torque/position)" if sign < 0 else "in phase",
        **({"operating_point": varying} if varying is not None else {}),
        "low_band": low,
        "tonic_cue": cue,
        "trials": [tr.name for tr in trials],
    }
    series = {
        "trials": trials,
        "measured": y_band,
        "nominal": list(nominal.predictions),
        "corrected": list(sel.stages[-1].predictions),
        "stages": models,
        "residual_tests_final": residual_tests(trials, sel.stages[-1].residuals),
        "noise": noise,
    }
    return results, series


def diagnose_joint(records, cfg: DiagnosisConfig) -> tuple[dict, dict]:
    """Diagnose 1-DoF joint trials (pooled, or each trial on its own with ``cfg.per_trial``).

    Args:
        records: imported trials (``name``, ``position`` rad, ``torque`` N·m, ``fs_hz``).
        cfg: the diagnosis settings.

    Returns:
        (results, series). In per-trial mode ``results`` has the pooled keys of the first trial's
        diagnosis replaced by a ``"per_trial"`` list of every trial's results and a summary
        ``verdict`` per trial; ``series`` is keyed by trial name.
    """
    records = list(records)
    cfg = cfg.with_rules(RULES)
    settings = asdict(cfg)
    if not cfg.per_trial:
        results, series = _diagnose_group(records, cfg)
        results["protocol"] = "joint_1dof"
        results["settings"] = settings
        return results, {"all": series}
    per, series = [], {}
    for r in records:
        res, ser = _diagnose_group([r], cfg)
        res["trial"] = r.name
        per.append(res)
        series[r.name] = ser
    summary = {
        "protocol": "joint_1dof",
        "settings": settings,
        "verdict": {p["trial"]: p["verdict"] for p in per},
        "ranking": {p["trial"]: p["ranking"] for p in per},
        "gap": {p["trial"]: p["gap"] for p in per},
        "per_trial": per,
    }
    return summary, series

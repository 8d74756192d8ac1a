"""``armlab diagnose`` for ``stiffness_5dof_emg``: where the static K_q model misses, which effect,
how far.

The nominal model is the paper's (Eq. (14), activation frozen; per pre-load condition a symmetric
K_q fitted on the training disturbances, the SPD estimate of Eqs. (16)-(17) reported beside it)
with the nominal lab's displacement and the seat's statics (:mod:`.data`, :mod:`.models`); the
held-out disturbances' rows are predicted and scored. Gap and floor follow
docs/diagnosis_schema.md (fractions of the whitened measured power). Not candidates yet: torso
motion (the arm model's torso is welded to the seat: no lab switch) and EMG cross-talk (needs the
EMG stage). Pure computation: a trial set and a :class:`DiagnosisConfig` in, a JSON-ready results
dict and the series for the figures out.
"""

from __future__ import annotations

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.attribution import select_candidates, select_effects
from armlab.diagnosis.families import FittedModel
from armlab.diagnosis.localise import masked_gap
from armlab.diagnosis.summary import gap_section, row_floor, stage_entry, verdict_section
from armlab.errors import EstimationError
from armlab.estimation.static_stiffness import static_stiffness
from armlab.protocols.stiffness_5dof_emg.diagnosis.data import CHANNELS, Stiff5Set, prepare_stiff5
from armlab.protocols.stiffness_5dof_emg.diagnosis.models import STIFF5_SURROGATES, stiff5_family
from armlab.protocols.stiffness_5dof_emg.diagnosis.rules import RULES

__all__ = [
    "diagnose_stiff5",
    "stiff5_candidates",
]

_GROUPS = {"torque": slice(0, 5), "displacement": slice(5, 10), "base": slice(10, 16)}


def stiff5_candidates(cfg: DiagnosisConfig) -> list[str]:
    """The candidate list after ``candidates`` / ``exclude`` (unknown names raise ConfigError)."""
    return select_candidates(cfg, STIFF5_SURROGATES, "stiffness_5dof_emg")


def _breakdowns(cs: Stiff5Set, y: np.ndarray, resid: np.ndarray) -> dict:
    """Held-out gap per time bin after onset, channel, channel group, condition and direction."""
    noise, held = cs.row_noise_var, cs.held
    row_cond, row_dir = cs.condition[cs.row_trial], cs.direction[cs.row_trial]
    windows = [
        {"window_ms": cs.bin_ms[b].tolist(), **masked_gap(resid, y, noise, held & (cs.row_bin == b))}
        for b in range(cs.bin_ms.shape[0])
    ]
    channels = [
        {
            "channel": name.split(".")[0],
            "axis": name.split(".")[1],
            **masked_gap(resid, y, noise, held & (cs.row_channel == k)),
        }
        for k, name in enumerate(CHANNELS)
    ]
    groups = [
        {
            "group": g,
            **masked_gap(resid, y, noise, held & (cs.row_channel >= s.start) & (cs.row_channel < s.stop)),
        }
        for g, s in _GROUPS.items()
    ]
    conditions = [
        {"condition": name, **masked_gap(resid, y, noise, held & (row_cond == c))}
        for c, name in enumerate(cs.condition_names)
    ]
    dirs = [
        {"direction": int(d), **masked_gap(resid, y, noise, held & (row_dir == d))}
        for d in np.unique(cs.direction[cs.held_trials])
    ]
    return {
        "windows": windows,
        "channels": channels,
        "groups": groups,
        "conditions": conditions,
        "directions": dirs,
    }


def _stage(cs: Stiff5Set, y: np.ndarray, model: FittedModel, floor: float) -> dict:
    entry, _ = stage_entry(model, (cs,), [y], floor)
    return {
        **entry,
        **_breakdowns(cs, y, model.residuals[0]),
        "parameters": dict(zip(model.linear_names, map(float, model.beta[0]), strict=True)),
        "nonlinear_parameters": dict(model.theta),
        "n_params": model.n_params,
    }


def _spd_estimates(cs: Stiff5Set) -> list[dict]:
    """Per condition, the protocol's SPD estimate (Eqs. (14)-(17)) on the training disturbances' hold."""
    out = []
    dq, tau = cs.dq.mean(axis=1), cs.y[:, :, :5].mean(axis=1)
    for c, name in enumerate(cs.condition_names):
        i = (cs.condition == c) & ~cs.held_trials
        zero = np.zeros((int(i.sum()), 5))
        try:
            est = static_stiffness(zero, dq[i], zero, tau[i])
        except EstimationError as err:
            out.append({"condition": name, "error": str(err)})
            continue
        out.append(
            {
                "condition": name,
                "n_train": int(i.sum()),
                "K_spd_Nm_per_rad": est.K.tolist(),
                "min_eigenvalue_Nm_per_rad": float(est.spd.eigenvalues.min()),
            }
        )
    return out


def diagnose_stiff5(trials, cfg: DiagnosisConfig) -> tuple[dict, dict]:
    """Diagnose a ``stiffness_5dof_emg`` trial set (see the module docstring and :mod:`.data`).

    Returns:
        (results, series): ``series["all"]`` holds the scoring set and each stage's prediction.
    """
    cfg = cfg.with_rules(RULES)
    names = stiff5_candidates(cfg)
    cs = prepare_stiff5(trials)
    y = cs.yw
    floor = row_floor(cs, y)
    sel = select_effects(
        (cs,),
        [y],
        None,
        {n: STIFF5_SURROGATES[n] for n in names},
        floor,
        cfg,
        band_share=1.0,
        family=stiff5_family(cs),
    )
    stages = [_stage(cs, y, m, floor) for m in sel.stages]
    metric = (
        "held-out residual power / measured power of the hold's 50 ms bins (torque, "
        "displacement and base rows, each whitened by its noise; 1 - VAF)"
    )
    results = {
        **verdict_section("stiffness_5dof_emg", cfg, sel),
        "gap": {
            **gap_section(metric, stages, floor),
            "noise_source": "the pre-disturbance still segment: spread of its four 50 ms bins per trial "
            "and channel, pooled (the sensors and the IK as recorded)",
        },
        "where": {k: stages[0][k] for k in ("windows", "channels", "groups", "conditions", "directions")},
        "how_far": stages,
        "indistinct": sel.indistinct,
        "partial": sel.partial,
        "trials": list(cs.names),
        "nominal_model": {
            "K_spd": _spd_estimates(cs),
            "xi_red": cs.xi_source,
            "chain": "the nominal arm model's (models/arm_5dof)",
            "noise_std": dict(zip(CHANNELS, np.sqrt(cs.noise_var).tolist(), strict=True)),
        },
        "not_candidates": {
            "torso_motion": "no lab switch yet: the arm model's torso is welded to the seat",
            "emg_crosstalk": "needs the EMG stage (not in the trial file)",
        },
        "scoring": {
            "held_out_trials": int(cs.held_trials.sum()),
            "n_trials": cs.n_trials,
            "window_ms": [float(cs.bin_ms[0, 0]), float(cs.bin_ms[-1, 1])],
        },
    }
    series = {
        "set": cs,
        "measured": y,
        "nominal": sel.stages[0].predictions[0],
        "corrected": sel.stages[-1].predictions[0],
        "stages": sel.stages,
        "channels": CHANNELS,
    }
    return results, {"all": series}

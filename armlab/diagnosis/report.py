"""``report.md`` and the terminal summary of ``armlab diagnose``: the results dict in words.

Pure string building over the results dict of :func:`armlab.diagnosis.diagnose.diagnose_joint`
(or the same keys read back from ``results.json``; see ``docs/diagnosis_schema.md``). The report
is meant to be read on its own by someone who has not read the code: a summary paragraph with the
verdict, then **Where** the gap lies, **Which** effect explains it, **How far** it shrinks, the
settings and the figures.

All gaps are fractions of the measured torque power in the scoring band, printed in %:
``gap = 1 - VAF`` on the held-out part of every trial; the noise floor is the gap that sensor noise
alone would leave.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import PurePath
from typing import Any

from armlab.config.effects import EFFECTS

__all__ = [
    "format_report",
    "format_summary",
]

#: Readable names of the joint_1dof candidates (the catalogue key is printed beside them).
_LABELS = {
    "reflex": "a stretch reflex",
    "cuff_compliance": "cuff (limb–pedal interface) compliance",
    "transmission_compliance": "transmission compliance",
    "joint_friction": "joint friction",
    "force_sensor_bandwidth": "the torque sensor's bandwidth",
    "channel_delay": "a delay between the torque and position channels",
    "cocontraction_variation": "slow co-contraction variation",
    "payload_mass": "an unmodelled payload mass",
}
#: Units of the linear (per-trial) parameters.
_UNITS = {
    "I": "kg·m²",
    "B": "N·m·s/rad",
    "K": "N·m/rad",
    "reflex.gain": "N·m·s/rad",
    "joint_friction.coulomb": "N·m",
    "cocontraction_variation.stiffness_slope": "N·m/rad",
    "cocontraction_variation.damping_slope": "N·m·s/rad",
    "compliance.gain": "N·m/rad",
    "cuff_compliance.pedal_inertia": "kg·m²",
}
_FIGURE_CAPTIONS = {
    "gap_by_band": "Held-out gap per frequency band, nominal and after each added effect, vs the noise floor",
    "gap_by_window": "Held-out gap per window after perturbation onset, per stage, vs the noise floor",
    "residual_correlation": (
        "Residual autocorrelation (whiteness) and residual–velocity cross-correlation with the ±95 % bound"
    ),
    "time_overlay": "A few held-out seconds: measured, nominal and corrected torque",
    "vaf_per_trial": "Held-out VAF per trial and stage, with the best VAF the noise allows",
}
_WHITE_FRACTION = 0.1  # autocorrelation lags outside the 95 % bound above which the residual is coloured


# ---------------------------------------------------------------------------------------------
# number formatting
# ---------------------------------------------------------------------------------------------


def _finite(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _pct(gap: Any) -> str:
    """A gap fraction as a percentage with enough digits to be non-zero ("–" when missing)."""
    v = _finite(gap)
    if v is None:
        return "–"
    p = 100.0 * v
    if abs(p) < 5e-4:
        return "≈ 0 %"
    if abs(p) >= 10:
        return f"{p:.1f} %"
    if abs(p) >= 0.1:
        return f"{p:.2f} %"
    return f"{p:.2g} %"


def _vaf(gap: Any) -> str:
    """VAF = 100 (1 - gap) % with as many decimals as the gap needs to show."""
    v = _finite(gap)
    if v is None:
        return "–"
    g = abs(100.0 * v)
    digits = 1 if g >= 1 else 2 if g >= 0.1 else 3 if g >= 0.01 else 4
    return f"{100.0 * (1.0 - v):.{digits}f} %"


def _num(x: Any, sig: int = 3) -> str:
    v = _finite(x)
    if v is None:
        return "–"
    return f"{(v if abs(v) > 1e-12 else 0.0):.{sig}g}"


def _score(x: Any) -> str:
    """A penalised score (ΔBIC): whole numbers once it is large."""
    v = _finite(x)
    if v is None:
        return "–"
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"


def _share(x: Any) -> str:
    """A fraction (of the excess gap) as a percentage with one decimal, never "-0.0 %"."""
    v = _finite(x)
    return "–" if v is None else f"{round(100.0 * v, 1) + 0.0:.1f} %"


def _ms(seconds: Any) -> str:
    v = _finite(seconds)
    return "–" if v is None else f"{1e3 * v:.0f} ms"


def _part(x: float) -> str:
    """A share in % with whole numbers in 1-99 % and two decimals near 0 or 100 %."""
    p = 100.0 * x
    return f"{p:.0f} %" if 1 <= p <= 99 else f"{p:.2f} %"


def _ratio(gap: Any, floor: Any) -> str:
    g, f = _finite(gap), _finite(floor)
    if g is None or f is None or f <= 0:
        return "–"
    return f"{g / f:,.0f}×" if g / f >= 100 else f"{g / f:.3g}×"


def _label(name: str) -> str:
    return f"{_LABELS.get(name, name.replace('_', ' '))} (`{name}`)"


def _effects_words(names: Sequence[str]) -> str:
    if not names:
        return "nominal"
    return ", then ".join(_label(n) for n in names)


def _stage_name(effects: Sequence[str]) -> str:
    return "nominal" if not effects else "nominal + " + " + ".join(effects)


def _table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return out


def _own_params(name: str, params: Mapping[str, Any]) -> str:
    """The candidate's own nonlinear parameters (``params`` also holds the earlier effects')."""
    own = [(k.split(".", 1)[1], v) for k, v in params.items() if k.startswith(name + ".")]
    return ", ".join(f"{k} = {_num(v)}" for k, v in own) or "–"


# ---------------------------------------------------------------------------------------------
# wording of the verdict and of the residual tests
# ---------------------------------------------------------------------------------------------


def _tolerance(results: Mapping[str, Any], settings: Mapping[str, Any] | None) -> float:
    s = settings or results.get("settings") or {}
    return float(s.get("none_tolerance", 0.25))


def _verdict_paragraph(r: Mapping[str, Any], settings: Mapping[str, Any] | None) -> str:
    verdict = list(r.get("verdict") or [])
    gap = r["gap"]
    nominal, floor = float(gap["nominal"]), float(gap["noise_floor"])
    stages = r.get("how_far") or []
    final = float(stages[-1]["held_out_gap"]) if stages else nominal
    floor_words = f"noise floor {_pct(floor)} (the best VAF the sensor noise allows is {_vaf(floor)})"
    excess0 = max(nominal - floor, 0.0)
    if verdict == ["none"]:
        return (
            "**Verdict: no gap beyond measurement noise.** The nominal simulation already reaches a "
            f"held-out VAF of {_vaf(nominal)} (gap {_pct(nominal)}) at the {floor_words}: its excess over "
            f"the floor is within the {100 * _tolerance(r, settings):.0f} % tolerance. No unmodelled effect "
            "is needed; the candidate ranking below is shown for completeness."
        )
    if verdict == ["unknown"] or not verdict:
        ranking = r.get("ranking") or []
        best = next((e for e in ranking if e.get("identifiable", True)), None)
        best_words = (
            f" The best candidate, {_label(best['name'])}, would lower the gap by only "
            f"{_pct(best['gap_reduction'])} ({_share(best['explained_fraction'])} of the excess over "
            f"the floor; Δ penalised score {_score(best['delta_bic'])})."
            if best
            else ""
        )
        return (
            f"**Verdict: unknown — the gap is real but no catalogue effect explains it.** The nominal "
            f"simulation's held-out VAF is {_vaf(nominal)} (gap {_pct(nominal)}), well above the "
            f"{floor_words}, yet no candidate effect passed the acceptance rules.{best_words} See *Where* "
            "for the band and the time after onset that hold the gap: the missing effect is probably not in "
            "the catalogue, or it was left out by `candidates`/`exclude` in the settings."
        )
    removed = (nominal - final) / excess0 if excess0 > 0 else 0.0
    if final - floor <= _tolerance(r, settings) * floor:
        rest = "The corrected model reaches the noise floor: nothing measurable is left unexplained."
    else:
        rest = (
            f"{'Together they remove' if len(verdict) > 1 else 'It removes'} {_part(removed)} of the "
            f"gap above the noise floor; the remaining {_part(1 - removed)} (gap {_pct(final)}, "
            f"{_ratio(final, floor)} the floor) is not explained by any catalogue effect (see *How far*)."
        )
    text = (
        f"**Verdict: the gap is explained by {_effects_words(verdict)}.** Held-out VAF "
        f"{_vaf(nominal)} → {_vaf(final)} (gap {_pct(nominal)} → {_pct(final)} of the measured torque "
        f"power), {floor_words}. {rest}"
    )
    caution = [
        p
        for p in r.get("indistinct") or []
        if p["effects"][0] in verdict and p["effects"][1] != "limb inertia"
    ]
    for p in caution:
        a, b = p["effects"]
        text += (
            f" Caution: with these trials `{a}` cannot be told apart from `{b}`; {p['separating_trial']} "
            "would separate them."
        )
    return text


def _xcorr_meaning(lag_s: float, value: float, bound: float) -> str:
    """What the peak of the residual–velocity cross-correlation points to."""
    if abs(value) <= bound:
        return (
            "no significant residual–velocity correlation at any lag: what is left is not linearly related "
            "to the recent joint motion"
        )
    ms = 1e3 * lag_s
    if lag_s < -0.01:
        return (
            f"the residual *precedes* the velocity by {-ms:.0f} ms: the torque channel leads the position "
            "channel (a delayed position channel) or anticipatory/voluntary activity"
        )
    if abs(lag_s) <= 0.01:
        return (
            "the residual moves with the velocity at (near) zero lag: an error in the instantaneous "
            "impedance — damping, friction — or a channel skew or sensor low-pass of a few ms"
        )
    if lag_s < 0.025:
        return (
            f"the residual follows the velocity by {ms:.0f} ms: a torque-sensor low-pass or channel delay, "
            "or a short-latency reflex component"
        )
    if lag_s <= 0.12:
        return (
            f"the residual follows the velocity by {ms:.0f} ms: a delayed response to stretch velocity, as a "
            "stretch-reflex pathway leaves (40–50 ms latency at the ankle, Kearney et al. 1997)"
        )
    return (
        f"the residual follows the velocity by {ms:.0f} ms: a slow or long-loop response (voluntary "
        "reaction, co-contraction change)"
    )


def _window_meaning(lo: float, hi: float) -> str:
    if hi <= 20:
        return "right at onset: inertial or sensor dynamics (bandwidth, channel delay, compliance)"
    if lo >= 20 and hi <= 120:
        return "a delayed response after onset, at the latency of a stretch reflex"
    return "late after onset: slow responses, or friction and tonic changes during the holds"


# ---------------------------------------------------------------------------------------------
# sections of one diagnosis
# ---------------------------------------------------------------------------------------------


def _where(r: Mapping[str, Any], h: str) -> list[str]:
    w = r["where"]
    floor = r["gap"]["noise_floor"]
    out = [
        f"{h} Where: the nominal model's held-out residual",
        "",
        "Each gap is the held-out residual power of the nominal simulation in that slice, as a fraction of "
        "the measured torque power in the same slice; *floor* is what the sensor noise alone would leave "
        "there.",
        "",
    ]
    bands = w.get("bands") or []
    total = sum(_finite(b.get("residual_power")) or 0.0 for b in bands)
    out += [f"{h}# By frequency band", ""]
    out += _table(
        ["band (Hz)", "gap", "noise floor", "gap / floor", "share of the residual power"],
        [
            [
                f"{b['band_hz'][0]:g}–{b['band_hz'][1]:g}",
                _pct(b["gap"]),
                _pct(b["floor"]),
                _ratio(b["gap"], b["floor"]),
                _pct((_finite(b.get("residual_power")) or 0.0) / total) if total > 0 else "–",
            ]
            for b in bands
        ],
    )
    valid = [b for b in bands if _finite(b.get("gap")) is not None]
    if valid and total > 0:
        worst = max(valid, key=lambda b: b["gap"])
        most = max(valid, key=lambda b: _finite(b.get("residual_power")) or 0.0)
        out += [
            "",
            f"The relative gap is largest in {worst['band_hz'][0]:g}–{worst['band_hz'][1]:g} Hz "
            f"({_pct(worst['gap'])} of the measured power there); most residual power lies in "
            f"{most['band_hz'][0]:g}–{most['band_hz'][1]:g} Hz "
            f"({_pct((_finite(most.get('residual_power')) or 0.0) / total)} of it).",
        ]
    windows = w.get("windows") or []
    out += ["", f"{h}# By time after perturbation onset", ""]
    out += _table(
        ["window (ms)", "gap", "noise floor", "gap / floor", "samples"],
        [
            [
                f"{x['window_ms'][0]:g}–{x['window_ms'][1]:g}",
                _pct(x["gap"]),
                _pct(x["floor"]),
                _ratio(x["gap"], x["floor"]),
                x.get("samples", "–"),
            ]
            for x in windows
        ],
    )
    filled = [x for x in windows if _finite(x.get("gap")) is not None]
    if filled:
        worst = max(filled, key=lambda x: x["gap"])
        lo, hi = worst["window_ms"]
        out += [
            "",
            f"The gap is largest {lo:g}–{hi:g} ms after onset ({_pct(worst['gap'])}; "
            f"{_pct(r['gap']['nominal'])} over the whole held-out part): {_window_meaning(lo, hi)}.",
        ]
    out += ["", f"{h}# By trial", ""]
    out += _table(
        ["trial", "held-out gap", "held-out VAF", "gap / floor"],
        [
            [p["trial"], _pct(p["held_out_gap"]), _vaf(p["held_out_gap"]), _ratio(p["held_out_gap"], floor)]
            for p in w.get("per_trial") or []
        ],
    )
    t = w.get("residual_tests") or {}
    if t:
        frac = float(t["whiteness_fraction_outside"])
        white = frac <= _WHITE_FRACTION
        lags = [x for x in t.get("lags_s") or [] if x > 0]
        meaning = _xcorr_meaning(
            float(t["peak_cross_lag_s"]), float(t["peak_cross_value"]), float(t["bound"])
        )
        span = f"{_ms(min(lags))}–{_ms(max(lags))}" if lags else "positive lags"
        out += [
            "",
            f"{h}# Residual tests",
            "",
            f"- **Whiteness:** {100 * frac:.0f} % of the residual autocorrelation lags ({span}) lie outside "
            f"the ±{_num(t['bound'])} band a white residual stays in 95 % of the time (≈ 5 % expected if "
            "white): "
            + (
                "the residual is consistent with noise."
                if white
                else "the residual is coloured — the nominal model misses structured dynamics."
            ),
            f"- **Residual–velocity cross-correlation:** peak {_num(t['peak_cross_value'])} at a lag of "
            f"{_ms(t['peak_cross_lag_s'])} (bound ±{_num(t['bound'])}; a positive lag means the residual "
            f"follows the velocity): {meaning}.",
        ]
    bias = w.get("parameter_bias") or []
    if bias:
        out += [
            "",
            f"{h}# Parameter bias (FRF fit)",
            "",
            "The protocol's own frequency-response fit (I, B, K of `K − I·ω² + j·B·ω`, 1–20 Hz) applied to "
            "the measured torque and to the nominal simulation's torque; the bias is measured − simulated, "
            "i.e. how the model error shows up in the parameters a lab would identify.",
            "",
        ]
        rows = []
        for name, b in zip(r.get("trials") or [str(i) for i in range(len(bias))], bias, strict=False):
            for k in ("I", "B", "K"):
                m = _finite(b["measured"][k])
                rel = f"{100 * b[k] / m:+.0f} %" if m else "–"
                rows.append([name, f"{k} ({_UNITS[k]})", _num(m), _num(b["simulated"][k]), _num(b[k]), rel])
        out += _table(
            ["trial", "parameter", "measured", "nominal simulation", "bias", "bias / measured"], rows
        )
    return out


def _which(r: Mapping[str, Any], h: str, settings: Mapping[str, Any] | None) -> list[str]:
    s = settings or r.get("settings") or {}
    verdict = list(r.get("verdict") or [])
    effects = [n for n in verdict if n not in ("none", "unknown")]
    out = [
        f"{h} Which: the candidate effects",
        "",
        "Each candidate is added to the current model, refitted on the training parts and scored on the "
        "held-out parts. *Reduction* is the drop of the held-out gap, *% of excess* its share of the nominal "
        "gap above the noise floor, *Δ penalised score* a BIC-like score against the current model "
        "(`n_eff·ln(RSS_new/RSS_old) + Δp·ln(n_eff)`, negative is better) and *added parameters* Δp (the "
        "linear ones once per trial plus the shared nonlinear ones; negative when the effect replaces "
        f"parameters). An effect is accepted when Δ < −{_num(s.get('bic_margin', 10.0))}, its reduction is "
        f"at least {100 * float(s.get('min_step_fraction', 0.1)):.0f} % of the nominal excess and "
        f"{100 * float(s.get('min_floor_fraction', 0.1)):.0f} % of the floor, and the first one explains at "
        f"least {100 * float(s.get('min_first_explained', 0.4)):.0f} % of the excess; up to "
        f"{s.get('max_effects', 3)} effects are added greedily.",
    ]
    for step, entries in enumerate(r.get("ranking_steps") or [r.get("ranking") or []]):
        base = _stage_name(effects[:step])
        out += ["", f"{h}# Step {step + 1}: candidates added to the {base} model", ""]
        rows = []
        for i, e in enumerate(entries, start=1):
            chosen = step < len(effects) and e["name"] == effects[step]
            if not e.get("identifiable", True):
                rows.append([i, f"`{e['name']}`", "not identifiable", "–", "–", "–", "–", "–", ""])
                continue
            rows.append(
                [
                    i,
                    f"**`{e['name']}`**" if chosen else f"`{e['name']}`",
                    _pct(e["held_out_gap"]),
                    _pct(e["gap_reduction"]),
                    _share(e["explained_fraction"]),
                    _score(e["delta_bic"]),
                    e["added_params"],
                    _own_params(e["name"], e.get("params") or {}),
                    "selected" if chosen else "",
                ]
            )
        out += _table(
            [
                "rank",
                "candidate",
                "held-out gap",
                "reduction",
                "% of excess",
                "Δ penalised score",
                "added parameters",
                "fitted nonlinear parameters",
                "",
            ],
            rows,
        )
        if step >= len(effects):
            out += ["", "No candidate passed the acceptance rules at this step: the selection stops here."]

    if effects:
        out += ["", f"{h}# The selected effects (from the catalogue)", ""]
        for n in effects:
            cls = EFFECTS.get(n)
            if cls is None:
                out.append(f"- **`{n}`**: not in the catalogue.")
                continue
            out.append(f"- **`{n}`** ({cls.LEVEL} level): {cls.PHYSICS}. *Typical magnitude:* {cls.SOURCE}.")
    pairs = r.get("indistinct") or []
    hidden = [p for p in pairs if p["effects"][1] == "limb inertia"]
    twins = [p for p in pairs if p["effects"][1] != "limb inertia"]
    out += ["", f"{h}# What these trials cannot tell apart", ""]
    if not pairs:
        out.append("Every candidate could be told apart from the others with these trials.")
    for p in hidden:
        out.append(
            f"- `{p['effects'][0]}` is not identifiable: the calibrated {p['effects'][1]} absorbs it. "
            f"Separating trial: {p['separating_trial']}."
        )
    if twins:
        out += [""] if hidden else []
        out += _table(
            ["selected", "runner-up", "reductions", "trial that would separate them"],
            [
                [
                    f"`{p['effects'][0]}`",
                    f"`{p['effects'][1]}`",
                    " vs ".join(_pct(x) for x in p["reductions"]),
                    p["separating_trial"],
                ]
                for p in twins
            ],
        )
    return out


def _how_far(r: Mapping[str, Any], h: str) -> list[str]:
    stages = r.get("how_far") or []
    floor = r["gap"]["noise_floor"]
    nominal = float(r["gap"]["nominal"])
    excess0 = max(nominal - float(floor), 0.0)
    names = [_stage_name(s["effects"]) for s in stages]
    out = [f"{h} How far: the gap after each added effect", ""]
    out += _table(
        [
            "stage",
            "held-out gap",
            "held-out VAF",
            "gap / floor",
            "% of the nominal excess removed",
            "parameters",
        ],
        [
            [
                n,
                _pct(s["held_out_gap"]),
                _vaf(s["held_out_gap"]),
                _ratio(s["held_out_gap"], floor),
                f"{100 * (nominal - s['held_out_gap']) / excess0:.0f} %" if excess0 > 0 else "–",
                s.get("n_params", "–"),
            ]
            for n, s in zip(names, stages, strict=True)
        ]
        + [["noise floor", _pct(floor), _vaf(floor), "1×", "", ""]],
    )
    trials = [p["trial"] for p in stages[0]["per_trial"]] if stages else []
    if trials:
        out += ["", f"{h}# Per trial (held-out VAF)", ""]
        out += _table(
            ["trial", *names],
            [[t, *(_vaf(s["per_trial"][i]["held_out_gap"]) for s in stages)] for i, t in enumerate(trials)],
        )
    if stages and stages[0].get("bands"):
        out += ["", f"{h}# Per band (held-out gap)", ""]
        out += _table(
            ["band (Hz)", *names, "noise floor"],
            [
                [
                    f"{b['band_hz'][0]:g}–{b['band_hz'][1]:g}",
                    *(_pct(s["bands"][j]["gap"]) for s in stages),
                    _pct(b["floor"]),
                ]
                for j, b in enumerate(stages[0]["bands"])
            ],
        )
    if stages and stages[0].get("windows"):
        out += ["", f"{h}# Per window after onset (held-out gap)", ""]
        out += _table(
            ["window (ms)", *names, "noise floor"],
            [
                [
                    f"{x['window_ms'][0]:g}–{x['window_ms'][1]:g}",
                    *(_pct(s["windows"][j]["gap"]) for s in stages),
                    _pct(x["floor"]),
                ]
                for j, x in enumerate(stages[0]["windows"])
            ],
        )
    if len(stages) >= 1:
        first, last = stages[0], stages[-1]
        out += [
            "",
            f"{h}# Parameters before and after",
            "",
            "Fitted per trial on the training parts (the torque sign folded in: "
            f"{r.get('torque_sign', 'as recorded')}). A compliance effect replaces I, B, K by its own "
            "parameters.",
            "",
        ]
        rows = []
        for i, t in enumerate(trials):
            before, after = first["parameters"][i], last["parameters"][i]
            for k in dict.fromkeys([*before, *after]):
                unit = _UNITS.get(k, "")
                rows.append(
                    [t, f"{k} ({unit})" if unit else k, _num(before.get(k), 4), _num(after.get(k), 4)]
                )
        out += _table(["trial", "parameter", "nominal", _stage_name(last["effects"])], rows)
        nl = last.get("nonlinear_parameters") or {}
        if nl:
            out += [
                "",
                "Shared nonlinear parameters of the final model: "
                + ", ".join(f"`{k}` = {_num(v)}" for k, v in nl.items())
                + ".",
            ]
        if len(stages) > 1 and first.get("frf_bias") and last.get("frf_bias"):
            out += ["", "Bias of the FRF-identified parameters (measured − simulated), before and after:", ""]
            rows = [
                [t, f"{k} ({_UNITS[k]})", _num(first["frf_bias"][i][k]), _num(last["frf_bias"][i][k])]
                for i, t in enumerate(trials)
                for k in ("I", "B", "K")
            ]
            out += _table(["trial", "parameter", "nominal", _stage_name(last["effects"])], rows)
    return out


def _one(r: Mapping[str, Any], h: str, settings: Mapping[str, Any] | None) -> list[str]:
    return [
        _verdict_paragraph(r, settings),
        "",
        *_where(r, h),
        "",
        *_which(r, h, settings),
        "",
        *_how_far(r, h),
    ]


def _noise_words(source: str) -> str:
    if source.startswith("repeats"):
        return (
            "from repeated trials (trials whose positions correlate above 0.99 repeat one perturbation): "
            "var(y_i − y_j)/2 in the scoring band — the most direct estimate."
        )
    return (
        f"{source}: E[(Δ²y)²] = 6σ² for white noise (Rice 1984), scaled to the scoring band. With no "
        "repeated trials this assumes white sensor noise; coloured noise or tremor would raise the true "
        "floor."
    )


def _settings(results: Mapping[str, Any], data_path: str, sources: Sequence[str]) -> list[str]:
    s = results.get("settings") or {}
    out = ["## Settings and noise floor", ""]
    out.append(f"- **Data:** `{data_path}`; protocol `{results.get('protocol', 'joint_1dof')}`.")
    if s:
        hold = float(s.get("holdout_fraction", 1 / 3))
        out.append(
            f"- **Scoring:** models fitted at {_num(s.get('fs_fit_hz'))} Hz on the first "
            f"{100 * (1 - hold):.0f} % of every trial and scored on the last {100 * hold:.0f} %, in the band "
            f"{_num(s.get('highpass_hz'))}–{_num(s.get('band_hz'))} Hz (below the high-pass the torque is "
            "the subject's voluntary/tonic activity)."
        )
    for src in dict.fromkeys(sources):
        out.append(f"- **Noise floor:** {_noise_words(src)}")
    if s:
        out += ["", *_table(["setting", "value"], [[f"`{k}`", f"`{v}`"] for k, v in s.items()])]
    return out


def _figures(figures: Sequence[str]) -> list[str]:
    out = ["## Figures", ""]
    if not figures:
        return out + ["No figures were written for this run."]
    for f in figures:
        stem = PurePath(f).stem
        caption = _FIGURE_CAPTIONS.get(stem, stem.replace("_", " "))
        out += [f"- [{caption}]({f})", "", f"  ![{caption}]({f})", ""]
    return out


def format_report(results: Mapping[str, Any], *, data_path: str, figures: Sequence[str]) -> str:
    """The Markdown ``report.md`` of one ``armlab diagnose`` run.

    Pooled results: a summary paragraph (the verdict in words, held-out VAF nominal → final, the noise
    floor), then *Where* (gap per band, per window after onset, per trial; residual whiteness and the
    residual–velocity cross-correlation peak with its meaning; FRF parameter bias), *Which* (one ranking
    table per greedy step, the catalogue's physics and typical magnitude of the selected effects, what
    cannot be told apart and the trial that would separate it), *How far* (gap and VAF per stage, per
    trial, per band and per window beside the noise floor; parameters before/after), the settings with
    the noise-floor source, and the figures. Per-trial results (a ``per_trial`` key): a summary table
    (trial, verdict, top-ranked candidate, VAF nominal → final) and then one such section per trial.

    Args:
        results: the results dict of :func:`armlab.diagnosis.diagnose.diagnose_joint` (or read back
            from ``results.json``).
        data_path: the measured data the run read (printed, not opened).
        figures: figure paths relative to the report's folder, linked and embedded in order.

    Returns:
        The report text (ends with a newline).
    """
    per = results.get("per_trial")
    settings = results.get("settings")
    if per is None:
        lines = [
            f"# Sim-to-real gap diagnosis ({results.get('protocol', 'joint_1dof')})",
            "",
            f"Trials {', '.join(f'`{t}`' for t in results.get('trials') or [])} from `{data_path}`, pooled: "
            "one set of effects for all trials, the linear parameters fitted per trial.",
            "",
            "## Summary",
            "",
            *_one(results, "##", settings),
        ]
        sources = [results["gap"].get("noise_source", "unknown")]
    else:
        lines = [
            f"# Sim-to-real gap diagnosis ({results.get('protocol', 'joint_1dof')}, per trial)",
            "",
            f"{len(per)} trials from `{data_path}`, each diagnosed on its own (its own effects and "
            "parameters).",
            "",
            "## Summary",
            "",
        ]
        rows = []
        for p in per:
            stages = p.get("how_far") or []
            final = stages[-1]["held_out_gap"] if stages else p["gap"]["nominal"]
            top = (p.get("ranking") or [{}])[0].get("name")
            rows.append(
                [
                    f"`{p['trial']}`",
                    ", then ".join(p["verdict"]),
                    f"`{top}`" if top else "–",
                    f"{_vaf(p['gap']['nominal'])} → {_vaf(final)}",
                    _pct(p["gap"]["noise_floor"]),
                ]
            )
        lines += _table(
            ["trial", "verdict", "top-ranked candidate", "held-out VAF nominal → final", "noise floor"], rows
        )
        verdicts = {tuple(p["verdict"]) for p in per}
        lines += [
            "",
            (
                f"All trials agree: {', then '.join(next(iter(verdicts)))}."
                if len(verdicts) == 1
                else "The trials disagree: the effect differs between subjects or conditions (see each "
                "trial below)."
            ),
        ]
        for p in per:
            lines += ["", f"## Trial `{p['trial']}`", "", *_one(p, "###", settings)]
        sources = [p["gap"].get("noise_source", "unknown") for p in per]
    lines += ["", *_settings(results, data_path, sources), "", *_figures(figures)]
    return "\n".join(lines).rstrip() + "\n"


def _summary_lines(r: Mapping[str, Any], indent: str) -> list[str]:
    stages = r.get("how_far") or []
    nominal = r["gap"]["nominal"]
    final = stages[-1]["held_out_gap"] if stages else nominal
    top = [
        f"{e['name']} ({_score(e['delta_bic'])})" if e.get("identifiable", True) else f"{e['name']} (n/i)"
        for e in (r.get("ranking") or [])[:3]
    ]
    return [
        f"{indent}held-out VAF {_vaf(nominal)} -> {_vaf(final)} (gap {_pct(nominal)} -> {_pct(final)}); "
        f"noise floor {_pct(r['gap']['noise_floor'])}",
        f"{indent}ranking (Δ penalised score): {', '.join(top) or '–'}",
    ]


def format_summary(results: Mapping[str, Any]) -> str:
    """A few lines for the terminal: the verdict, VAF nominal → final, the floor, the top candidates."""
    per = results.get("per_trial")
    if per is None:
        n = len(results.get("trials") or [])
        lines = [f"diagnosis ({n} trials pooled): verdict {' -> '.join(results['verdict'])}"]
        lines += _summary_lines(results, "  ")
    else:
        lines = [f"diagnosis ({len(per)} trials, each on its own):"]
        for p in per:
            lines.append(f"  {p['trial']}: verdict {' -> '.join(p['verdict'])}")
            lines += _summary_lines(p, "    ")
    return "\n".join(lines)
